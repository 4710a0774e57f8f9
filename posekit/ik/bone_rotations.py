"""Joint rotations for a pose known only by its positions: turn each bone from its old direction to its new one.

Introduced in ``notebooks/05_protores.ipynb``, where FABRIK (which moves positions only) is compared with
models that predict rotations: its result needs local rotations before a rotation error can be measured.
Conventions: :mod:`posekit.conventions` (column vectors, metres).

Parent first, each joint's world rotation is its parent's new rotation times its old local rotation,
then corrected by the rotation ``Q`` that best turns the joint's bones (to its children) onto the new
positions:

* one child: the shortest rotation taking the old bone direction onto the new one (no twist added);
* several children (a pelvis, a chest): the least-squares rotation of the children's offsets onto
  their new positions (Kabsch: ``Q = U diag(1, 1, det(U V^T)) V^T`` from the SVD of the 3 x 3 covariance);
* a leaf: no correction (it keeps its old local rotation).

Where positions came from a pose with these bone lengths, the rotations reproduce them by FK (to the
fit of the multi-child joints, whose children FABRIK may move slightly off their rigid layout).
"""

from __future__ import annotations

import numpy as np

from .._jit import njit
from ..kinematics import fk
from ..rotations import matrix_to_quat, quat_to_matrix
from ..skeleton import Skeleton
from .api import Pose

__all__ = ["rotations_from_positions", "shortest_rotation", "check_roundtrip", "pose_with_rotations"]


