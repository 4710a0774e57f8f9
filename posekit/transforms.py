"""Whole-pose transforms: left/right mirroring, rotation about the up axis, and the root frame.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``. Axes: :mod:`posekit.conventions`
(Y up, facing +Z, mirroring reflects x -> -x).

The *root frame* follows Victor et al. 2021 (Sec. 3.2): its origin is the pelvis projected on the
floor (y = 0) and it faces +Z, so a pose expressed in it no longer depends on where the character
stands or which way it looks.
"""

from __future__ import annotations

import numpy as np

from .conventions import UP
from .rotations import axis_angle_to_quat, quat_multiply
from .skeleton import Skeleton

__all__ = [
    "mirror_positions",
    "mirror_rotations",
    "mirror_frame_signs",
    "mirror_rotation_matrices",
    "rotate_y_positions",
    "rotate_y_rotations",
    "facing_angle",
    "root_frame",
    "to_root_space",
    "from_root_space",
]

_FLIP_X = np.array([-1.0, 1.0, 1.0])


def _check_positions(skeleton: Skeleton, global_pos) -> np.ndarray:
    global_pos = np.asarray(global_pos, dtype=float)
    if global_pos.ndim < 2 or global_pos.shape[-2:] != (skeleton.n_joints, 3):
        raise ValueError(
            f"global_pos: expected shape (..., {skeleton.n_joints}, 3) for skeleton "
            f"{skeleton.name or '(unnamed)'}, got {global_pos.shape}"
        )
    return global_pos


def mirror_positions(skeleton: Skeleton, global_pos) -> np.ndarray:
    """Reflect joint positions across the YZ plane and swap left/right joints.

    Parameters
    ----------
    global_pos : ndarray, shape (..., J, 3), metres

    Returns
    -------
    ndarray, shape (..., J, 3)
    """
    global_pos = _check_positions(skeleton, global_pos)
    return global_pos[..., skeleton.mirror_indices(), :] * _FLIP_X


def mirror_rotations(skeleton: Skeleton, local_rot, root_pos):
    """Mirror a pose given as local quaternions: ``q = (x, y, z, w) -> (x, -y, -z, w)``, sides swapped.

    Reflecting by ``M = diag(-1, 1, 1)`` maps a rotation ``R`` to ``M R M``, which on quaternions
    negates the y and z components. FK of the result equals :func:`mirror_positions` of FK of the
    input exactly when the skeleton is symmetric (:meth:`Skeleton.is_symmetric`).

    Parameters
    ----------
    local_rot : ndarray, shape (..., J, 4)
    root_pos : ndarray, shape (..., 3), metres

    Returns
    -------
    local_rot : ndarray, shape (..., J, 4)
    root_pos : ndarray, shape (..., 3)
    """
    local_rot = np.asarray(local_rot, dtype=float)
    if local_rot.shape[-2:] != (skeleton.n_joints, 4):
        raise ValueError(f"local_rot: expected shape (..., {skeleton.n_joints}, 4), got {local_rot.shape}")
    q = local_rot[..., skeleton.mirror_indices(), :] * np.array([1.0, -1.0, -1.0, 1.0])
    return q, np.asarray(root_pos, dtype=float) * _FLIP_X


_REFLECTIONS = np.array([[-1.0, 1, 1], [1, -1, 1], [1, 1, -1], [-1, -1, -1]])
"""The diagonal reflections (det -1) a joint's frame may need when a pose is mirrored."""


