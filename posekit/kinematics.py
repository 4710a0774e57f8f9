"""Forward kinematics (FK): local joint rotations + root position -> global positions and rotations.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``, where it is derived by hand first.
Conventions (column vectors, parent-first composition, metres): :mod:`posekit.conventions`.

:func:`fk` works on numpy arrays and on torch tensors (differentiable, used by the learned solvers).
"""

from __future__ import annotations

import numpy as np

from ._jit import HAVE_NUMBA, njit
from .rotations import is_torch, quat_to_matrix
from .skeleton import Skeleton

__all__ = ["fk", "rest_pose", "bone_lengths_of", "check_finite"]


def check_finite(x, what: str):
    """Raise ``ValueError`` naming ``what`` when ``x`` holds NaN or inf."""
    ok = bool(x.isfinite().all()) if is_torch(x) else bool(np.all(np.isfinite(x)))
    if not ok:
        raise ValueError(f"{what} contains NaN or inf; expected finite values")


def _as_matrices(local_rot, J: int):
    shape = tuple(local_rot.shape)
    if len(shape) >= 2 and shape[-2:] == (J, 4):
        check_finite(local_rot, "local_rot")
        norms = local_rot.norm(dim=-1) if is_torch(local_rot) else np.linalg.norm(local_rot, axis=-1)
        if bool((norms < 1e-8).any()):
            raise ValueError("local_rot holds zero-length quaternions; expected unit quaternions (x, y, z, w)")
        return quat_to_matrix(local_rot)
    if len(shape) >= 3 and shape[-3:] == (J, 3, 3):
        check_finite(local_rot, "local_rot")
        return local_rot
    raise ValueError(
        f"local_rot: expected quaternions of shape (..., {J}, 4) or matrices of shape "
        f"(..., {J}, 3, 3) for a {J}-joint skeleton, got {shape}"
    )


def fk(skeleton: Skeleton, local_rot, root_pos=None, local_pos=None):
    """Forward kinematics.

    ``global_rot[j] = global_rot[p] @ local_rot[j]`` and
    ``global_pos[j] = global_pos[p] + global_rot[p] @ local_pos[j]`` with ``p = parents[j]``,
    visiting joints parent-first (the recursion of Eq. 1 in Aristidou et al. 2018, "Inverse
    Kinematics Techniques in Computer Graphics: A Survey").

    Parameters
    ----------
    skeleton : Skeleton
        J joints.
    local_rot : ndarray or tensor, shape (..., J, 4) or (..., J, 3, 3)
        Local rotations as quaternions ``(x, y, z, w)`` or matrices.
    root_pos : ndarray or tensor, shape (..., 3), metres, optional
        World position of joint 0; defaults to ``skeleton.offsets[0]``.
    local_pos : ndarray or tensor, shape (..., J, 3), metres, optional
        Per-frame joint translations (BVH position channels); defaults to ``skeleton.offsets``.
        When given, its root row is used unless ``root_pos`` is also given.

    Returns
    -------
    global_pos : shape (..., J, 3), metres
    global_rot : shape (..., J, 3, 3)

    Raises
    ------
    ValueError
        Wrong shapes, or NaN/inf in the inputs.
    """
    J = skeleton.n_joints
    R = _as_matrices(local_rot, J)
    batch = tuple(R.shape[:-3])
    for arr, name, tail in ((root_pos, "root_pos", (3,)), (local_pos, "local_pos", (J, 3))):
        if arr is not None:
            if tuple(arr.shape[len(arr.shape) - len(tail):]) != tail:
                raise ValueError(f"{name}: expected shape (..., {', '.join(map(str, tail))}), got {tuple(arr.shape)}")
            check_finite(arr, name)
    if is_torch(R):
        return _fk_torch(skeleton, R, batch, root_pos, local_pos)
    return _fk_numpy(skeleton, np.asarray(R, dtype=float), batch, root_pos, local_pos)


_CHUNK = 2048
_SMALL = 512
"""Below this many poses :func:`_fk_small` runs instead: the layout change costs more than it saves."""


