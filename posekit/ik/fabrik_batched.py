"""Batched full-body FABRIK: many independent problems at once, for benchmarks and data generation.

Introduced in ``notebooks/01_fabrik.ipynb``. Same algorithm and numbers as
:class:`posekit.ik.fabrik.FabrikSolver` without joint constraints — forward reaching, near-extended
chains straightened (:func:`posekit.ik.single_chain.straighten_chain`), backward reaching — laid out joint x
xyz x batch ``(J, 3, B)`` so every step is one vectorised numpy operation over the problems still
unsolved; converged problems leave the working set after each iteration. The arithmetic follows the
compiled kernel (:mod:`posekit.ik.fabrik_kernel`) operation by operation, so both agree to rounding.
"""

from __future__ import annotations

import numpy as np

from ..kinematics import bone_lengths_of
from ..skeleton import Skeleton
from .api import base_index
from .effector_errors import position_errors
from .fabrik_tree import ZERO_BONE, collapse_zero_bones, effector_chains, reduced_effectors
from .fabrik_kernel import _S_MAX, EXTENDED_RATIO, MIN_AXIAL, SECANT_STEPS

__all__ = ["fabrik_batched"]


def _unit(u):
    """(u / |u|, |u|) over the batch, with (0, 1, 0) where |u| < 1e-12 (as the kernel)."""
    L = np.sqrt((u * u).sum(axis=0))
    bad = L < 1e-12
    if bad.any():
        u = np.where(bad, np.array([0.0, 1.0, 0.0])[:, None], u)
        L = np.where(bad, 1.0, L)
    return u / L, L


def _straighten(back, chain, q, bl, R, d, w, todo):
    """:func:`posekit.ik.fabrik_kernel._straighten` for the problems ``todo`` (indices): writes the
    straightened ones into ``back`` and returns a mask of them."""
    q = [x[:, todo] for x in q]
    bl = [x[todo] for x in bl]
    R, d, w = R[todo], d[todo], w[:, todo]
    n = len(q) - 1
    e = q[n] - q[0]
    S = np.sqrt((e * e).sum(axis=0))
    ok = S >= 1e-12  # no joint limits here, so bending further is allowed (may_bend)
    e = e / np.where(ok, S, 1.0)
    ax, lat = [], []
    for i in range(n):
        v = q[i + 1] - q[i]
        a = (v * e).sum(axis=0)
        ok &= a >= MIN_AXIAL * bl[i]
        ax.append(a)
        lat.append(v - a * e)

    def span2(sig):
        s = 0.0
        for i in range(n):
            v = ax[i] * e + sig * lat[i]
            s = s + (bl[i] / np.sqrt((v * v).sum(axis=0))) * v
        return (s * s).sum(axis=0)

    reach = d < R
    d2 = d * d
    g0 = R * R - d2
    g1 = S * S - d2
    ok &= ~(reach & (g0 - g1 < 1e-12 * R * R))
    s0 = np.zeros_like(d)
    s1 = np.ones_like(d)
    live = ok & reach
    for _ in range(SECANT_STEPS):
        upd = live & (g1 != g0) & (np.abs(g1) > 1e-13 * d2)
        if not upd.any():
            break
        s2 = np.minimum(np.maximum(s1 - g1 * (s1 - s0) / np.where(upd, g1 - g0, 1.0), 0.0), _S_MAX)
        s0 = np.where(upd, s1, s0)
        g0 = np.where(upd, g1, g0)
        s1 = np.where(upd, s2, s1)
        g1 = np.where(upd, span2(np.sqrt(s1)) - d2, g1)
    sig = np.where(reach, np.sqrt(s1), 0.0)
    offs = []
    s = 0.0
    for i in range(n):
        v = ax[i] * e + sig * lat[i]
        s = s + (bl[i] / np.sqrt((v * v).sum(axis=0))) * v
        offs.append(s)
    a = s / np.sqrt((s * s).sum(axis=0))
    b = w / d
    k = np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])
    c = (a * b).sum(axis=0)
    ok &= ~(c < -1.0 + 1e-9)
    f = 1.0 / np.where(ok, 1.0 + c, 1.0)
    for i in range(n):
        x = offs[i]
        kd = (k * x).sum(axis=0) * f
        kxx = np.stack([k[1] * x[2] - k[2] * x[1], k[2] * x[0] - k[0] * x[2], k[0] * x[1] - k[1] * x[0]])
        new = q[0] + (c * x + kxx + k * kd)
        cols = todo[ok]
        back[chain[i + 1]][:, cols] = new[:, ok]
    out = np.zeros(back.shape[2], dtype=bool)
    out[todo[ok]] = True
    return out