def mirror_frame_signs(skeleton: Skeleton, local_rot=None) -> np.ndarray:
    """Per-joint frame reflections that mirror a skeleton whose local frames are not mirror images.

    :func:`mirror_rotations` needs a symmetric skeleton (offsets that are mirror images in every
    joint's frame). Many capture skeletons (the Bandai Namco one: every bone along its joint's local
    +x, left and right frames not reflected) are not. Mirroring a pose then maps joint ``j``'s world
    rotation to ``R'_{m(j)} = M R_j D_j`` with ``M = diag(-1, 1, 1)`` and ``D_j`` a diagonal reflection,
    chosen so that the mirrored bones keep their lengths: ``D_j o_{m(c)} = o_c`` for every child ``c``
    of ``j`` (``o`` the rest offsets). Where several reflections satisfy that (a joint with one child on
    its x axis, a leaf), the one whose mirrored local rotations look most like the other side's
    (the mean rotation matrix over ``local_rot``) is taken.

    Parameters
    ----------
    skeleton : Skeleton
    local_rot : ndarray, shape (F, J, 3, 3), optional
        Sample poses for the tie-break (default: the tie is broken towards the parent's choice).

    Returns
    -------
    signs : ndarray, shape (J, 3)
        The diagonal of ``D_j``; ``prod(signs[j]) == -1``.
    """
    J, m, off, par = skeleton.n_joints, skeleton.mirror_indices(), np.asarray(skeleton.offsets), skeleton.parents
    mean = None if local_rot is None else np.asarray(local_rot, dtype=float).mean(axis=0)
    signs = np.zeros((J, 3))
    for j in range(J):  # parents come first
        kids = np.nonzero(par == j)[0]
        err = np.array([sum(np.abs(d * off[m[c]] - off[c]).sum() for c in kids) for d in _REFLECTIONS])
        ok = np.nonzero(err <= err.min() + 2e-3)[0]
        dp = _FLIP_X if par[j] < 0 else signs[par[j]]
        if len(ok) == 1:
            signs[j] = _REFLECTIONS[ok[0]]
        elif mean is None:
            same = [i for i in ok if np.array_equal(_REFLECTIONS[i], dp)]
            signs[j] = _REFLECTIONS[same[0] if same else ok[0]]
        else:
            cost = [np.abs(dp[:, None] * mean[j] * _REFLECTIONS[i][None, :] - mean[m[j]]).sum() for i in ok]
            signs[j] = _REFLECTIONS[ok[int(np.argmin(cost))]]
    return signs


def mirror_rotation_matrices(skeleton: Skeleton, local_rot, root_pos, signs=None):
    """Mirror poses given as local rotation matrices, for any skeleton (see :func:`mirror_frame_signs`).

    ``R'_{m(j)} = D_{p(j)} R_j D_j`` (local rotations; ``D_{p(root)} = M``) and ``root' = M root``.
    FK of the result equals :func:`mirror_positions` of FK of the input up to the skeleton's own
    asymmetry (on the Bandai skeleton: under 0.5 mm).

    Parameters
    ----------
    local_rot : ndarray, shape (..., J, 3, 3)
    root_pos : ndarray, shape (..., 3), metres
    signs : ndarray, shape (J, 3), optional
        :func:`mirror_frame_signs` (default: computed without sample poses).

    Returns
    -------
    local_rot : ndarray, shape (..., J, 3, 3)
    root_pos : ndarray, shape (..., 3)
    """
    R = np.asarray(local_rot, dtype=float)
    if R.shape[-3:] != (skeleton.n_joints, 3, 3):
        raise ValueError(f"local_rot: expected shape (..., {skeleton.n_joints}, 3, 3), got {R.shape}")
    d = mirror_frame_signs(skeleton) if signs is None else np.asarray(signs, dtype=float)
    par = skeleton.parents
    dp = np.stack([_FLIP_X if p < 0 else d[p] for p in par])
    out = np.empty_like(R)
    out[..., skeleton.mirror_indices(), :, :] = dp[:, :, None] * R * d[:, None, :]
    return out, np.asarray(root_pos, dtype=float) * _FLIP_X


def _yaw_quat(angle):
    angle = np.asarray(angle, dtype=float)
    return axis_angle_to_quat(np.broadcast_to(UP, angle.shape + (3,)), angle)


