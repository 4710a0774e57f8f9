"""Checkers for ``notebooks/01_fabrik.ipynb``."""

from __future__ import annotations

import numpy as np

from ..ik.single_chain import fabrik_chain
from ..ik.two_bone import two_bone_ik
from ._check import report


def _chains(seed=0):
    rng = np.random.default_rng(seed)
    out = []
    for n in (2, 3, 5):
        p = np.cumsum(np.vstack([[0, 0, 0], rng.normal(size=(n, 3)) * 0.2 + [0, 0.2, 0]]), axis=0)
        reach = np.linalg.norm(np.diff(p, axis=0), axis=1).sum()
        d = rng.normal(size=3)
        out.append((p, p[0] + d / np.linalg.norm(d) * reach * rng.uniform(0.3, 0.9)))
    out.append((out[0][0], out[0][0][0] + np.array([5.0, 0, 0])))  # unreachable
    return out


def check_fabrik_chain(my_fabrik_chain) -> bool:
    """Check ``my_fabrik_chain(positions (n+1, 3), target (3,), tolerance, max_iter) -> positions``
    (Algorithm 1 of Aristidou & Lasenby 2011) against posekit's on reachable and unreachable targets."""
    def describe(got, expected):
        j = int(np.argmax(np.linalg.norm(got - expected, axis=1)))
        return f"joint {j} is {np.linalg.norm(got[j] - expected[j]) * 100:.2f} cm off (base fixed? lengths kept?)"
    cases = [((p.copy(), t.copy(), 1e-3, 20), fabrik_chain(p, t, 1e-3, 20)[0], describe) for p, t in _chains()]
    return report("check_fabrik_chain", my_fabrik_chain, cases, atol=1e-6)


def check_two_bone(my_two_bone) -> bool:
    """Check ``my_two_bone(root, mid, end, target, pole) -> (new_mid, new_end)`` (law of cosines)."""
    rng = np.random.default_rng(2)
    cases = []

    def describe(got, expected):
        return f"max coordinate error {np.abs(got - expected).max() * 100:.2f} cm (mid joint bent towards the pole?)"
    for _ in range(4):
        root = rng.normal(size=3)
        mid = root + rng.normal(size=3) * 0.3
        end = mid + rng.normal(size=3) * 0.3
        target = root + rng.normal(size=3) * 0.25
        pole = root + rng.normal(size=3)
        m, e, _ = two_bone_ik(root, mid, end, target, pole)
        cases.append(((root, mid, end, target, pole), np.stack([m, e]), describe))

    def wrapped(*args):
        m, e = my_two_bone(*args)[:2]
        return np.stack([np.asarray(m, float), np.asarray(e, float)])
    return report("check_two_bone", wrapped, cases, atol=1e-6)


__all__ = ["check_fabrik_chain", "check_two_bone"]