def shortest_rotation(a, b) -> np.ndarray:
    """The smallest rotations taking directions ``a`` onto ``b``, both (..., 3): matrices (..., 3, 3).
    Opposite directions turn by pi about an axis perpendicular to ``a``."""
    a = a / np.maximum(np.linalg.norm(a, axis=-1, keepdims=True), 1e-12)
    b = b / np.maximum(np.linalg.norm(b, axis=-1, keepdims=True), 1e-12)
    v = np.cross(a, b)
    c = np.sum(a * b, axis=-1)
    K = np.zeros(a.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    K = K - np.swapaxes(K, -1, -2)
    R = np.eye(3) + K + (K @ K) / np.maximum(1.0 + c, 1e-12)[..., None, None]
    opposite = c < -1.0 + 1e-9
    if np.any(opposite):  # pi about any axis perpendicular to a
        ao = a[opposite]
        helper = np.where(np.abs(ao[:, :1]) < 0.9, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
        axis = np.cross(ao, helper)
        axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
        R[opposite] = 2 * axis[:, :, None] * axis[:, None, :] - np.eye(3)
    return R


def _kabsch(src, dst) -> np.ndarray:
    """Rotations (B, 3, 3) best taking point sets src (B, n, 3) onto dst (B, n, 3), both about the origin."""
    H = np.swapaxes(src, -1, -2) @ dst
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(np.swapaxes(Vt, -1, -2) @ np.swapaxes(U, -1, -2)))
    D = np.zeros_like(H)
    D[:, 0, 0], D[:, 1, 1], D[:, 2, 2] = 1.0, 1.0, d
    return np.swapaxes(Vt, -1, -2) @ D @ np.swapaxes(U, -1, -2)


_BONE_CHILDREN: dict = {}


def _bone_children(skeleton):
    """Each joint's children with a bone (offset longer than 1e-9 m), as CSR arrays (start (J + 1,), index);
    kept per skeleton (its parents and offsets), as the exact finish asks once per solve."""
    off = np.asarray(skeleton.offsets, dtype=float)
    key = (np.asarray(skeleton.parents).tobytes(), off.tobytes())
    if key not in _BONE_CHILDREN:
        _BONE_CHILDREN[key] = _bone_children_of(skeleton, off)
    return _BONE_CHILDREN[key]


def _bone_children_of(skeleton, off):
    kids = [[c for c in skeleton.children(j) if np.linalg.norm(off[c]) > 1e-9] for j in range(skeleton.n_joints)]
    start = np.zeros(len(kids) + 1, dtype=np.int64)
    start[1:] = np.cumsum([len(k) for k in kids])
    return start, np.array([c for k in kids for c in k], dtype=np.int64)


@njit
def _rotations_one(parents, off, kid_start, kids, L0, P, L, G):
    """:func:`rotations_from_positions` for one pose, the same steps joint by joint (compiled: the exact finish
    of :mod:`posekit.ik.finish` runs it once per solve). Writes local ``L`` and world ``G`` (J, 3, 3)."""
    J = parents.shape[0]
    for j in range(J):
        if parents[j] < 0:
            R = L0[j].copy()
        else:
            R = G[parents[j]] @ L0[j]
        n = kid_start[j + 1] - kid_start[j]
        if n == 1:
            c = kids[kid_start[j]]
            a = R @ off[c]
            b = P[c] - P[j]
            a = a / max(np.sqrt((a * a).sum()), 1e-12)
            b = b / max(np.sqrt((b * b).sum()), 1e-12)
            v = np.cross(a, b)
            cs = (a * b).sum()
            K = np.zeros((3, 3))
            K[0, 1], K[0, 2], K[1, 2] = -v[2], v[1], -v[0]
            K[1, 0], K[2, 0], K[2, 1] = v[2], -v[1], v[0]
            if cs < -1.0 + 1e-9:  # opposite: pi about an axis perpendicular to a
                helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
                ax = np.cross(a, helper)
                ax = ax / np.sqrt((ax * ax).sum())
                Q = 2.0 * np.outer(ax, ax) - np.eye(3)
            else:
                Q = np.eye(3) + K + (K @ K) / max(1.0 + cs, 1e-12)
            R = Q @ R
        elif n > 1:
            H = np.zeros((3, 3))
            for k in range(kid_start[j], kid_start[j + 1]):
                c = kids[k]
                H += np.outer(R @ off[c], P[c] - P[j])
            U, _, Vt = np.linalg.svd(H)
            D = np.eye(3)
            D[2, 2] = np.sign(np.linalg.det(Vt.T @ U.T))
            R = Vt.T @ D @ U.T @ R
        G[j] = R
        if parents[j] < 0:
            L[j] = R
        else:
            L[j] = G[parents[j]].T @ R


def rotations_from_positions(skeleton: Skeleton, local_rot, root_pos, global_pos):
    """Local rotations that move a pose's bones onto new joint positions (see the module docstring).

    Parameters
    ----------
    skeleton : Skeleton
    local_rot : ndarray, shape (B, J, 3, 3)
        The old pose's local rotations (where the positions came from: FABRIK's start pose).
    root_pos : ndarray, shape (B, 3), metres
        Unused except for its shape; the new root position is ``global_pos[:, 0]``.
    global_pos : ndarray, shape (B, J, 3), metres
        The new positions.

    Returns
    -------
    local_rot : ndarray, shape (B, J, 3, 3)
    root_pos : ndarray, shape (B, 3)
    """
    L0 = np.asarray(local_rot, dtype=float)
    P = np.asarray(global_pos, dtype=float)
    J = skeleton.n_joints
    if L0.ndim != 4 or L0.shape[1:] != (J, 3, 3) or P.shape != L0.shape[:2] + (3,):
        raise ValueError(f"expected local_rot (B, {J}, 3, 3) and global_pos (B, {J}, 3); got {L0.shape}, {P.shape}")
    off = np.asarray(skeleton.offsets, dtype=float)
    par = skeleton.parents
    G = np.empty_like(L0)
    L = np.empty_like(L0)
    start, kids = _bone_children(skeleton)
    if len(L0) == 1:  # one pose: the compiled twin (numpy's per-call overhead dominates at B = 1)
        _rotations_one(np.asarray(par, dtype=np.int64), np.ascontiguousarray(off), start, kids,
                       np.ascontiguousarray(L0[0]), np.ascontiguousarray(P[0]), L[0], G[0])
        return L, P[:, 0].copy()
    for j in range(J):
        R = L0[:, j] if par[j] < 0 else G[:, par[j]] @ L0[:, j]
        mine = kids[start[j]:start[j + 1]]
        if len(mine) == 1:
            c = mine[0]
            Q = shortest_rotation(R @ off[c], P[:, c] - P[:, j])
            R = Q @ R
        elif len(mine) > 1:
            src = np.stack([R @ off[c] for c in mine], axis=1)
            dst = np.stack([P[:, c] - P[:, j] for c in mine], axis=1)
            R = _kabsch(src, dst) @ R
        G[:, j] = R
        L[:, j] = R if par[j] < 0 else np.swapaxes(G[:, par[j]], -1, -2) @ R
    return L, P[:, 0].copy()


def check_roundtrip(skeleton, local_rot, root_pos) -> float:
    """Largest FK position change (metres) of :func:`rotations_from_positions` applied to a pose's own
    positions: 0 to rounding (a self-check used by the tests)."""
    P = fk(skeleton, local_rot, root_pos)[0]
    L, r = rotations_from_positions(skeleton, local_rot, root_pos, P)
    return float(np.abs(fk(skeleton, L, r)[0] - P).max())


def pose_with_rotations(skeleton: Skeleton, pose, reference, atol: float = 1e-6):
    """A :class:`~posekit.records.Pose` with local rotations that reproduces ``pose``'s positions exactly.

    ``pose`` itself when it has rotations; else rotations turned from ``reference``'s (a Pose with
    rotations, e.g. the solve's start) onto ``pose``'s positions (:func:`rotations_from_positions`). One
    rotation per joint cannot always place every child of a multi-child joint (full-body FABRIK moves a
    pelvis's or a chest's children independently, keeping each bone's length): those children get a
    local translation (``local_pos``, a BVH position channel) of their bone's length in the new direction,
    so that FK of the result gives ``pose.global_pos`` to within ``atol`` metres. Used to write a
    positions-only solver's pose as BVH (``notebooks/06_posing_studio.ipynb``).
    """
    if pose.local_rot is not None:
        return pose
    if reference is None or reference.local_rot is None:
        raise ValueError("a pose known only by its positions needs a reference pose with rotations")
    P = np.asarray(pose.global_pos, float)
    L, root = rotations_from_positions(skeleton, quat_to_matrix(np.asarray(reference.local_rot, float))[None],
                                       P[None, 0], P[None])
    _, G = fk(skeleton, L[0], root[0])
    par = skeleton.parents
    local_pos = np.array(skeleton.offsets, dtype=float)
    for j in range(1, skeleton.n_joints):
        local_pos[j] = G[par[j]].T @ (P[j] - P[par[j]])
    moved = np.linalg.norm(local_pos - skeleton.offsets, axis=-1) > atol
    moved[0] = False
    local_pos = np.where(moved[:, None], local_pos, skeleton.offsets)
    return Pose.from_rotations(skeleton, matrix_to_quat(L[0]), root[0], local_pos if moved.any() else None)
