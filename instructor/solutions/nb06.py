"""Reference solutions of lesson 06's exercises (instructor version; ``posekit exercises solutions 06`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_drag_on_sphere", "exercise_slerp"]


def exercise_drag_on_sphere(c, q, centre, radius):
    """A joint dragged on the sphere of its bone around its parent: the bone keeps its length (an FK drag).

    The ray is ``c + t d``, ``d = q - c``, ``t >= 0``. With ``t_c = ((centre - c) . d) / (d . d)`` (the line's point
    nearest the centre, ``x_c = c + t_c d``) and ``h^2 = radius^2 - |x_c - centre|^2``, the line meets the sphere
    at ``t = t_c -+ sqrt(h^2 / (d . d))`` when ``h^2 >= 0``; the answer is the first of them in front of the camera
    (``t > 0``: from inside the sphere, the far one). When neither is in front (the ray passes beside the sphere,
    or the sphere is behind the camera), the joint goes to the sphere's point nearest the ray,
    ``centre + radius (x - centre) / |x - centre|`` with ``x = c + max(t_c, 0) d``. Both rules give the same point
    where the ray just touches the sphere, so the joint does not jump as the mouse leaves the sphere's outline.

    Parameters
    ----------
    c : ndarray, shape (3,), metres
        Camera position.
    q : ndarray, shape (3,), metres
        A point on the mouse ray (``q - c`` is not of unit length).
    centre : ndarray, shape (3,), metres
        The parent joint.
    radius : float, metres
        The bone's length.

    Returns
    -------
    ndarray, shape (3,), metres
        A point at ``radius`` from ``centre``.
    """
    import numpy as np

    c, q, centre = (np.asarray(a, dtype=float) for a in (c, q, centre))
    d = q - c
    dd = d @ d
    t_c = ((centre - c) @ d) / dd
    h2 = radius**2 - np.sum((c + t_c * d - centre) ** 2)
    if h2 >= 0:
        dt = np.sqrt(h2 / dd)
        for t in (t_c - dt, t_c + dt):  # the nearer first
            if t > 0:
                return c + t * d
    x = c + max(t_c, 0.0) * d  # the ray's point nearest the centre
    v = x - centre
    return centre + radius * v / np.linalg.norm(v)


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