def _extended_chain(back, lengths, chain, t, ratio):
    """:func:`posekit.ik.fabrik_kernel._extended_chain` over the batch: ``t`` (3, B) targets."""
    q = [back[chain[0]].copy()]
    bl = []
    R = 0.0
    for j in chain[1:]:
        u, _ = _unit(back[j] - q[-1])
        q.append(q[-1] + lengths[j] * u)
        bl.append(lengths[j])
        R = R + lengths[j]
    done = np.zeros(back.shape[2], dtype=bool)
    for m in range(len(chain) - 2):
        w = t - q[m]
        d = np.sqrt((w * w).sum(axis=0))
        cand = np.nonzero(~done & (d >= ratio * R) & (d > 1e-12))[0]
        if len(cand):
            done |= _straighten(back, chain[m:], q[m:], bl[m:], R, d, w, cand)
        R = R - bl[m]


def fabrik_batched(skeleton: Skeleton, start_pos, eff_joints, targets, tolerance=1e-3,
                   max_iter: int = 20, base: str | None = None):
    """Solve B full-body FABRIK problems with one effector set.

    :meth:`posekit.ik.FabrikSolver.solve_batch` calls this; it agrees with
    :meth:`~posekit.ik.FabrikSolver.solve` (no constraints) to rounding, iterations included.

    Parameters
    ----------
    skeleton : Skeleton
    start_pos : ndarray, shape (B, J, 3), metres
        Start poses (their bone lengths are kept). A bone shorter than
        :data:`posekit.ik.fabrik_tree.ZERO_BONE` is a rigid attachment
        (:func:`posekit.ik.fabrik_tree.collapse_zero_bones`); it must be so in every start pose.
    eff_joints : sequence of str or int, length K
        Effector joints (names, roles or indices), the same for every problem.
    targets : ndarray, shape (B, K, 3), metres
    tolerance : float or ndarray broadcastable to (B, K), metres
    max_iter : int
    base : str, optional
        Fixed joint (default the pelvis role); its ancestors are fixed too.

    Returns
    -------
    positions : ndarray, shape (B, J, 3)
    converged : ndarray of bool, shape (B,)
    iterations : ndarray of int, shape (B,)
    """
    start_pos = np.asarray(start_pos, dtype=float)
    targets = np.asarray(targets, dtype=float)
    J = skeleton.n_joints
    eff = skeleton.indices(eff_joints)
    K = len(eff)
    B = start_pos.shape[0] if start_pos.ndim == 3 else -1
    if start_pos.shape != (B, J, 3):
        raise ValueError(f"start_pos: expected shape (B, {J}, 3), got {start_pos.shape}")
    if targets.shape != (B, K, 3):
        raise ValueError(f"targets: expected shape ({B}, {K}, 3), got {targets.shape}")
    if not (np.all(np.isfinite(start_pos)) and np.all(np.isfinite(targets))):
        raise ValueError("start_pos and targets must be finite")
    try:
        tol = np.broadcast_to(np.asarray(tolerance, dtype=float), (B, K))
    except ValueError:
        raise ValueError(f"tolerance: expected a number or an array broadcastable to ({B}, {K}), "
                         f"got shape {np.shape(tolerance)}") from None
    if not (np.all(np.isfinite(tol)) and np.all(tol > 0)):
        raise ValueError("tolerance must be positive (metres)")
    b = base_index(skeleton, base)
    fixed = np.zeros(J, bool)
    fixed[skeleton.chain(b, 0)] = True
    lengths = bone_lengths_of(skeleton, start_pos)  # (B, J)
    zero_each = ~fixed & (lengths < ZERO_BONE)
    zero = zero_each.any(axis=0)
    if (zero_each != zero).any():
        j = int(np.nonzero((zero_each != zero).any(axis=0))[0][0])
        raise ValueError(f"joint {skeleton.names[j]} has a zero-length bone in some start poses only; "
                         "solve those apart")
    if zero.any():
        keep, rep, parents = collapse_zero_bones(skeleton.parents, zero)
    else:
        keep, rep, parents = np.arange(J), np.arange(J), skeleton.parents
    eff_r = reduced_effectors(skeleton, rep, eff)
    pos, conv, it = _solve(parents, fixed[keep], eff_r, start_pos[:, keep], targets, lengths[:, keep], tol, max_iter)
    return pos[:, rep], conv, it


