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
        if exp is None:
            return (f"got {got}, expected None: the ray is parallel to the plane (d . n = 0) or meets it behind "
                    "or at the camera (t <= 0)")
        if got is None:
            return f"got None, expected {exp}: the ray meets the plane in front of the camera (t > 0)"
        return f"got {got}, expected {exp}; t = ((p0 - c) . n) / (d . n) with the plane's own normal n?"
    for k in range(6):
        c, p0 = rng.normal(size=3) * 3, rng.normal(size=3)
        n = c - p0 if k < 2 else rng.normal(size=3)  # facing the camera, then any normal (n is not c - p0)
        through = c + (p0 + rng.normal(size=3) * 0.5 - c) * rng.uniform(0.2, 0.8)
        if (through - c) @ n != 0 and ((p0 - c) @ n) / ((through - c) @ n) > 0:
            cases.append(((c, through, p0, n), drag_point(c, through, p0, n), describe))
    c = np.array([0.0, 1.0, 4.0])
    z = np.array([0.0, 0.0, 1.0])
    cases.append(((c, c + [1.0, 0.0, 0.0], np.zeros(3), z), None, describe))  # parallel, the plane behind
    cases.append(((c, c + [1.0, 0.0, 0.0], np.array([0.0, 0.0, 9.0]), z), None, describe))  # parallel, in front
    cases.append(((c, c + [0.0, 0.0, 1.0], np.zeros(3), z), None, describe))  # meets it behind the camera
    cases.append(((c, c + [0.3, 0.0, -1.0], c.copy(), z), None, describe))  # the camera on the plane: t = 0
    cases.append(((c, c + [0.0, 0.5, -2.0], np.zeros(3), 3 * z), drag_point(c, c + [0.0, 0.5, -2.0], np.zeros(3),
                                                                         3 * z), describe))  # n not of unit length

    def flat(*a):
        out = my_drag(*a)
        return None if out is None else np.asarray(out, float)
    return report("check_drag_point", flat, cases, atol=1e-9, forbid=(drag_point,),
                  arg_names=("camera", "through", "plane_point", "plane_normal"))


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
        got = np.asarray(got, float)
        said = f"got {np.round(got, 4)}, expected {np.round(exp, 4)} (or its negative)"
        if not np.all(np.isfinite(got)):
            return said + ": nearly equal quaternions make sin(theta) ~ 0: fall back to a normalised lerp there"
        if not np.isclose(np.linalg.norm(got), 1.0, atol=1e-6):
            return said + f": |q| = {np.linalg.norm(got):.4f}, a unit quaternion expected (normalised?)"
        return said + ": the shorter way round (flip q1 when q0 . q1 < 0)? theta = arccos(|q0 . q1|)?"
    for k, s in zip(range(0, 6, 2), (0.25, 0.5, 0.9)):
        cases.append(((q[k], q[k + 1], s), slerp(q[k], q[k + 1], s), describe))
        cases.append(((q[k], -q[k + 1], s), slerp(q[k], q[k + 1], s), describe))
    near = q[1] + 1e-9 * rng.normal(size=4)
    near /= np.linalg.norm(near)
    for q0, q1, s in ((q[0], q[0].copy(), 0.3), (q[1], near, 0.7), (q[2], q[3], 0.0), (q[2], q[3], 1.0)):
        cases.append(((q0, q1, s), slerp(q0, q1, s), describe))  # equal, nearly equal, the two ends

    def flat(q0, q1, s):
        out = np.asarray(my_slerp(q0, q1, s), float)
        exp = slerp(np.array(q0, float), np.array(q1, float), s)
        return out if out @ exp >= 0 else -out  # the same rotation either sign
    return report("check_slerp", flat, cases, atol=1e-7, forbid=(slerp,), arg_names=("q0", "q1", "s"))
