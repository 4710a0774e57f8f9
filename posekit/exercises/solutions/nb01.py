"""Reference solutions of lesson 01's exercises (instructor version; ``posekit exercises solutions 01`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_fabrik_chain", "exercise_two_bone"]


def exercise_fabrik_chain(positions, target, tolerance, max_iter):
    """FABRIK on a single chain (Algorithm 1 of Aristidou & Lasenby 2011).

    Repeats a backward pass (end on the target, walk to the base) and a forward pass (base back in
    place, walk to the end), each step a projection onto a sphere of the bone's length, until the end is
    within ``tolerance`` of the target or ``max_iter`` iterations have run. An unreachable target gets
    the chain stretched straight towards it.

    Parameters
    ----------
    positions : ndarray, shape (n+1, 3), metres
        Joint positions from the base (index 0, stays fixed) to the end effector (index n).
    target : ndarray, shape (3,), metres
    tolerance : float, metres
    max_iter : int

    Returns
    -------
    ndarray, shape (n+1, 3), metres
        The new positions; every bone keeps its length.
    """
    import numpy as np

    p = np.array(positions, dtype=float)  # a copy: the caller's array is left alone
    d = np.linalg.norm(np.diff(p, axis=0), axis=1)  # bone lengths d_i = |p_{i+1} - p_i|
    base = p[0].copy()

    if np.linalg.norm(target - base) > d.sum():  # out of reach: point every bone at the target
        for i in range(len(d)):
            u = (target - p[i]) / np.linalg.norm(target - p[i])
            p[i + 1] = p[i] + d[i] * u
        return p

    for _ in range(max_iter):
        if np.linalg.norm(p[-1] - target) <= tolerance:
            break
        # backward: the end on the target, then each joint at bone length from its (moved) child
        p[-1] = target
        for i in range(len(d) - 1, -1, -1):
            u = (p[i] - p[i + 1]) / np.linalg.norm(p[i] - p[i + 1])
            p[i] = p[i + 1] + d[i] * u
        # forward: the base back in place, then each joint at bone length from its (moved) parent
        p[0] = base
        for i in range(len(d)):
            u = (p[i + 1] - p[i]) / np.linalg.norm(p[i + 1] - p[i])
            p[i + 1] = p[i] + d[i] * u
    return p


def exercise_two_bone(root, mid, end, target, pole):
    """Analytic two-bone IK (shoulder-elbow-wrist, hip-knee-ankle) by the law of cosines.

    With ``l1 = |mid - root|``, ``l2 = |end - mid|`` and ``d = |target - root|`` clamped to the reachable
    range ``[|l1 - l2|, l1 + l2]``, the angle at the root between the root-target line and the first bone is
    ``cos(alpha) = (l1^2 + d^2 - l2^2) / (2 l1 d)``; the middle joint bends towards ``pole``.

    Parameters
    ----------
    root, mid, end : ndarray, shape (3,), metres
        Current joint positions (they give the bone lengths).
    target : ndarray, shape (3,), metres
    pole : ndarray, shape (3,), metres
        A point the middle joint should bend towards (behind the elbow, in front of the knee).

    Returns
    -------
    new_mid, new_end : ndarray, shape (3,), metres
        ``new_end`` is on the target whenever it is reachable, else as near as the bones allow.
    """
    import numpy as np

    l1 = np.linalg.norm(mid - root)
    l2 = np.linalg.norm(end - mid)
    dist = np.linalg.norm(target - root)
    eps = 1e-6
    d = np.clip(dist, abs(l1 - l2) + eps, l1 + l2 - eps)  # the triangle l1, l2, d must exist
    u = (target - root) / dist                            # unit vector root -> target

    # bend direction: the pole made perpendicular to the root-target line
    v = (pole - root) - ((pole - root) @ u) * u
    v = v / np.linalg.norm(v)

    cos_a = (l1**2 + d**2 - l2**2) / (2 * l1 * d)        # law of cosines
    cos_a = np.clip(cos_a, -1.0, 1.0)                     # guard against rounding
    sin_a = np.sqrt(1.0 - cos_a**2)
    new_mid = root + l1 * (cos_a * u + sin_a * v)
    new_end = root + d * u
    return new_mid, new_end
