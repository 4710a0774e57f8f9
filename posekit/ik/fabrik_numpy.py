"""Full-body FABRIK written plainly in numpy: the readable twin of the solver's numba kernel.

Introduced in ``notebooks/01_fabrik.ipynb`` (section 3); ``posekit bench ik`` times it as the
baseline. Units: :mod:`posekit.conventions` (metres).
"""

from __future__ import annotations

import numpy as np

from ..kinematics import bone_lengths_of
from .api import base_index
from .fabrik_tree import effector_chains
from .single_chain import straighten_chain

__all__ = ["fabrik_numpy"]


def fabrik_numpy(skeleton, start, eff, targets, tol=1e-3, max_iter=20):
    """The full-body FABRIK of :class:`~posekit.ik.FabrikSolver`, readable: backward pass with plain
    centroids at the sub-bases (Aristidou & Lasenby 2011, Sec. 4.2), near-extended chains
    straightened (:func:`~posekit.ik.single_chain.straighten_chain`), forward pass — numpy vector
    ops per joint and no compilation, as a newcomer would write it after the lesson. The solver's
    numba kernel (:mod:`posekit.ik.fabrik_kernel`) computes the same positions; ``posekit bench ik``
    times this version as its baseline (no joint limits, no zero-length bones).

    Parameters
    ----------
    skeleton : Skeleton
    start : ndarray, shape (J, 3), metres
    eff : ndarray of int, shape (K,)
        Effector joints.
    targets : ndarray, shape (K, 3), metres

    Returns
    -------
    ndarray, shape (J, 3)
    """
    parents = skeleton.parents
    pos = np.array(start, dtype=float)
    L = bone_lengths_of(skeleton, pos)
    fixed = np.zeros(len(parents), dtype=bool)
    fixed[skeleton.chain(base_index(skeleton), 0)] = True
    active = set()
    for e in eff:
        active.update(skeleton.chain(int(e), 0))
    chains = effector_chains(skeleton, eff, fixed)
    goal = {int(e): targets[k] for k, e in enumerate(eff)}
    it = 0
    while np.linalg.norm(pos[eff] - targets, axis=1).max() > tol and it < max_iter:
        back = pos.copy()
        for j in range(len(parents) - 1, -1, -1):
            if fixed[j] or j not in active:
                continue
            if j in goal:
                back[j] = goal[j]
                continue
            props = [back[c] + L[c] * (pos[j] - back[c]) / np.linalg.norm(pos[j] - back[c])
                     for c in np.nonzero(parents == j)[0] if c in active]
            back[j] = np.mean(props, axis=0)
        for ch in chains:  # each chain as the forward pass would place it, straightened if near-extended
            q = [back[ch[0]]]
            for j in ch[1:]:
                q.append(q[-1] + L[j] * (back[j] - q[-1]) / np.linalg.norm(back[j] - q[-1]))
            straightened = straighten_chain(np.array(q), goal[int(ch[-1])])
            if straightened is not None:
                m, new = straightened
                back[ch[m + 1:]] = new[m + 1:]
        for j in range(len(parents)):
            if fixed[j]:
                continue
            u = (back[j] if j in active else pos[j]) - pos[parents[j]]
            pos[j] = pos[parents[j]] + L[j] * u / np.linalg.norm(u)
        it += 1
    return pos