def _solve(parents, fixed, eff, start_pos, targets, lengths, tol, max_iter):
    """The batched passes on a tree without zero-length bones: ``start_pos`` (B, J, 3), ``lengths``
    (B, J), ``targets`` (B, K, 3), ``tol`` (B, K)."""
    J = len(parents)
    K = len(eff)
    active = np.zeros(J, bool)
    for e in eff:
        j = int(e)
        while j >= 0 and not active[j]:
            active[j] = True
            j = int(parents[j])
    slot = np.full(J, -1)
    slot[eff] = np.arange(K)
    children = [np.nonzero((parents == j) & active)[0] for j in range(J)]
    chains = effector_chains(parents, eff, fixed)

    # (J, 3, B) layout: one contiguous vector over problems per joint coordinate
    pos = start_pos.transpose(1, 2, 0).copy()  # a copy always (a view when B == 1 would be written to)
    tgt = np.ascontiguousarray(targets.transpose(1, 2, 0))  # (K, 3, B)
    lengths = np.ascontiguousarray(lengths.T)  # (J, B)
    tol = np.ascontiguousarray(tol.T)  # (K, B)

    out_pos = np.empty_like(pos)
    out_it = np.zeros(pos.shape[2], int)
    out_conv = np.zeros(pos.shape[2], bool)
    work = np.arange(pos.shape[2])
    it = 0
    while True:
        err = position_errors(pos[eff], tgt, axis=1)  # (K, b): the shared position error
        done = (err <= tol).all(axis=0)
        if done.any() or it >= max_iter:
            leaving = done if it < max_iter else np.ones_like(done)
            out_pos[:, :, work[leaving]] = pos[:, :, leaving]
            out_it[work[leaving]] = it
            out_conv[work[leaving]] = done[leaving]
            keep = ~leaving
            if not keep.any():
                break
            pos, tgt, lengths, tol, work = pos[:, :, keep], tgt[:, :, keep], lengths[:, keep], tol[:, keep], work[keep]
        # forward reaching: effectors on their targets, sub-bases at the centroid of their proposals
        back = pos.copy()
        for j in range(J - 1, -1, -1):
            if fixed[j] or not active[j]:
                continue
            if slot[j] >= 0:
                back[j] = tgt[slot[j]]
                continue
            acc = 0.0
            for c in children[j]:
                u = pos[j] - back[c]
                L = np.sqrt((u * u).sum(axis=0))
                degenerate = L < 1e-12
                if degenerate.any():
                    alt = pos[j] - pos[c]
                    u = np.where(degenerate, alt, u)
                    L = np.where(degenerate, np.sqrt((alt * alt).sum(axis=0)), L)
                acc = acc + (back[c] + u * (lengths[c] / L))
            back[j] = acc / len(children[j])
        # near-extended chains, straightened at their targets
        with np.errstate(divide="ignore", invalid="ignore"):
            for ch in chains:
                _extended_chain(back, lengths, ch, tgt[slot[ch[-1]]], EXTENDED_RATIO)
        # forward
        for j in range(J):
            if fixed[j]:
                continue
            p = parents[j]
            u, _ = _unit((back[j] if active[j] else pos[j]) - pos[p])
            pos[j] = pos[p] + lengths[j] * u
        it += 1
    return out_pos.transpose(2, 0, 1).copy(), out_conv, out_it
