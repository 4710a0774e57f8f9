"""Small compiled helpers shared by the rotation-based solvers (CCD, DLS): FK of one pose,
Rodrigues' formula, the rotation vector of a matrix and the shortest rotation between two directions. Conventions:
:mod:`posekit.conventions` (column vectors, parent-first FK)."""

from __future__ import annotations

import numpy as np

from .._jit import njit
from ..rotations import matrix_to_quat, quat_to_matrix
from ..skeleton import Skeleton
from .api import Pose


@njit
def fk_one(parents, local_pos, Rl, root_pos, Rg, Pg):
    """FK of one pose into ``Rg`` (J, 3, 3) and ``Pg`` (J, 3); ``local_pos`` (J, 3)."""
    J = parents.shape[0]
    for a in range(3):
        Pg[0, a] = root_pos[a]
        for b in range(3):
            Rg[0, a, b] = Rl[0, a, b]
    for j in range(1, J):
        p = parents[j]
        R = Rg[p] @ Rl[j]
        o = Rg[p] @ local_pos[j]
        # element copies: slice assignment (Rg[j] = ...) costs numba seconds of compile time
        for a in range(3):
            Pg[j, a] = Pg[p, a] + o[a]
            for b in range(3):
                Rg[j, a, b] = R[a, b]


@njit
def rodrigues(wx, wy, wz):
    """Rotation matrix of the rotation vector (wx, wy, wz) (axis * angle, radians)."""
    th = np.sqrt(wx * wx + wy * wy + wz * wz)
    R = np.eye(3)
    if th < 1e-12:
        return R
    kx, ky, kz = wx / th, wy / th, wz / th
    c, s = np.cos(th), np.sin(th)
    v = 1.0 - c
    R[0, 0] = c + kx * kx * v
    R[0, 1] = kx * ky * v - kz * s
    R[0, 2] = kx * kz * v + ky * s
    R[1, 0] = ky * kx * v + kz * s
    R[1, 1] = c + ky * ky * v
    R[1, 2] = ky * kz * v - kx * s
    R[2, 0] = kz * kx * v - ky * s
    R[2, 1] = kz * ky * v + kx * s
    R[2, 2] = c + kz * kz * v
    return R


@njit
def rotation_between(a, b):
    """Shortest rotation taking direction ``a`` to direction ``b`` (both (3,))."""
    na = np.sqrt(a[0] ** 2 + a[1] ** 2 + a[2] ** 2)
    nb = np.sqrt(b[0] ** 2 + b[1] ** 2 + b[2] ** 2)
    if na < 1e-12 or nb < 1e-12:
        return np.eye(3)
    ax = (a[1] * b[2] - a[2] * b[1]) / (na * nb)
    ay = (a[2] * b[0] - a[0] * b[2]) / (na * nb)
    az = (a[0] * b[1] - a[1] * b[0]) / (na * nb)
    s = np.sqrt(ax * ax + ay * ay + az * az)
    c = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (na * nb)
    ang = np.arctan2(s, c)
    if s < 1e-12:
        return np.eye(3)  # parallel (or exactly opposite: no unique rotation, skip this step)
    return rodrigues(ax / s * ang, ay / s * ang, az / s * ang)


@njit
def rotate_joint(Rl, Rg, parents, j, Rw):
    """Turn joint ``j`` by the world-frame rotation ``Rw``: its local rotation becomes
    ``Rg[parent]^T Rw Rg[parent] Rl[j]``."""
    p = parents[j]
    if p < 0:
        R = Rw @ Rl[j]
    else:
        R = Rg[p].T @ (Rw @ (Rg[p] @ Rl[j]))
    # re-orthonormalise (Gram-Schmidt on the columns): thousands of products would otherwise drift
    # away from a rotation and stretch bones by micrometres
    a = R[:, 0] / np.sqrt(R[0, 0] ** 2 + R[1, 0] ** 2 + R[2, 0] ** 2)
    b = R[:, 1] - (a[0] * R[0, 1] + a[1] * R[1, 1] + a[2] * R[2, 1]) * a
    b = b / np.sqrt(b[0] ** 2 + b[1] ** 2 + b[2] ** 2)
    for i in range(3):
        Rl[j, i, 0] = a[i]
        Rl[j, i, 1] = b[i]
    Rl[j, 0, 2] = a[1] * b[2] - a[2] * b[1]
    Rl[j, 1, 2] = a[2] * b[0] - a[0] * b[2]
    Rl[j, 2, 2] = a[0] * b[1] - a[1] * b[0]


