"""Restoring bone lengths of predicted joint positions: the FABRIK backward pass alone.

Introduced in ``notebooks/01_fabrik.ipynb``; lesson 03 uses it as the post-processing of the neural
solvers (Victor et al. 2021, Sec. 3.4). Units: :mod:`posekit.conventions` (metres).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from .._jit import njit
from ..skeleton import Skeleton

__all__ = ["fix_bone_lengths"]


@njit
def _place(out, j, child, anchor, length, w):
    """``out[j] += w * (anchor + length * (child - anchor) / |child - anchor|)``."""
    ux, uy, uz = child[0] - anchor[0], child[1] - anchor[1], child[2] - anchor[2]
    f = length / max(np.sqrt(ux * ux + uy * uy + uz * uz), 1e-12)
    out[j, 0] += w * (anchor[0] + f * ux)
    out[j, 1] += w * (anchor[1] + f * uy)
    out[j, 2] += w * (anchor[2] + f * uz)


@njit
def _fix_kernel(pos, parents, lengths, child_start, child_idx, backward):
    """The passes of :func:`fix_bone_lengths` on (N, J, 3) positions, in place."""
    N, J = pos.shape[0], pos.shape[1]
    tmp = np.zeros((1, 3))
    for n in range(N):
        p = pos[n]
        if backward:
            for j in range(J - 1, -1, -1):
                a, b = child_start[j], child_start[j + 1]
                if b == a:
                    continue
                tmp[0, 0] = tmp[0, 1] = tmp[0, 2] = 0.0
                for k in range(a, b):
                    c = child_idx[k]
                    _place(tmp, 0, p[j], p[c], lengths[c], 1.0 / (b - a))
                p[j, 0], p[j, 1], p[j, 2] = tmp[0, 0], tmp[0, 1], tmp[0, 2]
        for j in range(1, J):
            q = parents[j]
            tmp[0, 0] = tmp[0, 1] = tmp[0, 2] = 0.0
            _place(tmp, 0, p[j], p[q], lengths[j], 1.0)
            p[j, 0], p[j, 1], p[j, 2] = tmp[0, 0], tmp[0, 1], tmp[0, 2]


@lru_cache(maxsize=32)
def _children(parents: tuple):
    """Parents as an array and every joint's children in CSR form (start offsets (J + 1,), indices)."""
    p = np.asarray(parents, dtype=np.int64)
    kids = [np.nonzero(p == j)[0] for j in range(len(p))]
    start = np.concatenate([[0], np.cumsum([len(k) for k in kids])]).astype(np.int64)
    idx = np.concatenate(kids).astype(np.int64) if len(p) > 1 else np.zeros(0, np.int64)
    return p, start, idx


def fix_bone_lengths(skeleton: Skeleton, global_pos, lengths=None, keep: str = "leaves") -> np.ndarray:
    """Restore bone lengths of predicted joint positions with one FABRIK pass.

    Parameters
    ----------
    global_pos : ndarray, shape (..., J, 3), metres
        Positions whose bones may have the wrong length (e.g. a network's output).
    lengths : ndarray, shape (J,), optional
        Wanted bone lengths; default ``skeleton.bone_lengths()``.
    keep : {"leaves", "root"}
        ``"leaves"``: FABRIK's forward reaching — leaves stay where they are and every parent is
        placed at the right distance from its children (at the centroid where several children
        meet), so the hands and feet keep their positions; then one backward-reaching stage from the
        root (now moved) makes every bone exact (posekit's choice). ``"root"``: only the walk from the
        root outwards, as the authors' code of Victor et al. 2021 (``fix_lengths``) does.

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
    if keep not in ("leaves", "root"):
        raise ValueError(f"keep must be 'leaves' or 'root', got {keep!r}")
    L = skeleton.bone_lengths() if lengths is None else np.asarray(lengths, dtype=float)
    parents, child_start, child_idx = _children(tuple(int(p) for p in skeleton.parents))
    shape = pos.shape
    out = np.ascontiguousarray(pos.reshape(-1, J, 3))
    _fix_kernel(out, parents, np.ascontiguousarray(L, dtype=float), child_start, child_idx, keep == "leaves")
    return out.reshape(shape)
