"""Checkers for ``notebooks/06_posing_studio.ipynb``."""

from __future__ import annotations

import numpy as np

from ._check import report
from ._judge import judged


@judged
def check_drag_point(my_drag) -> bool:
    """Check ``my_drag(camera (3,), through (3,), plane_point (3,), plane_normal (3,)) -> (3,) or None``: where
    the ray from the camera through ``through`` meets the plane, ``c + t d`` with ``d = through - c`` and
    ``t = ((p0 - c) . n) / (d . n)``; None when the ray is parallel to the plane or meets it behind the
    camera (:func:`posekit.viz.drag.drag_point`)."""
    from ..viz.drag import drag_point

    rng = np.random.default_rng(16)
    cases = []

    def describe(got, exp):
        return f"got {got}, expected {exp}; t = ((p0 - c) . n) / (d . n), and None when t <= 0 or d . n = 0?"
    for _ in range(4):
        c, p0 = rng.normal(size=3) * 3, rng.normal(size=3)
        n = c - p0
        through = c + (p0 + rng.normal(size=3) * 0.5 - c) * rng.uniform(0.2, 0.8)
        cases.append(((c, through, p0, n), drag_point(c, through, p0, n), describe))
    c = np.array([0.0, 1.0, 4.0])
    cases.append(((c, c + [1.0, 0.0, 0.0], np.zeros(3), np.array([0.0, 0.0, 1.0])), None, describe))  # parallel
    cases.append(((c, c + [0.0, 0.0, 1.0], np.zeros(3), np.array([0.0, 0.0, 1.0])), None, describe))  # behind

    def flat(*a):
        out = my_drag(*a)
        return None if out is None else np.asarray(out, float)
    return report("check_drag_point", flat, cases, atol=1e-9)


@judged
def check_slerp(my_slerp) -> bool:
    """Check ``my_slerp(q0 (4,), q1 (4,), s) -> (4,)``: spherical linear interpolation of unit quaternions
    ``(x, y, z, w)`` the shorter way round (flip ``q1`` when ``q0 . q1 < 0``); compared as rotations, so
    ``q`` and ``-q`` are both right (:func:`posekit.ik.keyframes.slerp`)."""
    from ..ik.keyframes import slerp
    from ..rotations import random_rotations

    rng = np.random.default_rng(17)
    q = random_rotations((6,), rng)
    cases = []

    def describe(got, exp):
        return f"got {np.round(got, 4)}, expected {np.round(exp, 4)} (or its negative); the shorter way round?"
    for k, s in zip(range(0, 6, 2), (0.25, 0.5, 0.9)):
        cases.append(((q[k], q[k + 1], s), slerp(q[k], q[k + 1], s), describe))
        cases.append(((q[k], -q[k + 1], s), slerp(q[k], q[k + 1], s), describe))

    def flat(q0, q1, s):
        out = np.asarray(my_slerp(q0, q1, s), float)
        exp = slerp(q0, q1, s)
        return out if out @ exp >= 0 else -out  # the same rotation either sign
    return report("check_slerp", flat, cases, atol=1e-7)
