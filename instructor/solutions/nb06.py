"""Reference solutions of lesson 06's exercises (instructor version; ``posekit exercises solutions 06`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_drag", "exercise_slerp"]


def exercise_drag(c, q, p0, n):
    """Where the mouse ray meets the drag plane: a ray-plane intersection.

    The ray runs from the camera ``c`` through ``q``, ``c + t d`` with ``d = q - c``; the plane passes
    through ``p0`` with normal ``n``, so ``t = ((p0 - c) . n) / (d . n)``. No point when the ray runs along
    the plane (``d . n = 0``) or meets it behind the camera (``t <= 0``).

    Parameters
    ----------
    c : ndarray, shape (3,), metres
        Camera position.
    q : ndarray, shape (3,), metres
        A point on the mouse ray.
    p0 : ndarray, shape (3,), metres
        The grabbed point, on the plane.
    n : ndarray, shape (3,)
        Plane normal (need not be unit).

    Returns
    -------
    ndarray, shape (3,), metres, or None
    """
    import numpy as np

    d = q - c
    denom = d @ n
    if abs(denom) <= 1e-12 * np.linalg.norm(d) * np.linalg.norm(n):  # parallel, up to rounding
        return None
    t = ((p0 - c) @ n) / denom
    if t <= 0:  # the plane is behind the camera
        return None
    return c + t * d


def exercise_slerp(q0, q1, s):
    """Spherical linear interpolation of unit quaternions (Shoemake 1985), the shorter way round.

    With ``cos(theta) = q0 . q1 >= 0`` (else ``q1`` is replaced by ``-q1``, the same rotation):
    ``slerp(q0, q1; s) = (sin((1 - s) theta) q0 + sin(s theta) q1) / sin(theta)``. For nearly equal
    quaternions ``sin(theta)`` is tiny, and the normalised linear interpolation is used instead.

    Parameters
    ----------
    q0, q1 : ndarray, shape (4,)
        Unit quaternions ``(x, y, z, w)``.
    s : float
        0 gives ``q0``, 1 gives ``q1``.

    Returns
    -------
    ndarray, shape (4,)
        A unit quaternion.
    """
    import numpy as np

    q0, q1 = np.asarray(q0, dtype=float), np.asarray(q1, dtype=float)
    cos_theta = q0 @ q1
    if cos_theta < 0:  # q1 and -q1 are the same rotation: take the nearer one
        q1, cos_theta = -q1, -cos_theta
    theta = np.arccos(np.clip(cos_theta, -1.0, 1.0))
    sin_theta = np.sin(theta)
    if sin_theta < 1e-6:  # nearly equal: dividing by sin(theta) would lose all precision
        q = (1 - s) * q0 + s * q1
        return q / np.linalg.norm(q)
    return (np.sin((1 - s) * theta) * q0 + np.sin(s * theta) * q1) / sin_theta
