"""Batched full-body FABRIK: many independent problems at once, for benchmarks and data generation.

Introduced in ``notebooks/01_fabrik.ipynb``. Same algorithm and numbers as
:class:`posekit.ik.fabrik.FabrikSolver` without joint constraints, laid out joint x xyz x batch
``(J, 3, B)`` so every step is one vectorised numpy operation over the problems still unsolved;
converged problems leave the working set after each iteration.
"""

from __future__ import annotations

import numpy as np

from ..skeleton import Skeleton
from .api import base_index

__all__ = ["fabrik_batched"]


def fabrik_batched(skeleton: Skeleton, start_pos, eff_joints, targets, tolerance: float = 1e-3,
                   max_iter: int = 20, base: str | None = None):
    """Solve B full-body FABRIK problems with one effector set.

    Parameters
    ----------
    skeleton : Skeleton
    start_pos : ndarray, shape (B, J, 3), metres
        Start poses (their bone lengths are kept).
    eff_joints : sequence of str or int, length K
        Effector joints (names, roles or indices), the same for every problem.
    targets : ndarray, shape (B, K, 3), metres
    tolerance : float, metres
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
    parents = skeleton.parents
    b = base_index(skeleton, base)
    fixed = np.zeros(J, bool)
    fixed[skeleton.chain(b, 0)] = True
    active = np.zeros(J, bool)
    for e in eff:
        j = int(e)
        while j >= 0 and not active[j]:
            active[j] = True
            j = int(parents[j])
    slot = np.full(J, -1)
    slot[eff] = np.arange(K)
    children = [np.nonzero((parents == j) & active)[0] for j in range(J)]

    # (J, 3, B) layout: one contiguous vector over problems per joint coordinate
    pos = np.ascontiguousarray(start_pos.transpose(1, 2, 0))
    tgt = np.ascontiguousarray(targets.transpose(1, 2, 0))  # (K, 3, B)
    lengths = np.linalg.norm(pos - pos[np.maximum(parents, 0)], axis=1)  # (J, B)
    lengths[0] = 0.0
    if np.any(lengths[~fixed] < 1e-9):
        raise ValueError("zero-length bone: FABRIK needs every bone > 0")
    # for each joint: its nearest effector below (by rest chain length) and, per problem, the chain
    # length from the joint's parent down to it (the proposal weights of FabrikSolver)
    sub_eff = np.zeros(J, int)
    best = np.full(J, np.inf)
    for k, e in enumerate(eff):
        for j in skeleton.chain(int(e), 0)[1:]:
            reach = lengths[skeleton.chain(int(e), j), 0].sum()
            if reach < best[j]:
                best[j], sub_eff[j] = reach, k
    sub_reach = np.full((J, pos.shape[2]), np.inf)
    for j in np.nonzero(np.isfinite(best))[0]:
        sub_reach[j] = lengths[skeleton.chain(int(eff[sub_eff[j]]), int(j))].sum(axis=0)
    tols = tolerance

    out_pos = np.empty_like(pos)
    out_it = np.zeros(pos.shape[2], int)
    out_conv = np.zeros(pos.shape[2], bool)
    work = np.arange(pos.shape[2])
    it = 0
    while True:
        err = np.sqrt(((pos[eff] - tgt) ** 2).sum(axis=1)).max(axis=0)  # (b,)
        done = err <= tols
        if done.any() or it >= max_iter:
            leaving = done if it < max_iter else np.ones_like(done)
            out_pos[:, :, work[leaving]] = pos[:, :, leaving]
            out_it[work[leaving]] = it
            out_conv[work[leaving]] = done[leaving]
            keep = ~leaving
            if not keep.any():
                break
            pos, tgt, lengths, sub_reach, work = (pos[:, :, keep], tgt[:, :, keep], lengths[:, keep],
                                                  sub_reach[:, keep], work[keep])
        # backward
        back = pos.copy()
        for j in range(J - 1, -1, -1):
            if fixed[j] or not active[j]:
                continue
            if slot[j] >= 0:
                back[j] = tgt[slot[j]]
                continue
            acc = 0.0
            wsum = 0.0
            for c in children[j]:
                u = pos[j] - back[c]
                L = np.sqrt((u * u).sum(axis=0))
                degenerate = L < 1e-12
                if degenerate.any():
                    alt = pos[j] - pos[c]
                    u = np.where(degenerate, alt, u)
                    L = np.where(degenerate, np.sqrt((alt * alt).sum(axis=0)), L)
                t = tgt[sub_eff[c]] - pos[j]
                slack = sub_reach[c] - np.sqrt((t * t).sum(axis=0))
                w = 1.0 / (np.maximum(slack, 0.0) + 0.01)
                acc = acc + w * (back[c] + u * (lengths[c] / L))
                wsum = wsum + w
            back[j] = acc / wsum
        # forward
        for j in range(J):
            if fixed[j]:
                continue
            p = parents[j]
            u = (back[j] if active[j] else pos[j]) - pos[p]
            L = np.sqrt((u * u).sum(axis=0))
            L = np.where(L < 1e-12, 1.0, L)
            pos[j] = pos[p] + u * (lengths[j] / L)
        it += 1
    return out_pos.transpose(2, 0, 1).copy(), out_conv, out_it
