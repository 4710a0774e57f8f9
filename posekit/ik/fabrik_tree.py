"""The skeleton as full-body FABRIK sees it: effector chains, and zero-length bones collapsed.

Introduced in ``notebooks/01_fabrik.ipynb``. Shared by the solver (:mod:`posekit.ik.fabrik`, whose
compiled loop is :mod:`posekit.ik.fabrik_kernel`) and its batched path (:mod:`posekit.ik.fabrik_batched`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["ZERO_BONE", "effector_chains", "collapse_zero_bones", "reduced_effectors"]

ZERO_BONE = 1e-9
"""A bone shorter than this (metres) is a rigid attachment (:func:`collapse_zero_bones`)."""


def effector_chains(skeleton, eff_idx, fixed) -> list[np.ndarray]:
    """Every effector's chain for the near-extended step, base first: from the nearest joint above it
    that is fixed or itself an effector, down to the effector. Ordered by effector index, so a chain
    comes after the chains of the effectors above it (whose new positions it starts from).
    ``skeleton`` may also be a ``parents`` array (a tree without its zero-length bones)."""
    parents = np.asarray(getattr(skeleton, "parents", skeleton))
    effs = {int(e) for e in eff_idx}
    chains = []
    for e in sorted(effs):
        c, j = [e], e
        while not fixed[j] and (j == e or j not in effs):
            j = int(parents[j])
            c.append(j)
        if len(c) > 2:  # one bone is what the forward pass does anyway
            chains.append(np.array(c[::-1], dtype=np.int64))
    return chains


def collapse_zero_bones(parents, zero):
    """The tree without its zero-length bones, for FABRIK.

    A joint whose bone has zero length (CMU's ``LHipJoint``) has no direction, so FABRIK cannot place
    it by one; it is rigidly attached instead: it sits on its parent, and its children hang from the
    parent. This drops such joints and re-parents their children onto the nearest kept ancestor.

    Parameters
    ----------
    parents : ndarray of int, shape (J,)
    zero : ndarray of bool, shape (J,)
        Joints whose bone has zero length (never the root).

    Returns
    -------
    keep : ndarray of int, shape (J',)
        The kept joints, in order (parents still before children).
    rep : ndarray of int, shape (J,)
        For every joint the index (into ``keep``) of the kept joint it sits on: itself if kept, else its
        nearest kept ancestor. ``reduced_positions[rep]`` gives back all J joints.
    reduced_parents : ndarray of int, shape (J',)
    """
    parents = np.asarray(parents)
    zero = np.asarray(zero, dtype=bool)
    if zero[0]:
        raise ValueError("the root has no bone; it cannot be a zero-length bone")
    keep = np.nonzero(~zero)[0]
    new = np.full(len(parents), -1, dtype=np.int64)
    new[keep] = np.arange(len(keep))
    rep = np.empty(len(parents), dtype=np.int64)
    for j in range(len(parents)):
        rep[j] = new[j] if not zero[j] else rep[parents[j]]
    reduced = np.array([-1 if parents[k] < 0 else rep[parents[k]] for k in keep], dtype=np.int64)
    return keep, rep, reduced


def reduced_effectors(skeleton, rep, joints) -> np.ndarray:
    """Effector joints in the tree without zero-length bones (:func:`collapse_zero_bones`); two
    effectors that land on one point are refused."""
    eff = rep[np.asarray(joints)].astype(np.int64)
    if len(set(eff.tolist())) < len(eff):
        for a in range(len(eff)):
            for b in range(a):
                if eff[a] == eff[b]:
                    na, nb = skeleton.names[joints[a]], skeleton.names[joints[b]]
                    raise ValueError(f"effectors on {nb} and {na}: a zero-length bone joins them, so they sit on "
                                     "one point; keep one of them")
    return eff
