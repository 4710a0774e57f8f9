"""Checkers for ``notebooks/06_posing_studio.ipynb``.

Section 3 builds the studio's drag — a ray from the camera meets a plane through the grabbed point — in front of
the student; exercise 1 asks for the drag it does not show: a joint dragged on the *sphere* of its bone around its
parent, so that the bone keeps its length (an FK drag), including the rays that miss the sphere. Section 5 states
slerp; exercise 2 asks for it, with nearly equal, equal and opposite quaternions. Each checker starts with a generic
case, accepts float32 answers, and refuses an answer that calls the function it is compared against or changes its
inputs.
"""

from __future__ import annotations

import numpy as np

from ._check import report
from ._judge import judged


# -- exercise 1: a drag on the bone's sphere --------------------------------------------------------------------------

def sphere_drag_reference(c, q, centre, radius):
    """What :func:`check_drag_on_sphere` expects: where the ray from ``c`` through ``q`` first meets the sphere of
    ``radius`` around ``centre`` in front of the camera (smallest ``t > 0`` of ``c + t (q - c)``); when it meets
    it nowhere in front (a ray beside the sphere, or the sphere behind the camera), the sphere's point nearest the
    ray: ``centre + radius * (x - centre) / |x - centre|``, ``x`` the ray's point nearest the centre (``t >= 0``).
    The two rules agree where the ray touches the sphere, so the dragged joint never jumps."""
    c, q, centre = (np.asarray(a, dtype=float) for a in (c, q, centre))
    d = q - c
    dd = d @ d
    tc = ((centre - c) @ d) / dd  # the line's point nearest the centre
    h2 = radius ** 2 - np.sum((c + tc * d - centre) ** 2)
    if h2 >= 0:
        dt = np.sqrt(h2 / dd)
        for t in (tc - dt, tc + dt):
            if t > 0:
                return c + t * d
    x = c + max(tc, 0.0) * d
    v = x - centre
    return centre + radius * v / np.linalg.norm(v)


