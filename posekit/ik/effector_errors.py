"""How far a pose is from its effectors: the solvers' one definition of every kind's error.

Introduced in ``notebooks/01_fabrik.ipynb``. The kinds and their errors are tabled in
:mod:`posekit.ik.effectors` (position: metres; rotation and look-at: radians). :func:`effector_errors`
(one pose) and :func:`effector_errors_batch` (B poses) are the solvers' one implementation: every
solver reports its errors through them and its iteration loop stops on the same compiled kernel
(:func:`errors_into`). The benchmarks measure every returned pose with it again
(:mod:`posekit.evaluation.pose_scores`), so no solver's own report is taken on trust.
"""

from __future__ import annotations

import numpy as np

from .._jit import njit
from .effectors import Effector, ResolvedEffectors, as_resolved

__all__ = ["effector_errors", "effector_errors_batch", "errors_into", "errors_of", "position_errors_into",
           "position_errors"]


@njit
def _distance(Pg, j, tpos, k):
    dx = Pg[j, 0] - tpos[k, 0]
    dy = Pg[j, 1] - tpos[k, 1]
    dz = Pg[j, 2] - tpos[k, 2]
    return np.sqrt(dx * dx + dy * dy + dz * dz)


@njit
def position_errors_into(Pg, joints, tpos, out):
    """:func:`errors_into` for position effectors only (the FABRIK kernel, which has no rotations)."""
    for k in range(joints.shape[0]):
        out[k] = _distance(Pg, joints[k], tpos, k)


def position_errors(p, t, axis: int = -1):
    """:func:`errors_into`'s position error in numpy, ``sqrt(dx^2 + dy^2 + dz^2)`` along ``axis``
    (the same operations in the same order, so the same bits; used by the batched FABRIK)."""
    return np.sqrt(((p - t) ** 2).sum(axis=axis))


@njit
def errors_into(Pg, Rg, joints, codes, tpos, trot, axis, out):
    """Every effector error of one pose into ``out`` (K,): the definition the solvers share.

    ``Pg`` (J, 3) and ``Rg`` (J, 3, 3) are world positions and rotations (``Rg`` is read only for
    the angular kinds); ``tpos`` (K, 3), ``trot`` (K, 3, 3), ``axis`` (K, 3) as in
    :class:`ResolvedEffectors`.

    * position: ``sqrt(dx^2 + dy^2 + dz^2)``, metres;
    * rotation: the geodesic angle of ``M = R_j^T R_t``,
      ``atan2(|vee(M - M^T)| / 2, (tr M - 1) / 2)`` (accurate near 0 and pi, unlike ``arccos``);
    * look_at: the angle between ``u = R_j a`` and ``w = t - p_j``, ``atan2(|u x w|, u . w)``
      (pi when the joint sits on its target).
    """
    for k in range(joints.shape[0]):
        j = joints[k]
        c = codes[k]
        if c == 0:
            out[k] = _distance(Pg, j, tpos, k)
        elif c == 1:
            tr = 0.0
            for i in range(3):
                for m in range(3):
                    tr += Rg[j, m, i] * trot[k, m, i]
            # M = R_j^T R_t; its skew part M[a, b] - M[b, a]
            s0 = 0.0
            s1 = 0.0
            s2 = 0.0
            for m in range(3):
                s0 += Rg[j, m, 2] * trot[k, m, 1] - Rg[j, m, 1] * trot[k, m, 2]
                s1 += Rg[j, m, 0] * trot[k, m, 2] - Rg[j, m, 2] * trot[k, m, 0]
                s2 += Rg[j, m, 1] * trot[k, m, 0] - Rg[j, m, 0] * trot[k, m, 1]
            out[k] = np.arctan2(0.5 * np.sqrt(s0 * s0 + s1 * s1 + s2 * s2), 0.5 * (tr - 1.0))
        else:
            ux = Rg[j, 0, 0] * axis[k, 0] + Rg[j, 0, 1] * axis[k, 1] + Rg[j, 0, 2] * axis[k, 2]
            uy = Rg[j, 1, 0] * axis[k, 0] + Rg[j, 1, 1] * axis[k, 1] + Rg[j, 1, 2] * axis[k, 2]
            uz = Rg[j, 2, 0] * axis[k, 0] + Rg[j, 2, 1] * axis[k, 1] + Rg[j, 2, 2] * axis[k, 2]
            wx = tpos[k, 0] - Pg[j, 0]
            wy = tpos[k, 1] - Pg[j, 1]
            wz = tpos[k, 2] - Pg[j, 2]
            if wx * wx + wy * wy + wz * wz < 1e-24:
                out[k] = np.pi
            else:
                cx = uy * wz - uz * wy
                cy = uz * wx - ux * wz
                cz = ux * wy - uy * wx
                out[k] = np.arctan2(np.sqrt(cx * cx + cy * cy + cz * cz), ux * wx + uy * wy + uz * wz)


@njit
def _errors_batch(Pg, Rg, joints, codes, tpos, trot, axis, out):
    for b in range(Pg.shape[0]):
        errors_into(Pg[b], Rg[b], joints, codes, tpos[b], trot[b], axis[b], out[b])


