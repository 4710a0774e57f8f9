"""Training-set utilities: clip-level splits, normalisation statistics, augmentation, frame pairs.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``; the learned solvers of notebooks 03-05
train on what these produce.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..records import NormStats
from ..transforms import mirror_positions, rotate_y_positions
from .motion import MotionSet

__all__ = ["split_by_clip", "split_by_time", "NormStats", "augment_positions", "sample_pairs"]


def split_by_clip(motions: MotionSet, fractions=(0.8, 0.1, 0.1), seed: int = 0, fallback: bool = False):
    """Split frames into train/val/test so that every clip lies in exactly one set.

    Clips are shuffled with ``seed`` and assigned greedily so each set's *frame* share is close to
    its fraction; each set gets at least one clip when there are enough clips.

    Parameters
    ----------
    fractions : sequence of float
        Shares of frames per set; normalised to sum to 1.
    fallback : bool
        When there are fewer clips than sets with a non-zero share (one or two BVH files for three
        sets), split *within* each clip instead (:func:`split_by_time`) and warn; without it such
        sets stay empty.

    Returns
    -------
    list of ndarray
        Frame indices of each set, sorted.

    Warns
    -----
    UserWarning
        ``fallback=True`` and too few clips: the split is frame-level, in time.
    """
    fr = np.asarray(fractions, dtype=float)
    if fr.ndim != 1 or len(fr) == 0 or np.any(fr < 0) or fr.sum() <= 0:
        raise ValueError(f"fractions: expected non-negative shares, got {fractions}")
    fr = fr / fr.sum()
    C = motions.n_clips
    if fallback and C < int(np.count_nonzero(fr)):
        warnings.warn(f"only {C} clip(s) for {int(np.count_nonzero(fr))} non-empty sets, too few for a clip-level "
                      "split; splitting each clip in time instead (train first, test last), so held-out frames "
                      "come from the same clips as the training frames", UserWarning, stacklevel=2)
        return split_by_time(motions, fractions)
    lengths = motions.clip_lengths()
    order = np.random.default_rng(seed).permutation(C)
    target = fr * lengths.sum()
    got = np.zeros(len(fr))
    clips = [[] for _ in fr]
    # first give each non-empty set one clip (if possible), then fill the most under-served set
    wanted = [k for k in np.argsort(-fr) if fr[k] > 0]
    queue = list(order)
    for k in wanted[: max(0, min(len(wanted), C))]:
        c = queue.pop(0)
        clips[k].append(c)
        got[k] += lengths[c]
    for c in queue:
        k = int(np.argmax((target - got) / np.maximum(target, 1e-9)))
        clips[k].append(c)
        got[k] += lengths[c]
    return [np.sort(np.concatenate([motions.clip_frames(c) for c in cs])) if cs else np.zeros(0, np.int64)
            for cs in clips]


def split_by_time(motions: MotionSet, fractions=(0.8, 0.1, 0.1)):
    """Frame-level split: each clip is cut in time into consecutive segments, one per set, in order
    (train = the first 80 % of every clip, val the next 10 %, test the last 10 %).

    Neighbouring frames are nearly identical, so a random frame-level split would leak; contiguous
    segments keep the leak to the segment borders. Use it only when there are too few clips for
    :func:`split_by_clip`.

    Returns
    -------
    list of ndarray
        Frame indices of each set, sorted.
    """
    fr = np.asarray(fractions, dtype=float)
    if fr.ndim != 1 or len(fr) == 0 or np.any(fr < 0) or fr.sum() <= 0:
        raise ValueError(f"fractions: expected non-negative shares, got {fractions}")
    edges = np.concatenate([[0.0], np.cumsum(fr / fr.sum())])
    sets = [[] for _ in fr]
    for c in range(motions.n_clips):
        frames = motions.clip_frames(c)
        cut = np.round(edges * len(frames)).astype(int)
        for k in range(len(fr)):
            sets[k].append(frames[cut[k]:cut[k + 1]])
    return [np.sort(np.concatenate(s)) if s else np.zeros(0, np.int64) for s in sets]


def augment_positions(skeleton, global_pos, rng=None, mirror_prob: float = 0.5, rotate: bool = True):
    """Random mirror and heading augmentation of joint positions.

    Parameters
    ----------
    global_pos : ndarray, shape (N, J, 3), metres
    mirror_prob : float
        Probability that a pose is mirrored (:func:`posekit.transforms.mirror_positions`).
    rotate : bool
        Turn each pose about the vertical through its pelvis by a uniform random angle.

    Returns
    -------
    ndarray, shape (N, J, 3)
    """
    rng = np.random.default_rng(rng)
    x = np.array(global_pos, dtype=float)
    flip = rng.random(len(x)) < mirror_prob
    if flip.any():
        x[flip] = mirror_positions(skeleton, x[flip])
    if rotate:
        pelvis = x[:, skeleton.pelvis()] * np.array([1.0, 0.0, 1.0])
        x = rotate_y_positions(x - pelvis[:, None], rng.uniform(-np.pi, np.pi, len(x))) + pelvis[:, None]
    return x


def sample_pairs(motions: MotionSet, n: int, rng=None, max_gap: int | None = None, frames=None):
    """Draw ``n`` (start, target) frame pairs from the same clip.

    The neural IK solvers learn to move the start pose so that chosen joints reach the target
    pose's positions (Victor et al. 2021, Sec. 3.3.2).

    Parameters
    ----------
    n : int
    max_gap : int, optional
        Largest distance in frames between the two; default any two frames of the clip.
    frames : ndarray, optional
        Restrict both frames to these indices (e.g. a training split).

    Returns
    -------
    start, target : ndarray of int, shape (n,)
    """
    rng = np.random.default_rng(rng)
    frames = np.arange(motions.n_frames) if frames is None else np.sort(np.asarray(frames))
    if len(frames) < 2:
        raise ValueError(f"sample_pairs needs at least two frames to draw pairs from, got {len(frames)} (of "
                         f"{motions.n_frames} frames in {motions.n_clips} clip(s)); an empty split set usually "
                         "means too few clips for a clip-level split: see split_by_clip(fallback=True)")
    clip = motions.clip_id[frames]
    # position of each frame's clip run inside `frames`
    lo = np.searchsorted(clip, clip, side="left")
    hi = np.searchsorted(clip, clip, side="right")
    start_pos = rng.integers(0, len(frames), n)
    a, b = lo[start_pos], hi[start_pos]
    if max_gap is not None:
        a = np.maximum(a, start_pos - max_gap)
        b = np.minimum(b, start_pos + max_gap + 1)
    target_pos = a + (rng.random(n) * (b - a)).astype(np.int64)
    return frames[start_pos], frames[target_pos]
