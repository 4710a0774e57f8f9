"""Checkers for ``notebooks/01_fabrik.ipynb``.

The lesson builds FABRIK and two-bone IK in front of the student; its exercises ask for what it did *not* show:
FABRIK with the roles of base and end swapped (a planted foot, a reaching hip), and two-bone IK steered by a swivel
angle instead of a pole point. Each checker starts with a generic case, accepts every convention the exercise's
text allows, and refuses an answer that calls the posekit function it is compared against or changes its inputs.
"""

from __future__ import annotations

import numpy as np

from ..ik.single_chain import fabrik_chain
from ..ik.two_bone import two_bone_ik
from ._check import Either, report
from ._judge import judged


def _chain(rng, n):
    """A random chain of ``n`` bones, 0.1-0.4 m each, that winds upwards (generic: no three joints in line)."""
    return np.cumsum(np.vstack([[0, 0, 0], rng.normal(size=(n, 3)) * 0.2 + [0, 0.2, 0]]), axis=0)


def planted_cases(seed: int = 0):
    """The cases of :func:`check_fabrik_planted`: ``(positions, target, tolerance, max_iter)`` tuples.

    Generic reachable targets first (3, 4 and 6 bones), then one the chain must stretch towards, then budgets a
    careless answer ignores: one iteration only, and a loose tolerance that stops early; a target out of reach with
    one iteration (an answer without the out-of-reach branch gets there only with many iterations); a reaching joint
    already within tolerance (an answer that tests the tolerance after a pass moves it).
    """
    rng = np.random.default_rng(seed)
    out = []
    for n in (3, 4, 6):
        p = _chain(rng, n)
        reach = np.linalg.norm(np.diff(p, axis=0), axis=1).sum()
        d = rng.normal(size=3)
        out.append((p, p[-1] + d / np.linalg.norm(d) * reach * rng.uniform(0.4, 0.8), 1e-4, 50))
    p = _chain(rng, 4)
    out.append((p, p[-1] + np.array([3.0, 0.5, 0.0]), 1e-4, 50))  # out of reach: stretched towards it
    p = _chain(rng, 5)
    reach = np.linalg.norm(np.diff(p, axis=0), axis=1).sum()
    far = p[-1] + np.array([0.0, 0.0, 0.93 * reach])  # near full reach: many iterations needed
    out.append((p, far, 1e-5, 1))  # only one iteration allowed
    out.append((p, far, 5e-2, 50))  # stops as soon as the hip is within 5 cm
    p = _chain(rng, 3)
    out.append((p, p[-1] + np.array([0.0, 4.0, 1.0]), 1e-4, 1))  # out of reach with one iteration: stretched at once
    p = _chain(rng, 4)
    out.append((p, p[0] + np.array([0.003, -0.004, 0.0]), 1e-2, 50))  # already within tolerance: nothing moves
    return out


def planted_reference(positions, target, tolerance, max_iter):
    """What :func:`check_fabrik_planted` expects: FABRIK with the chain read from the end (the planted joint is
    the base of the reversed chain)."""
    return fabrik_chain(np.asarray(positions)[::-1], target, tolerance, max_iter)[0][::-1]


@judged
def check_fabrik_planted(my_fabrik_planted) -> bool:
    """Check ``my_fabrik_planted(positions (n+1, 3), target (3,), tolerance, max_iter) -> positions (n+1, 3)``:
    the LAST joint stays planted, the FIRST joint reaches for ``target`` (Algorithm 1 of Aristidou & Lasenby 2011
    with the roles of base and end swapped), iterations stopping at ``tolerance`` or after ``max_iter``."""
    def describe(got, expected):
        j = int(np.argmax(np.linalg.norm(got - expected, axis=1)))
        hints = []
        if not np.allclose(got[-1], expected[-1]):
            hints.append("the last joint must stay planted")
        if j == 0:
            hints.append("the first joint reaches for the target")
        bones = np.diff(expected, axis=0)
        bones = bones / np.linalg.norm(bones, axis=1, keepdims=True)
        if np.allclose(bones, bones[0], atol=1e-9):
            hints.append("the target is out of reach: the chain stretched straight towards it, at once")
        elif np.allclose(expected, positions_of.get(id(expected), expected * np.nan)):
            hints.append("already within tolerance: nothing moves")
        hints.append("max_iter and tolerance kept? bone lengths kept?")
        return f"joint {j} is {np.linalg.norm(got[j] - expected[j]) * 1000:.3f} mm off ({'; '.join(hints)})"
    cases = [((p.copy(), t.copy(), tol, it), planted_reference(p, t, tol, it), describe)
             for p, t, tol, it in planted_cases()]
    positions_of = {id(expected): args[0] for args, expected, _ in cases}  # a case's start, by its expected answer
    return report("check_fabrik_planted", my_fabrik_planted, cases, atol=1e-6, forbid=(fabrik_chain,),
                  arg_names=("positions", "target", "tolerance", "max_iter"))


