"""Rotation conversions, the 6D representation and the geodesic distance, for numpy and torch.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``. Conventions (scalar-last quaternions,
column vectors) are in :mod:`posekit.conventions`.

Every function accepts a numpy array *or* a torch tensor and returns the same kind. The numpy path
uses :class:`scipy.spatial.transform.Rotation`; the torch path uses the ``roma`` library, so it is
differentiable. torch is imported only when a tensor is passed in.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = [
    "is_torch",
    "quat_to_matrix",
    "matrix_to_quat",
    "euler_to_quat",
    "quat_to_euler",
    "axis_angle_to_quat",
    "quat_multiply",
    "quat_inverse",
    "matrix_to_sixd",
    "sixd_to_matrix",
    "geodesic_distance",
    "random_rotations",
]


def is_torch(x) -> bool:
    """True when ``x`` is a torch tensor (checked without importing torch)."""
    return type(x).__module__.startswith("torch")


def _check_last(x, dims: tuple, what: str):
    shape = tuple(x.shape)
    if shape[len(shape) - len(dims):] != dims:
        raise ValueError(f"{what}: expected shape (..., {', '.join(map(str, dims))}), got {shape}")


def _scipy_apply(fn, x, in_dims: tuple, out_dims: tuple):
    """Apply a scipy (N, in_dims) -> (N, out_dims) function over arbitrary leading dims."""
    x = np.asarray(x, dtype=float)
    batch = x.shape[: x.ndim - len(in_dims)]
    flat = x.reshape((-1,) + in_dims)
    out = fn(flat) if flat.shape[0] else np.zeros((0,) + out_dims)
    return np.asarray(out).reshape(batch + out_dims)


def quat_to_matrix(q):
    """Unit quaternions to rotation matrices.

    Parameters
    ----------
    q : array or tensor, shape (..., 4)
        Quaternions ``(x, y, z, w)``; normalised before conversion.

    Returns
    -------
    R : shape (..., 3, 3)
    """
    _check_last(q, (4,), "quat_to_matrix")
    if is_torch(q):
        import roma

        return roma.unitquat_to_rotmat(q / q.norm(dim=-1, keepdim=True))
    return _scipy_apply(lambda f: Rotation.from_quat(f).as_matrix(), q, (4,), (3, 3))


def matrix_to_quat(R):
    """Rotation matrices to unit quaternions ``(x, y, z, w)`` with ``w >= 0``.

    Parameters
    ----------
    R : array or tensor, shape (..., 3, 3)

    Returns
    -------
    q : shape (..., 4)
    """
    _check_last(R, (3, 3), "matrix_to_quat")
    if is_torch(R):
        import roma

        q = roma.rotmat_to_unitquat(R)
        return q * (q[..., 3:4] >= 0).to(q.dtype).mul(2).sub(1)
    q = _scipy_apply(lambda f: Rotation.from_matrix(f).as_quat(), R, (3, 3), (4,))
    return np.where(q[..., 3:4] < 0, -q, q)


def euler_to_quat(angles, order: str, degrees: bool = False):
    """Euler angles to quaternions.

    Parameters
    ----------
    angles : array, shape (..., 3)
        Angles in the order of ``order``.
    order : str
        scipy sequence: upper case is intrinsic (BVH: ``"ZXY"`` means ``Rz @ Rx @ Ry``).
    degrees : bool
        Angles in degrees rather than radians.

    Returns
    -------
    q : ndarray, shape (..., 4)
    """
    _check_last(angles, (3,), "euler_to_quat")
    if is_torch(angles):
        import roma

        # roma reads the sequence as scipy does (upper case intrinsic, lower case extrinsic)
        return roma.euler_to_unitquat(order, angles.unbind(-1), degrees=degrees)
    return _scipy_apply(
        lambda f: Rotation.from_euler(order, f, degrees=degrees).as_quat(), angles, (3,), (4,)
    )


def quat_to_euler(q, order: str, degrees: bool = False):
    """Quaternions to Euler angles in the sequence ``order`` (see :func:`euler_to_quat`)."""
    _check_last(q, (4,), "quat_to_euler")
    if is_torch(q):
        import roma

        return roma.unitquat_to_euler(order, q, degrees=degrees)
    import warnings

    with warnings.catch_warnings():  # gimbal lock is expected on some frames; scipy still answers
        warnings.simplefilter("ignore", UserWarning)
        return _scipy_apply(
            lambda f: Rotation.from_quat(f).as_euler(order, degrees=degrees), q, (4,), (3,)
        )


def axis_angle_to_quat(axis, angle):
    """Rotation of ``angle`` radians about ``axis`` as a quaternion.

    Parameters
    ----------
    axis : array, shape (..., 3)
        Rotation axes (normalised here).
    angle : array, shape (...)
        Angles in radians.

    Returns
    -------
    q : ndarray, shape (..., 4)
    """
    if is_torch(axis) or is_torch(angle):
        import torch

        axis = torch.as_tensor(axis)
        angle = torch.as_tensor(angle, dtype=axis.dtype, device=axis.device)
        axis = axis / torch.linalg.norm(axis, dim=-1, keepdim=True)
        half = 0.5 * angle[..., None]
        return torch.cat([axis * torch.sin(half), torch.cos(half)], dim=-1)
    axis = np.asarray(axis, dtype=float)
    angle = np.asarray(angle, dtype=float)
    axis = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
    half = 0.5 * angle[..., None]
    return np.concatenate([axis * np.sin(half), np.cos(half)], axis=-1)


def quat_multiply(a, b):
    """Hamilton product ``a * b`` (apply ``b`` first, then ``a``), shapes (..., 4)."""
    if is_torch(a):
        import roma

        return roma.quat_product(a, b)
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )


def quat_inverse(q):
    """Inverse of unit quaternions (the conjugate), shape (..., 4)."""
    sign = np.array([-1.0, -1.0, -1.0, 1.0])
    if is_torch(q):
        import torch

        return q * torch.as_tensor(sign, dtype=q.dtype, device=q.device)
    return np.asarray(q, dtype=float) * sign


def matrix_to_sixd(R):
    """The 6D representation of Zhou et al. 2019: the first two columns of ``R``.

    Parameters
    ----------
    R : array or tensor, shape (..., 3, 3)

    Returns
    -------
    sixd : shape (..., 6)
        ``[R[:, 0], R[:, 1]]`` concatenated (Sec. 4 / Eq. 14 of Zhou et al. 2019, "On the
        Continuity of Rotation Representations in Neural Networks").
    """
    _check_last(R, (3, 3), "matrix_to_sixd")
    cols = R[..., :, :2]  # (..., 3, 2)
    if is_torch(R):
        return cols.transpose(-1, -2).reshape(*R.shape[:-2], 6)
    return np.swapaxes(cols, -1, -2).reshape(R.shape[:-2] + (6,))


def sixd_to_matrix(sixd):
    """Map any 6D vector to a rotation matrix by Gram-Schmidt (Eq. 15-16 of Zhou et al. 2019).

    ``b1 = a1/|a1|``, ``b2 = (a2 - (b1.a2) b1)/|...|``, ``b3 = b1 x b2``, ``R = [b1 b2 b3]``.

    Parameters
    ----------
    sixd : array or tensor, shape (..., 6)
        Two 3-vectors ``a1, a2``; they need not be orthonormal, only linearly independent.

    Returns
    -------
    R : shape (..., 3, 3)
    """
    _check_last(sixd, (6,), "sixd_to_matrix")
    if is_torch(sixd):
        import roma

        return roma.special_gramschmidt(sixd.reshape(*sixd.shape[:-1], 2, 3).transpose(-1, -2))
    x = np.asarray(sixd, dtype=float)
    a1, a2 = x[..., :3], x[..., 3:]
    n1 = np.linalg.norm(a1, axis=-1, keepdims=True)
    b1 = a1 / np.maximum(n1, 1e-12)
    u2 = a2 - np.sum(b1 * a2, axis=-1, keepdims=True) * b1
    b2 = u2 / np.maximum(np.linalg.norm(u2, axis=-1, keepdims=True), 1e-12)
    b3 = np.cross(b1, b2)
    return np.stack([b1, b2, b3], axis=-1)


def geodesic_distance(R1, R2):
    """Angle in radians of the rotation taking ``R1`` to ``R2``: ``arccos((tr(R1^T R2) - 1) / 2)``.

    Parameters
    ----------
    R1, R2 : array or tensor, shape (..., 3, 3)

    Returns
    -------
    angle : shape (...), radians in [0, pi]
    """
    _check_last(R1, (3, 3), "geodesic_distance")
    _check_last(R2, (3, 3), "geodesic_distance")
    if is_torch(R1):
        import roma

        return roma.rotmat_geodesic_distance(R1, R2)
    rel = np.swapaxes(np.asarray(R1, dtype=float), -1, -2) @ np.asarray(R2, dtype=float)
    # arctan2 form is accurate near 0 and pi, unlike arccos of the trace alone
    tr = np.trace(rel, axis1=-2, axis2=-1)
    skew = np.stack(
        [rel[..., 2, 1] - rel[..., 1, 2], rel[..., 0, 2] - rel[..., 2, 0], rel[..., 1, 0] - rel[..., 0, 1]],
        axis=-1,
    )
    return np.arctan2(0.5 * np.linalg.norm(skew, axis=-1), 0.5 * (tr - 1.0))


def random_rotations(shape, rng: np.random.Generator | int | None = None):
    """Uniformly random unit quaternions, shape ``shape + (4,)``, ``w >= 0``."""
    rng = np.random.default_rng(rng)
    q = rng.normal(size=tuple(np.atleast_1d(shape)) + (4,))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., 3:4] < 0, -q, q)
