"""FABRIK on one chain (Aristidou & Lasenby 2011, Algorithm 1), readable numpy, and the near-extended
step that posekit adds.

Introduced in ``notebooks/01_fabrik.ipynb`` (section 2), where the chain is derived step by step and
the step's effect is measured. Units and axes: :mod:`posekit.conventions` (metres).

* :func:`fabrik_chain` — forward reaching (stage 1 of Algorithm 1) puts the end on the target and walks
  to the base keeping bone lengths, backward reaching (stage 2) puts the base back and walks out again. An unreachable target
  stretches the chain straight at it.
* :func:`straighten_chain` — targets *near* full reach, FABRIK's slow regime, in one step (the
  paper's unreachable-target case generalised); the full-body solver
  (:class:`posekit.ik.FabrikSolver`) runs it between its passes.
"""

from __future__ import annotations

import numpy as np

from .fabrik_kernel import _S_MAX, EXTENDED_RATIO, MIN_AXIAL, SECANT_STEPS

__all__ = ["chain_lengths", "fabrik_chain", "straighten_chain"]


def chain_lengths(positions) -> np.ndarray:
    """Bone lengths of a chain of joint positions (n+1, 3) -> (n,)."""
    positions = np.asarray(positions, dtype=float)
    return np.linalg.norm(np.diff(positions, axis=0), axis=1)


