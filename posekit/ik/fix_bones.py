"""Restoring bone lengths of predicted joint positions: the FABRIK backward pass alone.

Introduced in ``notebooks/01_fabrik.ipynb``; lesson 03 uses it as the post-processing of the neural
solvers (Victor & Meyer 2020, Sec. 3.4). Units: :mod:`posekit.conventions` (metres).
"""

from __future__ import annotations

import numpy as np

from ..skeleton import Skeleton

__all__ = ["fix_bone_lengths"]


def fix_bone_lengths(skeleton: Skeleton, global_pos, lengths=None, keep: str = "leaves") -> np.ndarray:
    """Restore bone lengths of predicted joint positions with one FABRIK pass.

    Parameters
    ----------
    global_pos : ndarray, shape (..., J, 3), metres
        Positions whose bones may have the wrong length (e.g. a network's output).
    lengths : ndarray, shape (J,), optional
        Wanted bone lengths; default ``skeleton.bone_lengths()``.
    keep : {"leaves", "root"}
        ``"leaves"``: the backward pass of FABRIK — leaves stay where they are and every parent is
        placed at the right distance from its children (at the centroid where several children
        meet), so the hands and feet keep their positions; then one forward pass from the root
        (now moved) makes every bone exact. ``"root"``: only the forward pass from the root.

    Returns
    -------
    ndarray, shape (..., J, 3) with every bone length equal to ``lengths``.
    """
    pos = np.array(global_pos, dtype=float)
    J = skeleton.n_joints
    if pos.shape[-2:] != (J, 3):
        raise ValueError(f"global_pos: expected shape (..., {J}, 3), got {pos.shape}")
    if not np.all(np.isfinite(pos)):
        raise ValueError("global_pos contains NaN or inf")
    L = skeleton.bone_lengths() if lengths is None else np.asarray(lengths, dtype=float)
    parents = skeleton.parents

    def place(child, parent_pos, length):
        u = child - parent_pos
        n = np.linalg.norm(u, axis=-1, keepdims=True)
        return parent_pos + length * u / np.maximum(n, 1e-12)

    if keep == "leaves":
        back = pos.copy()
        for j in range(J - 1, 0, -1):
            kids = np.nonzero(parents == j)[0]
            if len(kids):
                back[..., j, :] = np.mean([place(back[..., j, :], back[..., c, :], L[c]) for c in kids], axis=0)
        kids = np.nonzero(parents == 0)[0]
        back[..., 0, :] = np.mean([place(back[..., 0, :], back[..., c, :], L[c]) for c in kids], axis=0)
        pos = back
    elif keep != "root":
        raise ValueError(f"keep must be 'leaves' or 'root', got {keep!r}")
    out = pos.copy()
    for j in range(1, J):
        out[..., j, :] = place(pos[..., j, :], out[..., parents[j], :], L[j])
    return out
