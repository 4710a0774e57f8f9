"""Lesson 03's training data: (start, target) pairs of poses (Victor et al. 2021, Sec. 3.3.2).

Introduced in ``notebooks/03_autoencoder_solvers.ipynb``. The poses themselves are root-frame vectors
(:mod:`posekit.data.pose_vectors`). Training pairs are two frames of one clip at most :data:`PAIR_MAX_S`
seconds apart: the solver learns to move the *start* pose so chosen joints reach the *target* pose's
positions. Pairs much further apart teach a solver to ignore its start (measured for the issue: errors
of 170-250 mm), so they stay close.
"""

from __future__ import annotations

import numpy as np

from ...data.motion import MotionSet
from ...data.pose_vectors import PoseData

__all__ = ["PAIR_MAX_S", "training_pairs"]

PAIR_MAX_S = 1.0
"""Largest time between the start and the target frame of a training pair, seconds (the
benchmark's same-clip cases use the same limit, :data:`posekit.data.cases.SAME_CLIP_MAX_S`)."""


def training_pairs(motions: MotionSet, data: PoseData, n: int, seed: int = 0, max_s: float = PAIR_MAX_S):
    """``n`` (start, target) row pairs of ``data``: two frames of one clip at most ``max_s`` apart
    (never the same frame), each pair mirrored with probability 1/2 when ``data`` is mirrored.

    Returns
    -------
    start, target : ndarray of int, shape (n,)
        Rows of ``data.x``.
    """
    rng = np.random.default_rng(seed)
    frames = data.frames
    clip = motions.clip_id[frames]
    lo = np.searchsorted(clip, clip, side="left")
    hi = np.searchsorted(clip, clip, side="right")
    if np.all(hi - lo < 2):
        raise ValueError(f"training_pairs: every clip of {motions.source!r} in this split has a single frame")
    gap = np.maximum(1, np.floor(max_s / motions.frame_time[clip] + 1e-9)).astype(np.int64)
    ok = np.nonzero(hi - lo >= 2)[0]
    a = ok[rng.integers(0, len(ok), n)]
    first = np.maximum(lo[a], a - gap[a])
    last = np.minimum(hi[a] - 1, a + gap[a])
    # a uniform other frame in [first, last] \ {a}
    b = first + (rng.random(n) * (last - first)).astype(np.int64)
    b = b + (b >= a)
    if data.mirrored:
        flip = rng.random(n) < 0.5
        a = a + flip * data.n
        b = b + flip * data.n
    return a.astype(np.int64), b.astype(np.int64)