def fabrik_chain(positions, target, tolerance: float = 1e-3, max_iter: int = 20, return_history: bool = False):
    """FABRIK on a single chain (Algorithm 1 of Aristidou & Lasenby 2011).

    Parameters
    ----------
    positions : ndarray, shape (n+1, 3), metres
        Joint positions from the base (index 0, stays fixed) to the end effector (index n).
    target : ndarray, shape (3,), metres
    tolerance : float, metres
        Stop when the end is this close to the target.
    max_iter : int
    return_history : bool
        Also return the positions after every iteration (for figures).

    Returns
    -------
    positions : ndarray, shape (n+1, 3)
    converged : bool
        False for an unreachable target (the chain is then stretched straight towards it).
    iterations : int
    history : list of ndarray, only with ``return_history``
    """
    p = np.array(positions, dtype=float)
    t = np.asarray(target, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 2:
        raise ValueError(f"positions: expected shape (n+1, 3) with n >= 1, got {p.shape}")
    if t.shape != (3,) or not np.all(np.isfinite(t)) or not np.all(np.isfinite(p)):
        raise ValueError("target must be 3 finite numbers and positions finite")
    d = chain_lengths(p)
    if np.any(d < 1e-9):
        raise ValueError(f"zero-length bone in the chain (bone {int(np.argmin(d))})")
    history = [p.copy()]
    base = p[0].copy()
    if np.linalg.norm(t - base) > d.sum():  # unreachable: stretch towards the target
        for i in range(len(d)):
            u = (t - p[i]) / np.linalg.norm(t - p[i])
            p[i + 1] = p[i] + d[i] * u
        history.append(p.copy())
        out = (p, False, 1)
        return out + (history,) if return_history else out
    it = 0
    while np.linalg.norm(p[-1] - t) > tolerance and it < max_iter:
        p[-1] = t  # forward reaching: end on the target, walk to the base
        for i in range(len(d) - 1, -1, -1):
            u = p[i] - p[i + 1]
            p[i] = p[i + 1] + d[i] * u / np.linalg.norm(u)
        p[0] = base  # backward reaching: base back in place, walk to the end
        for i in range(len(d)):
            u = p[i + 1] - p[i]
            p[i + 1] = p[i] + d[i] * u / np.linalg.norm(u)
        it += 1
        history.append(p.copy())
    out = (p, bool(np.linalg.norm(p[-1] - t) <= tolerance), it)
    return out + (history,) if return_history else out


# ------------------------------------------------------------------------------ near-extended chains
def straighten_chain(positions, target, ratio: float = EXTENDED_RATIO, may_bend: bool = True):
    """The near-extended chain step of :class:`FabrikSolver`, readable numpy (the kernel
    :func:`posekit.ik.fabrik_kernel._extended_chain` does the same with scalars).

    Generalises the first branch of Algorithm 1 of Aristidou & Lasenby 2011 — a target out of
    reach gets the chain straight at it, no iterations — to targets *close to* full reach, where the
    FABRIK passes are slowest (their contraction per iteration tends to 1 as the chain straightens;
    ``notebooks/01_fabrik.ipynb`` section 2 measures it):

    1. find the longest end part ``positions[m:]`` (two bones or more) whose target lies at
       ``d >= ratio * R`` of its reach ``R``;
    2. split each of its bones into the part along the axis ``e`` from ``positions[m]`` to the end
       and the part across it, and scale every sideways part by one factor ``sigma``:
       ``sigma = 0`` is the straight chain (the paper's unreachable case, taken when ``d >= R``),
       ``sigma = 1`` the chain as it is; the squared span is close to linear in ``sigma^2``, so a
       few secant steps from those two points find the ``sigma`` whose span is ``d``;
    3. turn the part rigidly about ``positions[m]`` so its end is on the target.

    Bone lengths are exact and the chain keeps its shape (where it bends, and which way) but for the
    amount. A part with a bone more than 60 deg off its axis is left to the FABRIK passes.

    Parameters
    ----------
    positions : ndarray, shape (n+1, 3), metres
        The chain, base first (the solver passes it as the forward pass would place it).
    target : ndarray, shape (3,)
    ratio : float
    may_bend : bool
        False: only straighten (``sigma <= 1``), never bend further — the solver's choice for chains
        with joint limits, where a larger bend could cross a hinge limit.

    Returns
    -------
    (m, positions) : int and ndarray, shape (n+1, 3)
        The new chain; only ``positions[m + 1:]`` moved. None when no end part qualifies.
    """
    q = np.array(positions, dtype=float)
    t = np.asarray(target, dtype=float)
    bones = np.diff(q, axis=0)
    bl = np.linalg.norm(bones, axis=1)
    for m in range(len(bl) - 1):
        R, d = bl[m:].sum(), np.linalg.norm(t - q[m])
        if d < ratio * R or d <= 1e-12:
            continue
        part = _straighten_part(q[m], bones[m:], bl[m:], R, t, may_bend)
        if part is not None:
            q[m + 1:] = part
            return m, q
    return None


def _straighten_part(base, bones, bl, R, t, may_bend):
    S = np.linalg.norm(bones.sum(axis=0))
    d = np.linalg.norm(t - base)
    if S < 1e-12 or (d < S and not may_bend):
        return None
    e = bones.sum(axis=0) / S
    along = bones @ e
    if np.any(along < MIN_AXIAL * bl):
        return None
    across = bones - along[:, None] * e

    def chain(sig):
        v = along[:, None] * e + sig * across
        return np.cumsum(bl[:, None] * v / np.linalg.norm(v, axis=1, keepdims=True), axis=0)

    sig = 0.0
    if d < R:
        g = lambda s: np.sum(chain(np.sqrt(s))[-1] ** 2) - d * d  # noqa: E731
        (s0, g0), (s1, g1) = (0.0, R * R - d * d), (1.0, S * S - d * d)
        if g0 - g1 < 1e-12 * R * R:
            return None  # straight already: no sideways part to scale
        for _ in range(SECANT_STEPS):
            if g1 != g0 and abs(g1) > 1e-13 * d * d:
                s0, g0, s1 = s1, g1, min(max(s1 - g1 * (s1 - s0) / (g1 - g0), 0.0), _S_MAX)
                g1 = g(s1)
        sig = np.sqrt(s1)
    offsets = chain(sig)
    a, b = offsets[-1] / np.linalg.norm(offsets[-1]), (t - base) / d
    k, c = np.cross(a, b), a @ b
    if c < -1.0 + 1e-9:
        return None
    # rotation a -> b without trigonometry: x -> c x + k x x + k (k . x) / (1 + c)
    return base + c * offsets + np.cross(k, offsets) + np.outer(offsets @ k, k) / (1.0 + c)
