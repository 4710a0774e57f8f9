"""Reference solutions of lesson 01's exercises (instructor version; ``posekit exercises solutions 01`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_fabrik_planted", "exercise_two_bone_swivel"]


def exercise_fabrik_planted(positions, target, tolerance, max_iter):
    """FABRIK with a planted end: the last joint (a foot) stays, the first joint (the hip) reaches ``target``.

    Algorithm 1 of Aristidou & Lasenby 2011 with the roles swapped: each iteration is a pass from the first joint
    (put on the target, then every joint at bone length from its moved neighbour towards the planted end) and a
    pass back (the planted joint restored, walking out to the first joint); it stops when the first joint is within
    ``tolerance`` of the target or after ``max_iter`` iterations. A target out of reach gets the chain stretched
    straight towards it from the planted joint.

    Parameters
    ----------
    positions : ndarray, shape (n+1, 3), metres
        Joint positions; index n is planted, index 0 reaches.
    target : ndarray, shape (3,), metres
    tolerance : float, metres
    max_iter : int

    Returns
    -------
    ndarray, shape (n+1, 3), metres
        The new positions (a new array; ``positions`` is left alone); every bone keeps its length.
    """
    import numpy as np

    p = np.array(positions, dtype=float)[::-1].copy()  # read from the planted joint: it is now the base, p[0]
    d = np.linalg.norm(np.diff(p, axis=0), axis=1)
    base = p[0].copy()

    if np.linalg.norm(target - base) > d.sum():  # out of reach: point every bone at the target
        for i in range(len(d)):
            u = (target - p[i]) / np.linalg.norm(target - p[i])
            p[i + 1] = p[i] + d[i] * u
        return p[::-1].copy()

    for _ in range(max_iter):
        if np.linalg.norm(p[-1] - target) <= tolerance:
            break
        p[-1] = target  # the reaching joint on the target, then each joint at bone length from its moved neighbour
        for i in range(len(d) - 1, -1, -1):
            u = (p[i] - p[i + 1]) / np.linalg.norm(p[i] - p[i + 1])
            p[i] = p[i + 1] + d[i] * u
        p[0] = base  # the planted joint back in place, then walk out again
        for i in range(len(d)):
            u = (p[i + 1] - p[i]) / np.linalg.norm(p[i + 1] - p[i])
            p[i + 1] = p[i] + d[i] * u
    return p[::-1].copy()


def exercise_two_bone_swivel(root, mid, end, target, swivel):
    """Two-bone IK by the law of cosines, the middle joint placed on its circle by a swivel angle.

    ``d = |target - root|`` clamped to ``[|l1 - l2|, l1 + l2]``; ``cos(alpha) = (l1^2 + d^2 - l2^2) / (2 l1 d)``;
    the bend direction is the current bend (the part of ``mid - root`` across the axis ``u``) turned by ``swivel``
    radians right-handed about ``u`` (Rodrigues' formula for a vector perpendicular to the axis).

    Parameters
    ----------
    root, mid, end : ndarray, shape (3,), metres
    target : ndarray, shape (3,), metres
    swivel : float, radians

    Returns
    -------
    new_mid, new_end : ndarray, shape (3,), metres
    """
    import numpy as np

    l1, l2 = np.linalg.norm(mid - root), np.linalg.norm(end - mid)
    dist = np.linalg.norm(target - root)
    d = np.clip(dist, abs(l1 - l2), l1 + l2)  # the triangle l1, l2, d must exist
    u = (target - root) / dist
    v0 = (mid - root) - ((mid - root) @ u) * u  # the current bend, across the axis
    v0 = v0 / np.linalg.norm(v0)
    v = np.cos(swivel) * v0 + np.sin(swivel) * np.cross(u, v0)  # turned about u
    cos_a = np.clip((l1**2 + d**2 - l2**2) / (2 * l1 * d), -1.0, 1.0)
    new_mid = root + l1 * (cos_a * u + np.sqrt(1.0 - cos_a**2) * v)
    return new_mid, root + d * u