def rotations_of(skeleton: Skeleton, start: Pose, who: str):
    """Local matrices (J, 3, 3), root position (3,) and local translations (J, 3) of a start pose."""
    from .api import check_pose

    check_pose(skeleton, start)
    if start.local_rot is None or start.root_pos is None:
        raise ValueError(f"{who} turns joints, so the start Pose needs local_rot and root_pos "
                         "(use Pose.from_rotations)")
    q = np.asarray(start.local_rot, dtype=float)
    if q.shape != (skeleton.n_joints, 4) or not np.all(np.isfinite(q)):
        raise ValueError(f"start.local_rot: expected finite quaternions of shape ({skeleton.n_joints}, 4), got {q.shape}")
    local_pos = skeleton.offsets if start.local_pos is None else np.asarray(start.local_pos, dtype=float)
    return (np.ascontiguousarray(quat_to_matrix(q)), np.asarray(start.root_pos, dtype=float).copy(),
            np.ascontiguousarray(local_pos, dtype=float))


def pose_from(Rl, root_pos, Pg, local_pos=None) -> Pose:
    """The :class:`~posekit.records.Pose` a rotation solver returns.

    Parameters
    ----------
    Rl : ndarray, shape (J, 3, 3)
        Solved local rotations (stored as quaternions ``(x, y, z, w)``).
    root_pos : ndarray, shape (3,), metres
    Pg : ndarray, shape (J, 3), metres
        Their FK positions (the kernel's, so the pose is exactly what was measured).
    local_pos : ndarray, shape (J, 3), optional
        The start pose's own joint translations, when it had them (None: the skeleton's offsets).
    """
    return Pose(Pg.copy(), matrix_to_quat(Rl), root_pos.copy(), None if local_pos is None else np.array(local_pos))


def rotatable(skeleton: Skeleton, eff_idx, base: int, turns_self=None) -> np.ndarray:
    """Joints the rotation solvers may turn: those on a chain from an effector's parent up to the
    base (the base turns too; its ancestors stay fixed), and the effector itself where
    ``turns_self[k]`` (rotation and look-at effectors: a joint's own rotation sets where it faces).
    Shape (J,) bool."""
    fixed = np.zeros(skeleton.n_joints, dtype=bool)
    fixed[skeleton.chain(base, 0)[:-1]] = True
    out = np.zeros(skeleton.n_joints, dtype=bool)
    for k, e in enumerate(eff_idx):
        j = int(e) if turns_self is not None and turns_self[k] else int(skeleton.parents[e])
        while j >= 0 and not fixed[j]:
            out[j] = True
            j = int(skeleton.parents[j])
    return out


@njit
def log_rotation(R):
    """Rotation vector (axis * angle, radians, |w| <= pi) of the rotation matrix ``R`` (3, 3): the
    inverse of :func:`rodrigues`; robust near 0 and pi."""
    sx = R[2, 1] - R[1, 2]
    sy = R[0, 2] - R[2, 0]
    sz = R[1, 0] - R[0, 1]
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    s = np.sqrt(sx * sx + sy * sy + sz * sz)  # 2 sin(angle)
    ang = np.arctan2(0.5 * s, 0.5 * (tr - 1.0))
    if s > 1e-6:
        f = ang / s
        return sx * f, sy * f, sz * f
    if tr > 0.0:  # angle ~ 0: w ~ vee(R - R^T) / 2
        return 0.5 * sx, 0.5 * sy, 0.5 * sz
    # angle ~ pi: R + I ~ 2 a a^T; the column with the largest diagonal gives the axis
    i = 0
    if R[1, 1] > R[i, i]:
        i = 1
    if R[2, 2] > R[i, i]:
        i = 2
    d = np.sqrt(max(0.5 * (R[i, i] + 1.0), 1e-300))
    ax = 0.5 * (R[0, i] + (1.0 if i == 0 else 0.0)) / d
    ay = 0.5 * (R[1, i] + (1.0 if i == 1 else 0.0)) / d
    az = 0.5 * (R[2, i] + (1.0 if i == 2 else 0.0)) / d
    if ax * sx + ay * sy + az * sz < 0.0:
        ax, ay, az = -ax, -ay, -az
    n = np.sqrt(ax * ax + ay * ay + az * az)
    return ax / n * ang, ay / n * ang, az / n * ang