def swivel_pole(root, mid, target, swivel):
    """The pole point that puts the middle joint at ``swivel`` radians around the root-target axis.

    The angle is measured from the current bend (the part of ``mid - root`` across the axis ``u``), positive
    turning right-handed about ``u`` (from the bend towards ``u x bend``).
    """
    u = (target - root) / np.linalg.norm(target - root)
    v0 = (mid - root) - ((mid - root) @ u) * u
    v0 = v0 / np.linalg.norm(v0)
    return root + np.cos(swivel) * v0 + np.sin(swivel) * np.cross(u, v0)


def swivel_cases(seed: int = 2):
    """The cases of :func:`check_two_bone_swivel`: ``(root, mid, end, target, swivel)`` tuples, generic first."""
    rng = np.random.default_rng(seed)
    out = []
    for swivel in (0.7, -1.2, 2.5, 0.0):
        root = rng.normal(size=3)
        mid = root + rng.normal(size=3) * 0.3
        end = mid + rng.normal(size=3) * 0.3
        l1, l2 = np.linalg.norm(mid - root), np.linalg.norm(end - mid)
        d = rng.normal(size=3)
        target = root + d / np.linalg.norm(d) * rng.uniform(abs(l1 - l2) + 0.02, l1 + l2 - 0.02)
        out.append((root, mid, end, target, swivel))
    root, mid = np.zeros(3), np.array([0.0, -0.3, 0.05])
    end = mid + np.array([0.0, -0.28, -0.04])
    out.append((root, mid, end, np.array([0.2, -1.0, 0.3]), 0.4))  # out of reach: the arm points at the target
    out.append((root, mid, end, np.array([0.0, -0.01, 0.005]), -0.4))  # closer than |l1 - l2|: folded
    return out


def swivel_answers(root, mid, end, target, swivel):
    """Every answer :func:`check_two_bone_swivel` accepts, stacked ``(2, 3)``: the distance clamped to
    ``[|l1 - l2|, l1 + l2]`` exactly, or with section 1's 1e-6 m margin inside it."""
    pole = swivel_pole(root, mid, target, swivel)
    return Either(*(np.stack(two_bone_ik(root, mid, end, target, pole, eps=eps)[:2]) for eps in (1e-6, 0.0)))


@judged
def check_two_bone_swivel(my_two_bone_swivel) -> bool:
    """Check ``my_two_bone_swivel(root, mid, end, target, swivel) -> (new_mid, new_end)``: two-bone IK by the law
    of cosines with the middle joint on its circle at ``swivel`` radians around the root-target axis, measured
    from the current bend, positive right-handed about the axis."""
    def describe(got, expected):
        err = np.abs(got - expected).max() * 100
        if np.allclose(got[1], expected[1], atol=1e-6):
            return (f"the end joint is right but the middle one is {err * 10:.3f} mm off (angle measured from the "
                    "current "
                    "bend? right-handed about root → target? law of cosines at the root?)")
        return f"the end joint is {np.abs(got[1] - expected[1]).max() * 1000:.3f} mm off (distance clamped?)"
    cases = [((root, mid, end, target, s), swivel_answers(root, mid, end, target, s), describe)
             for root, mid, end, target, s in swivel_cases()]

    def stacked(*args):
        m, e = my_two_bone_swivel(*args)[:2]
        return np.stack([np.asarray(m, float), np.asarray(e, float)])
    return report("check_two_bone_swivel", stacked, cases, atol=1e-6, forbid=(two_bone_ik,),
                  arg_names=("root", "mid", "end", "target", "swivel"))


__all__ = ["check_fabrik_planted", "check_two_bone_swivel"]