def sphere_cases(seed: int = 16):
    """The cases of :func:`check_drag_on_sphere`: ``(c, q, centre, radius, what)`` tuples, generic first."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(2):  # generic: the camera 2-4 m away, the ray through the sphere (q short of it, then beyond it)
        centre, r = rng.normal(size=3) * 0.5, rng.uniform(0.25, 0.45)
        c = centre + rng.normal(size=3) / np.sqrt(3) * 3
        aim = centre + rng.normal(size=3) * r * 0.3
        out.append((c, c + (aim - c) * (0.3 if k == 0 else 1.7), centre, r, "hit"))
    centre, r = np.array([0.1, 1.2, 0.0]), 0.4
    out.append((centre + [0.1, -0.05, 0.1], centre + [0.3, 0.2, -0.2], centre, r, "inside"))  # the camera inside
    c = np.array([0.0, 1.5, 3.0])
    out.append((c, c + [0.18, 0.02, -1.0], centre, r, "miss"))  # the ray passes beside the sphere
    out.append((c, c + [0.1, 0.0, 1.0], centre, r, "behind"))  # the sphere behind the camera
    out.append((c, c + [0.0, -0.2, 1.0], np.array([0.0, 1.5, 2.0]), 0.5, "behind"))  # the line meets it, behind
    out.append((np.array([1.0, 0.0, 5.0]), np.array([1.0, 0.0, 4.0]), np.zeros(3), 1.0, "tangent"))  # touches it
    out.append((c, c + (centre - c) * 0.5, centre, r, "hit"))  # straight at the centre
    out.append((c, c + [0.05, -0.1, -0.8], centre, 0.15, "radius"))  # another radius (the bone's length is an argument)
    c32 = (c + [0.2, 0.0, 0.0]).astype(np.float32)  # float32 inputs
    out.append((c32, (c32 + np.array([-0.05, -0.1, -1.0], np.float32)).astype(np.float32),
                centre.astype(np.float32), np.float32(0.35), "hit"))
    return out


@judged
def check_drag_on_sphere(my_drag_on_sphere) -> bool:
    """Check ``my_drag_on_sphere(c (3,), q (3,), centre (3,), radius) -> (3,)``: the dragged joint on the sphere of
    its bone around its parent (:func:`sphere_drag_reference`)."""
    hints = {
        "hit": "the ray meets the sphere twice: the nearer point in front of the camera (smallest t > 0)? t counts "
               "in units of d = q - c, which is not of unit length",
        "inside": "the camera is inside the sphere: the one point in front of it is where the ray leaves (t > 0)",
        "miss": "the ray misses the sphere: the sphere's point nearest the ray, centre + radius (x - centre) / "
                "|x - centre|, x the ray's point nearest the centre",
        "behind": "the sphere is behind the camera: the ray's point nearest the centre is the camera itself "
                  "(t >= 0: a ray starts at the camera), so the sphere's point nearest the camera",
        "tangent": "the ray touches the sphere: one point, where both rules agree",
        "radius": "the radius is an argument: the bone's length",
    }

    def describe_for(centre, r, what):
        def describe(got, exp):
            if got is None:
                return "got None: there is always an answer — " + hints[what]
            off = float(np.linalg.norm(got - centre))
            if not np.isfinite(got).all():
                return f"got {got}: not finite — " + hints[what]
            if abs(off - r) > 1e-6 * max(1.0, r):
                return (f"got {np.round(got, 4)}, {off:.4f} m from the centre, not on the sphere of radius {r:g} "
                        "(the bone must keep its length); " + hints[what])
            return f"got {np.round(got, 4)}, expected {np.round(exp, 4)}: " + hints[what]
        return describe

    cases = [((c, q, centre, r), sphere_drag_reference(c, q, centre, r), describe_for(centre, float(r), what))
             for c, q, centre, r, what in sphere_cases()]
    return report("check_drag_on_sphere", my_drag_on_sphere, cases, atol=1e-9, forbid=(sphere_drag_reference,),
                  arg_names=("c", "q", "centre", "radius"))


# -- exercise 2: slerp ------------------------------------------------------------------------------------------------

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

    def describe_for(what, q0, q1):
        def describe(got, exp):
            got = np.asarray(got, float)
            said = f"got {np.round(got, 4)}, expected {np.round(exp, 4)} (or its negative)"
            if not np.all(np.isfinite(got)):
                return said + (f": {what} make sin(theta) ~ 0 — fall back to a normalised lerp there")
            if not np.isclose(np.linalg.norm(got), 1.0, atol=1e-5):
                return said + f": |q| = {np.linalg.norm(got):.4f}, a unit quaternion expected (normalised?)"
            if what == "a small angle":
                return said + ": the angle is small but sin(theta) is not tiny — the lerp fallback taken too early?"
            if np.dot(q0, q1) < 0:
                return said + ": q0 . q1 < 0 — the shorter way round takes -q1 (the same rotation)"
            return said + ": (sin((1 - s) theta) q0 + sin(s theta) q1) / sin(theta), theta = arccos(|q0 . q1|)?"
        return describe

    for k, s in zip(range(0, 6, 2), (0.25, 0.5, 0.9)):
        for q1 in (q[k + 1], -q[k + 1]):  # as drawn, then of the other sign: one of them has q0 . q1 < 0
            cases.append(((q[k], q1, s), slerp(q[k], q1, s), describe_for("generic", q[k], q1)))
    near = q[1] + 1e-9 * rng.normal(size=4)
    near /= np.linalg.norm(near)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    turn = np.append(axis * np.sin(0.05), np.cos(0.05))  # 0.1 rad about axis: q0 . q1 = cos(0.05), not tiny
    x0, w0, x1, w1 = q[4][:3], q[4][3], turn[:3], turn[3]
    small = np.append(w1 * x0 + w0 * x1 + np.cross(x1, x0), w1 * w0 - x1 @ x0)  # turn composed with q[4]
    for q0, q1, s, what in ((q[0], q[0].copy(), 0.3, "equal quaternions"),
                            (q[1], near, 0.7, "nearly equal quaternions"),
                            (q[2], -q[2], 0.4, "opposite quaternions (q1 = -q0, one rotation)"),
                            (q[3], -(q[3] + 1e-9 * rng.normal(size=4)), 0.6, "nearly opposite quaternions"),
                            (q[4], small, 0.3, "a small angle"),
                            (q[2], q[3], 0.0, "the first end"), (q[2], q[3], 1.0, "the last end")):
        q1 = q1 / np.linalg.norm(q1)
        cases.append(((q0, q1, s), slerp(q0, q1, s), describe_for(what, q0, q1)))
    q32 = q[:2].astype(np.float32)  # float32 quaternions
    cases.append(((q32[0], q32[1], 0.35), slerp(q32[0].astype(float), q32[1].astype(float), 0.35),
                  describe_for("generic", q32[0], q32[1])))

    def flat(q0, q1, s):
        raw = my_slerp(q0, q1, s)
        single = getattr(raw, "dtype", None) == np.float32
        out = np.asarray(raw, float)
        if out.shape != (4,):
            return out
        exp = slerp(np.array(q0, float), np.array(q1, float), s)
        out = out if not out @ exp < 0 else -out  # the same rotation either sign
        return out.astype(np.float32) if single else out
    return report("check_slerp", flat, cases, atol=1e-7, forbid=(slerp,), arg_names=("q0", "q1", "s"))


__all__ = ["check_drag_on_sphere", "check_slerp"]