def _fk_numpy(skeleton, R, batch, root_pos, local_pos):
    """Numpy FK in a structure-of-arrays layout: every matrix entry is a contiguous vector over a
    cache-sized chunk of poses, so each multiply-add is one vectorised numpy call, about 1.5x faster than
    ``np.matmul`` on stacks of 3x3 matrices.

    With numba installed (a dependency) every batch goes to the compiled :func:`_fk_poses` instead: the same
    sums in the same order (bit-identical), 6-13x faster from one pose to tens of thousands, since it makes no
    numpy call per joint (``posekit bench fk``). The numpy layouts below are what runs without numba."""
    J = skeleton.n_joints
    parents = skeleton.parents
    N = int(np.prod(batch, dtype=np.int64))
    Rl = R.reshape(N, J, 3, 3)
    Ol = None if local_pos is None else np.broadcast_to(np.asarray(local_pos, dtype=float), batch + (J, 3)).reshape(N, J, 3)
    Root = None if root_pos is None else np.broadcast_to(np.asarray(root_pos, dtype=float), batch + (3,)).reshape(N, 3)
    if HAVE_NUMBA or N <= _ONE:
        return _fk_compiled(skeleton, Rl, batch, Root, Ol)
    if N < _SMALL:
        return _fk_small(skeleton, Rl, batch, Root, Ol)
    Rg_out = np.empty((N, J, 3, 3))
    Pg_out = np.empty((N, J, 3))
    for a in range(0, N, _CHUNK):
        b = min(N, a + _CHUNK)
        n = b - a
        rl = np.ascontiguousarray(Rl[a:b].transpose(1, 2, 3, 0))  # (J, 3, 3, n)
        ol = None if Ol is None else np.ascontiguousarray(Ol[a:b].transpose(1, 2, 0))  # (J, 3, n)
        rg = np.empty_like(rl)
        pg = np.empty((J, 3, n))
        tmp = np.empty(n)
        rg[0] = rl[0]
        if Root is not None:
            pg[0] = Root[a:b].T
        else:
            pg[0] = ol[0] if ol is not None else skeleton.offsets[0][:, None]
        for j in range(1, J):
            A, B, out = rg[parents[j]], rl[j], rg[j]
            for r in range(3):  # out = A @ B, entry by entry
                for c in range(3):
                    np.multiply(A[r, 0], B[0, c], out=out[r, c])
                    out[r, c] += np.multiply(A[r, 1], B[1, c], out=tmp)
                    out[r, c] += np.multiply(A[r, 2], B[2, c], out=tmp)
            o = skeleton.offsets[j] if ol is None else ol[j]  # (3,) or (3, n)
            pp, pj = pg[parents[j]], pg[j]
            for r in range(3):  # pj = pp + A @ o
                np.multiply(A[r, 0], o[0], out=pj[r])
                pj[r] += np.multiply(A[r, 1], o[1], out=tmp)
                pj[r] += np.multiply(A[r, 2], o[2], out=tmp)
                pj[r] += pp[r]
        Rg_out[a:b] = rg.transpose(3, 0, 1, 2)
        Pg_out[a:b] = pg.transpose(2, 0, 1)
    return Pg_out.reshape(batch + (J, 3)), Rg_out.reshape(batch + (J, 3, 3))


_ONE = 4
"""Without numba, up to this many poses still run :func:`_fk_poses` (as plain Python: numpy's per-call cost
dominates a single pose); with numba every batch does (:func:`_fk_compiled`)."""


@njit
def _fk_poses(parents, Rl, root, offsets, rg, pg):
    """:func:`_fk_small` compiled, pose by pose, with the same order of sums (bit-identical): ``Rl`` (N, J, 3, 3),
    ``root`` (N, 3), ``offsets`` (N, J, 3); writes ``rg`` (N, J, 3, 3) and ``pg`` (N, J, 3)."""
    N, J = Rl.shape[:2]
    for n in range(N):
        for r in range(3):
            pg[n, 0, r] = root[n, r]
            for c in range(3):
                rg[n, 0, r, c] = Rl[n, 0, r, c]
        for j in range(1, J):
            p = parents[j]
            for r in range(3):
                for c in range(3):
                    rg[n, j, r, c] = (rg[n, p, r, 0] * Rl[n, j, 0, c] + rg[n, p, r, 1] * Rl[n, j, 1, c]) \
                        + rg[n, p, r, 2] * Rl[n, j, 2, c]
                pg[n, j, r] = ((rg[n, p, r, 0] * offsets[n, j, 0] + rg[n, p, r, 1] * offsets[n, j, 1])
                               + rg[n, p, r, 2] * offsets[n, j, 2]) + pg[n, p, r]


_COMPILED_CHUNK = 8192
"""Poses per call of :func:`_fk_poses`: bounds the contiguous copies of the inputs (about 13 MB of rotations a chunk
for 22 joints)."""


def _writable(x):
    """``x`` as a contiguous, writable float64 array, copied only when it is not one: read-only views (a broadcast
    ``root_pos``) would otherwise make numba compile a second signature of :func:`_fk_poses`."""
    if x.flags.c_contiguous and x.flags.writeable and x.dtype == np.float64:
        return x
    return np.array(x, dtype=float, order="C")