def _global_rotations(skeleton, pose):
    from ..kinematics import fk

    if pose.local_rot is None:
        return None
    root = None if pose.root_pos is None else np.asarray(pose.root_pos, dtype=float)
    lp = None if pose.local_pos is None else np.asarray(pose.local_pos, dtype=float)
    return fk(skeleton, np.asarray(pose.local_rot, dtype=float), root, lp)[1]


def effector_errors(skeleton, pose, effectors) -> tuple[np.ndarray, bool]:
    """How far one pose is from its effectors.

    Parameters
    ----------
    skeleton : Skeleton
    pose : Pose
        ``global_pos`` gives the positions; rotation and look-at effectors also need ``local_rot``
        (global rotations by :func:`posekit.kinematics.fk`).
    effectors : sequence of Effector, or ResolvedEffectors

    Returns
    -------
    errors : ndarray, shape (K,)
        Metres for position effectors, radians for rotation and look-at effectors (see the module
        table).
    converged : bool
        Every error at most its effector's tolerance.
    """
    res = as_resolved(skeleton, effectors)
    pos = np.asarray(pose.global_pos, dtype=float)
    if pos.shape != (skeleton.n_joints, 3):
        raise ValueError(f"pose: expected global_pos of shape ({skeleton.n_joints}, 3), got {pos.shape}")
    rot = None
    if res.angular:
        rot = _global_rotations(skeleton, pose)
        if rot is None:
            k = next(i for i, kind in enumerate(res.kinds) if kind != "position")
            raise ValueError(f"{res.kinds[k]} effector on {res.names[k]}: the pose has no rotations (local_rot); "
                             "only position errors can be measured on it")
    return errors_of(pos, rot, res)


def errors_of(global_pos, global_rot, res: ResolvedEffectors) -> tuple[np.ndarray, bool]:
    """:func:`errors_into` on one pose, ``global_pos`` (J, 3) and ``global_rot`` (J, 3, 3) or None
    (position effectors only), for resolved effectors: (errors (K,), converged)."""
    if global_rot is None:
        if res.angular:
            raise ValueError("rotation and look-at effectors need the joints' rotations; got none")
        global_rot = _NO_ROT
    out = np.empty(len(res))
    errors_into(np.ascontiguousarray(global_pos, dtype=float), np.ascontiguousarray(global_rot, dtype=float),
                res.joints, res.codes, res.position, res.rotation, res.axis, out)
    return out, bool((out <= res.tolerance).all())


_NO_ROT = np.zeros((1, 3, 3))


def _stack(skeleton, effectors, B):
    """One ResolvedEffectors, or B of them with the same joints and kinds -> arrays with a batch axis."""
    if isinstance(effectors, ResolvedEffectors) or (len(effectors) and isinstance(effectors[0], Effector)):
        r = as_resolved(skeleton, effectors)
        rep = lambda a: np.broadcast_to(a, (B,) + a.shape)  # noqa: E731
        return r, rep(r.position), rep(r.rotation), rep(r.axis), rep(r.tolerance)
    rs = [as_resolved(skeleton, e) for e in effectors]
    if len(rs) != B:
        raise ValueError(f"expected {B} effector lists (one per pose), got {len(rs)}")
    r = rs[0]
    for i, o in enumerate(rs[1:], 1):
        if o.kinds != r.kinds or not np.array_equal(o.joints, r.joints):
            raise ValueError(f"effector list {i} has other joints or kinds than list 0; a batch shares them")
    return (r, np.stack([o.position for o in rs]), np.stack([o.rotation for o in rs]),
            np.stack([o.axis for o in rs]), np.stack([o.tolerance for o in rs]))


def effector_errors_batch(skeleton, global_pos, global_rot, effectors) -> tuple[np.ndarray, np.ndarray]:
    """:func:`effector_errors` over a batch of poses.

    Parameters
    ----------
    skeleton : Skeleton
    global_pos : ndarray, shape (B, J, 3), metres
    global_rot : ndarray, shape (B, J, 3, 3), or None
        World rotations (``fk(...)[1]``); needed only for rotation and look-at effectors.
    effectors : sequence of Effector (shared by every pose), sequence of B such sequences (the same
        joints and kinds, their own targets), or ResolvedEffectors

    Returns
    -------
    errors : ndarray, shape (B, K), metres or radians per kind
    converged : ndarray of bool, shape (B,)
    """
    P = np.ascontiguousarray(global_pos, dtype=float)
    J = skeleton.n_joints
    if P.ndim != 3 or P.shape[1:] != (J, 3):
        raise ValueError(f"global_pos: expected shape (B, {J}, 3), got {P.shape}")
    B = P.shape[0]
    r, tpos, trot, axis, tol = _stack(skeleton, effectors, B)
    if r.angular:
        if global_rot is None:
            raise ValueError("rotation and look-at effectors need global_rot (B, J, 3, 3); got None")
        R = np.ascontiguousarray(global_rot, dtype=float)
        if R.shape != (B, J, 3, 3):
            raise ValueError(f"global_rot: expected shape ({B}, {J}, 3, 3), got {R.shape}")
    else:
        R = np.zeros((B, 1, 3, 3))  # not read: position errors only
    out = np.empty((B, len(r)))
    _errors_batch(P, R, r.joints, r.codes, np.ascontiguousarray(tpos), np.ascontiguousarray(trot),
                  np.ascontiguousarray(axis), out)
    return out, np.all(out <= tol, axis=1)