def _yaw_matrix(angle):
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    z, o = np.zeros_like(angle), np.ones_like(angle)
    return np.stack([np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], -2)


def rotate_y_positions(global_pos, angle) -> np.ndarray:
    """Rotate positions about the world up axis through the origin.

    Parameters
    ----------
    global_pos : ndarray, shape (..., J, 3)
    angle : float or ndarray, shape (...), radians, counter-clockwise seen from above (+Z towards +X)
    """
    return np.einsum("...ab,...jb->...ja", _yaw_matrix(angle), np.asarray(global_pos, dtype=float))


def rotate_y_rotations(local_rot, root_pos, angle):
    """Rotate a pose given as local quaternions about the world up axis: only the root changes.

    Parameters
    ----------
    local_rot : ndarray, shape (..., J, 4)
    root_pos : ndarray, shape (..., 3)
    angle : float or ndarray, shape (...), radians
    """
    local_rot = np.array(local_rot, dtype=float)
    local_rot[..., 0, :] = quat_multiply(_yaw_quat(angle), local_rot[..., 0, :])
    root = np.einsum("...ab,...b->...a", _yaw_matrix(angle), np.asarray(root_pos, dtype=float))
    return local_rot, root


def facing_angle(skeleton: Skeleton, global_pos) -> np.ndarray:
    """Heading of each pose: the angle about +Y that turns +Z onto the facing direction.

    The facing direction is ``across x up`` projected on the floor, where ``across`` is the mean of
    the right-to-left hip and shoulder vectors (the skeleton must have the roles ``left_hip``,
    ``right_hip`` and, optionally, ``left_shoulder``/``right_shoulder``).

    Parameters
    ----------
    global_pos : ndarray, shape (..., J, 3)

    Returns
    -------
    angle : ndarray, shape (...), radians
    """
    global_pos = _check_positions(skeleton, global_pos)
    pairs = [("left_hip", "right_hip"), ("left_shoulder", "right_shoulder")]
    across = 0.0
    for left, right in pairs:
        if left in skeleton.roles and right in skeleton.roles:
            across = across + global_pos[..., skeleton.index(left), :] - global_pos[..., skeleton.index(right), :]
    if isinstance(across, float):
        skeleton.require_roles(("left_hip", "right_hip"), "the facing direction (facing_angle, to_root_space)")
    forward = np.cross(across, UP)
    return np.arctan2(forward[..., 0], forward[..., 2])


def root_frame(skeleton: Skeleton, global_pos):
    """The root frame of each pose (Victor et al. 2021, Sec. 3.2).

    Returns
    -------
    origin : ndarray, shape (..., 3)
        Pelvis projected on the floor (y = 0), metres.
    angle : ndarray, shape (...)
        Facing angle (see :func:`facing_angle`), radians.
    """
    global_pos = _check_positions(skeleton, global_pos)
    pelvis = global_pos[..., skeleton.pelvis(), :]
    origin = pelvis * np.array([1.0, 0.0, 1.0])
    return origin, facing_angle(skeleton, global_pos)


def to_root_space(skeleton: Skeleton, global_pos):
    """Express poses in their root frame: pelvis above the origin, facing +Z.

    Parameters
    ----------
    global_pos : ndarray, shape (..., J, 3), metres

    Returns
    -------
    local : ndarray, shape (..., J, 3)
        Positions in the root frame.
    origin, angle : see :func:`root_frame`; pass them to :func:`from_root_space` to undo.
    """
    global_pos = _check_positions(skeleton, global_pos)
    origin, angle = root_frame(skeleton, global_pos)
    local = rotate_y_positions(global_pos - origin[..., None, :], -angle)
    return local, origin, angle


def from_root_space(local, origin, angle) -> np.ndarray:
    """Inverse of :func:`to_root_space`: put root-frame positions back in the world."""
    return rotate_y_positions(local, angle) + np.asarray(origin)[..., None, :]