def _fk_compiled(skeleton, Rl, batch, Root, Ol):
    """FK of any number of poses by the compiled :func:`_fk_poses`, :data:`_COMPILED_CHUNK` poses at a time
    (bit-identical to :func:`_fk_small` and :func:`_fk_numpy`)."""
    N, J = Rl.shape[:2]
    rg = np.empty((N, J, 3, 3))
    pg = np.empty((N, J, 3))
    for a in range(0, N, _COMPILED_CHUNK):
        b = min(N, a + _COMPILED_CHUNK)
        off = np.broadcast_to(skeleton.offsets, (b - a, J, 3)) if Ol is None else Ol[a:b]
        root = off[:, 0] if Root is None else Root[a:b]
        # the skeleton's parents are read-only int64 arrays (Skeleton makes them so): one signature with the rest
        _fk_poses(skeleton.parents, _writable(Rl[a:b]), _writable(root), _writable(off), rg[a:b], pg[a:b])
    return pg.reshape(batch + (J, 3)), rg.reshape(batch + (J, 3, 3))


def _fk_small(skeleton, Rl, batch, Root, Ol):
    """:func:`_fk_numpy` for a few poses (one frame, a finite-difference Jacobian's neighbours): each joint's
    products as a few broadcast numpy calls over the poses, in the same order of sums, so the result is
    bit-identical to the chunked path and 2-4x faster below :data:`_SMALL` poses."""
    N, J = Rl.shape[:2]
    parents = skeleton.parents
    rg = np.empty((N, J, 3, 3))
    pg = np.empty((N, J, 3))
    rg[:, 0] = Rl[:, 0]
    if Root is not None:
        pg[:, 0] = Root
    else:
        pg[:, 0] = Ol[:, 0] if Ol is not None else skeleton.offsets[0]
    for j in range(1, J):
        p = parents[j]
        A, B = rg[:, p], Rl[:, j]  # out = A @ B: (A_r0 B_0c + A_r1 B_1c) + A_r2 B_2c
        rg[:, j] = A[:, :, 0:1] * B[:, 0:1, :] + A[:, :, 1:2] * B[:, 1:2, :] + A[:, :, 2:3] * B[:, 2:3, :]
        o = skeleton.offsets[j] if Ol is None else Ol[:, j, None, :]  # (3,) or (N, 1, 3)
        pg[:, j] = A[:, :, 0] * o[..., 0] + A[:, :, 1] * o[..., 1] + A[:, :, 2] * o[..., 2] + pg[:, p]
    return pg.reshape(batch + (J, 3)), rg.reshape(batch + (J, 3, 3))


def _fk_torch(skeleton, R, batch, root_pos, local_pos):
    import torch

    J = skeleton.n_joints
    offs = torch.tensor(np.array(skeleton.offsets), dtype=R.dtype, device=R.device) if local_pos is None else local_pos
    offs = offs.expand(*batch, J, 3)
    rots, poss = [R[..., 0, :, :]], [offs[..., 0, :] if root_pos is None else root_pos.expand(*batch, 3)]
    for j in range(1, J):
        p = int(skeleton.parents[j])
        rots.append(rots[p] @ R[..., j, :, :])
        poss.append(poss[p] + (rots[p] @ offs[..., j, :, None])[..., 0])
    return torch.stack(poss, dim=-2), torch.stack(rots, dim=-3)


def rest_pose(skeleton: Skeleton) -> np.ndarray:
    """Global joint positions with every local rotation the identity, shape (J, 3), metres."""
    eye = np.broadcast_to(np.eye(3), (skeleton.n_joints, 3, 3))
    return fk(skeleton, eye)[0]


def bone_lengths_of(skeleton: Skeleton, global_pos) -> np.ndarray:
    """Length of each bone (parent -> joint) in posed positions, shape (..., J), metres; 0 for the root.

    Parameters
    ----------
    global_pos : ndarray, shape (..., J, 3)
    """
    global_pos = np.asarray(global_pos, dtype=float)
    if global_pos.shape[-2:] != (skeleton.n_joints, 3):
        raise ValueError(f"global_pos: expected shape (..., {skeleton.n_joints}, 3), got {global_pos.shape}")
    p = np.maximum(skeleton.parents, 0)
    lengths = np.linalg.norm(global_pos - global_pos[..., p, :], axis=-1)
    lengths[..., 0] = 0.0
    return lengths
