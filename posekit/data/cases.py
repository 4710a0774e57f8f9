"""Posing cases: (start pose, true target pose) pairs from held-out real motion, in the root frame.

Introduced in ``notebooks/01_fabrik.ipynb``; every posing benchmark (``posekit bench ik``) and the
learned solvers of lessons 03-05 are measured on these cases. Units and axes:
:mod:`posekit.conventions`.

Where the poses come from
-------------------------
* **Targets** are frames of the *test* set: the set's own split when the :class:`MotionSet` carries
  one (``motions.split``, e.g. the Bandai mini set, :func:`posekit.data.load_bandai_mini`), else a
  clip-level split (:func:`posekit.data.split_by_clip`, seeded, with its time-split fallback when
  there are too few clips). No clip a learned solver trains on is ever a target
  (:func:`case_split` gives the training frames too).
* **Start conditions** (:data:`START_CONDITIONS`):

  - ``"same-clip"`` — another frame of the target's clip, at most :data:`SAME_CLIP_MAX_S` seconds
    away (``"frame"`` is accepted as an alias, the name of earlier releases);
  - ``"other-clip"`` — a frame of another held-out clip;
  - ``"rest"`` — the skeleton's rest pose (identity local rotations) when it stands upright; on
    skeletons whose zero-rotation pose does not stand (Bandai's bones lie along +X: head and feet
    both point sideways from the pelvis) the *typical* training pose instead — the training frame
    nearest the mean root-relative pose (:func:`rest_start`).

  For one seed and case count the *targets* are the same under every start condition, so the
  conditions compare like with like.
* Both poses are expressed in their root frame (pelvis above the origin, facing +Z; Victor et al.
  2021, Sec. 3.2) and the start is shifted so that its pelvis sits on the target's: the solvers keep
  the pelvis in place, so every case is reachable and the target is one exact solution.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics import fk
from ..records import Pose
from ..transforms import rotate_y_rotations, to_root_space
from .dataset import sample_pairs, split_by_clip
from .motion import MotionSet

__all__ = ["Cases", "build_cases", "case_split", "held_out_clips", "placement_joints",
           "START_CONDITIONS", "START_ALIASES",
           "SAME_CLIP_MAX_S", "REST_TOL", "start_condition", "rest_start"]

START_CONDITIONS = {
    "same-clip": "another frame of the target's clip, up to 1 s away",
    "other-clip": "a frame of another held-out clip",
    "rest": "the skeleton's rest pose (or, when it does not stand, the training pose nearest the mean)",
}
"""Start condition -> what the start pose is."""

START_ALIASES = {"frame": "same-clip"}
"""Older names still accepted."""

SAME_CLIP_MAX_S = 1.0
"""Largest time between start and target of a ``same-clip`` case, seconds."""

REST_TOL = 1e-6
"""``start="rest"`` on a set with per-frame joint translations (``local_pos``) needs every joint below
the pelvis to keep its skeleton offset within this many metres in the held-out frames."""


def start_condition(name: str) -> str:
    """The canonical name of a start condition (aliases resolved); a clear error lists the valid ones."""
    name = START_ALIASES.get(name, name)
    if name not in START_CONDITIONS:
        raise ValueError(f"unknown start condition {name!r}; valid: {', '.join(START_CONDITIONS)} "
                         f"(alias: {', '.join(f'{a} = {b}' for a, b in START_ALIASES.items())})")
    return name


@dataclass
class Cases:
    """Posing cases: start poses and the true poses whose joints give the effector targets.

    Every array is in the target's root frame, start pelvis on target pelvis.

    Attributes
    ----------
    skeleton : Skeleton
    start_rot : ndarray, shape (N, J, 4)
        Local quaternions of the start poses.
    start_root : ndarray, shape (N, 3), metres
    start_local_pos : ndarray, shape (N, J, 3) or None
        Per-joint translations of the start poses (None: the skeleton offsets).
    start_pos : ndarray, shape (N, J, 3), metres
    target_pos : ndarray, shape (N, J, 3), metres
        True poses; effector targets are taken from them.
    start : str
        The start condition (:data:`START_CONDITIONS`).
    source : str
        The data set.
    target_rot : ndarray, shape (N, J, 4)
        Local quaternions of the true poses (for rotation errors).
    target_root : ndarray, shape (N, 3), metres
    target_local_pos : ndarray, shape (N, J, 3) or None
    start_frame, target_frame : ndarray of int, shape (N,)
        Frame indices into the MotionSet (``start_frame`` is -1 for the rest pose).
    train_frames : ndarray of int
        The training frames of the same split (for the naturalness reference of
        :class:`posekit.data.metrics.NaturalnessIndex`).
    split : str
        Which split the cases come from.
    """

    skeleton: object
    start_rot: np.ndarray
    start_root: np.ndarray
    start_local_pos: np.ndarray | None
    start_pos: np.ndarray
    target_pos: np.ndarray
    start: str
    source: str
    target_rot: np.ndarray | None = None
    target_root: np.ndarray | None = None
    target_local_pos: np.ndarray | None = None
    start_frame: np.ndarray | None = None
    target_frame: np.ndarray | None = None
    train_frames: np.ndarray | None = None
    split: str = ""

    def __len__(self):
        return len(self.target_pos)

    def pose(self, i):
        """The start pose of case ``i`` as a :class:`posekit.ik.Pose` (what ``solver.solve`` takes)."""
        lp = None if self.start_local_pos is None else self.start_local_pos[i]
        return Pose(self.start_pos[i], self.start_rot[i], self.start_root[i], lp)


def case_split(motions: MotionSet, seed: int = 0, fractions=(0.8, 0.1, 0.1)):
    """Train, val and test frames for cases and for the solvers that learn from the same data.

    The set's own split when it carries one (``motions.split`` with ``train``/``val``/``test``, as
    :func:`posekit.data.load_bandai_mini` sets; ``seed`` and ``fractions`` are then unused), else
    :func:`posekit.data.split_by_clip` with ``fallback=True``.

    Returns
    -------
    train, val, test : ndarray of int
    how : str
        ``"<source>'s own split"`` or ``"split_by_clip(seed=S)"``.
    """
    own = getattr(motions, "split", None)
    if own is not None and all(hasattr(own, k) for k in ("train", "val", "test")):
        return (np.sort(np.asarray(own.train)), np.sort(np.asarray(own.val)), np.sort(np.asarray(own.test)),
                f"{motions.source.split(' ')[0] or 'the set'}'s own split")
    train, val, test = split_by_clip(motions, fractions, seed=seed, fallback=True)
    return train, val, test, f"split_by_clip(seed={seed})"


def placement_joints(skeleton) -> np.ndarray:
    """Joints from the root down to the pelvis (both included): they place the body in the world,
    shape (P,). Just ``[0]`` when the root is the pelvis; ``[joint_Root, Hips]`` on Bandai skeletons."""
    return np.array(skeleton.chain(skeleton.pelvis(), 0), dtype=np.int64)


def _rest_refusal(motions: MotionSet, frames) -> str | None:
    """Why the rest pose cannot start these targets (None when it can): a joint below the pelvis whose
    translation differs from the skeleton offset, so no rotation of the rest pose reaches the target."""
    if motions.local_pos is None:
        return None
    s = motions.skeleton
    body = np.setdiff1d(np.arange(s.n_joints), placement_joints(s))
    dev = np.abs(motions.local_pos[frames][:, body] - s.offsets[body]).max(axis=(0, 2))
    if len(dev) == 0 or dev.max() <= REST_TOL:
        return None
    j = body[int(np.argmax(dev))]
    return (f"the rest start (--start rest; start='rest' in Python) needs every joint below the pelvis to keep its "
            f"skeleton offset (within "
            f"{REST_TOL:g} m); in {s.name or motions.source!r} the translation of {s.names[j]} differs by "
            f"{dev.max() * 1e3:.3g} mm in held-out frames, so the rest pose cannot reach those targets; "
            "use the same-clip or other-clip start (--start same-clip,other-clip)")


def _same_clip_pairs(motions: MotionSet, n: int, rng, frames, max_s: float):
    """``n`` (start, target) pairs of distinct frames of one clip at most ``max_s`` apart, drawn with
    :func:`posekit.data.sample_pairs` and kept when within the time limit of their clip."""
    ft = motions.frame_time[motions.clip_id[frames]]
    max_gap = max(1, int(np.floor(max_s / ft.min() + 1e-9)))
    a_all, b_all, got = [], [], 0
    for _ in range(50):
        a, b = sample_pairs(motions, 2 * (n - got) + 16, rng=rng, max_gap=max_gap, frames=frames)
        keep = (a != b) & (np.abs(a - b) * motions.frame_time[motions.clip_id[a]] <= max_s + 1e-9)
        a_all.append(a[keep])
        b_all.append(b[keep])
        got += int(keep.sum())
        if got >= n:
            return np.concatenate(a_all)[:n], np.concatenate(b_all)[:n]
    raise ValueError(f"could not draw {n} same-clip pairs within {max_s:g} s from {len(frames)} held-out frames "
                     f"of {motions.source!r}: its held-out clips are too short")


def _other_clip_starts(motions: MotionSet, targets, frames, rng):
    """One start frame per target, uniform over the held-out frames of *other* clips."""
    clip = motions.clip_id[frames]
    n_clips = len(np.unique(clip))
    if n_clips < 2:
        raise ValueError(f"the other-clip start (--start other-clip; start='other-clip' in Python) needs at least two "
                         f"held-out clips; {motions.source!r} has {n_clips} (use the same-clip start: --start "
                         "same-clip, or --start rest,same-clip for posekit bench all)")
    t_clip = motions.clip_id[targets]
    lo = np.searchsorted(clip, t_clip, side="left")
    hi = np.searchsorted(clip, t_clip, side="right")
    k = (rng.random(len(targets)) * (len(frames) - (hi - lo))).astype(np.int64)
    k += (k >= lo) * (hi - lo)  # skip over the target's own clip
    return frames[k]


def _stands(skeleton, pos) -> bool:
    """True when a pose (J, 3) stands upright: head above the pelvis and feet below it, each by more
    than half its distance from the pelvis (True when the skeleton lacks those roles)."""
    need = ("pelvis", "head", "left_foot", "right_foot")
    if any(r not in skeleton.roles for r in need):
        return True
    pel, head = pos[skeleton.index("pelvis")], pos[skeleton.index("head")]
    ok = head[1] - pel[1] > 0.5 * np.linalg.norm(head - pel)
    for foot in ("left_foot", "right_foot"):
        f = pos[skeleton.index(foot)]
        ok &= pel[1] - f[1] > 0.5 * np.linalg.norm(f - pel)
    return bool(ok)


def rest_start(motions: MotionSet, train_frames):
    """The start pose of ``start="rest"``: local rotations (J, 4), root position (3,) and whether it
    is the skeleton's own rest pose.

    The skeleton's rest pose (identity rotations, root at its offset) when it stands upright;
    otherwise the training frame nearest the mean of the training poses in the root frame (mean
    joint distance), expressed in its root frame — a real, typical standing pose.
    """
    s = motions.skeleton
    rot = np.broadcast_to([0.0, 0.0, 0.0, 1.0], (s.n_joints, 4)).copy()
    if _stands(s, fk(s, rot, s.offsets[0])[0]) or len(train_frames) == 0:
        return rot, s.offsets[0].copy(), True
    pick = np.asarray(train_frames)[:: max(1, len(train_frames) // 20_000)]
    local, origin, angle = to_root_space(s, motions.global_pos[pick])
    k = int(np.argmin(np.linalg.norm(local - local.mean(0), axis=-1).mean(-1)))
    q, root = rotate_y_rotations(motions.local_rot[pick[k]], motions.root_pos[pick[k]] - origin[k], -angle[k])
    return q, root, False


def held_out_clips(motions: MotionSet, seed: int = 0, split=(0.8, 0.1, 0.1)) -> int:
    """How many clips the held-out frames of :func:`build_cases` come from (the ``other-clip`` start needs two)."""
    test = case_split(motions, seed, split)[2]
    return len(np.unique(motions.clip_id[test]))


def build_cases(motions: MotionSet, n_cases: int = 1000, seed: int = 0, start: str = "same-clip",
                split=(0.8, 0.1, 0.1)) -> Cases:
    """Held-out posing cases (see the module docstring).

    Parameters
    ----------
    motions : MotionSet
    n_cases : int
    seed : int
        Seeds the split (when the set has none of its own) and the draw; the targets depend only on
        ``seed`` and ``n_cases``, not on ``start``.
    start : str
        ``"same-clip"`` (alias ``"frame"``), ``"other-clip"`` or ``"rest"``.
    split : tuple of float
        Train/val/test shares for :func:`posekit.data.split_by_clip` (unused when the set has its own
        split). With fewer clips than sets the held-out frames are the end of every clip instead,
        with a warning.

    Raises
    ------
    ValueError
        An unknown start condition; ``"other-clip"`` with one held-out clip; ``"rest"`` when a joint
        below the pelvis has per-frame translations that differ from the skeleton offsets.
    """
    start = start_condition(start)
    s = motions.skeleton
    train, _, test, how = case_split(motions, seed, split)
    if len(test) < 2:
        raise ValueError(f"{motions.source!r}: {len(test)} held-out frame(s), too few for cases")
    rng = np.random.default_rng(seed)
    a, b = _same_clip_pairs(motions, n_cases, rng, test, SAME_CLIP_MAX_S)  # b: the targets
    if start == "other-clip":
        a = _other_clip_starts(motions, b, test, np.random.default_rng([seed, 1]))
    elif start == "rest":
        why = _rest_refusal(motions, test)
        if why:
            raise ValueError(why)
    frames = np.unique(np.concatenate([a, b]) if start != "rest" else b)
    local, origin, angle = to_root_space(s, motions.global_pos[frames])
    q, root = rotate_y_rotations(motions.local_rot[frames], motions.root_pos[frames] - origin, -angle)
    row = np.searchsorted(frames, b)
    lp_all = None if motions.local_pos is None else motions.local_pos[frames]
    target, t_lp = local[row], None if lp_all is None else lp_all[row]
    if start == "rest":
        q0, r0, _ = rest_start(motions, train)
        rot = np.broadcast_to(q0, (len(b), s.n_joints, 4)).copy()
        rpos = np.broadcast_to(r0, (len(b), 3)).copy()
        lp = None
        pos = fk(s, rot, rpos)[0]
        start_frame = np.full(len(b), -1, dtype=np.int64)
    else:
        ra = np.searchsorted(frames, a)
        rot, rpos, pos = q[ra], root[ra].copy(), local[ra]
        lp = None if lp_all is None else lp_all[ra]
        start_frame = a
    pel = s.pelvis()
    shift = target[:, pel] - pos[:, pel]
    return Cases(s, rot, rpos + shift, lp, pos + shift[:, None], target, start, motions.source,
                 target_rot=q[row], target_root=root[row], target_local_pos=t_lp, start_frame=start_frame,
                 target_frame=b, train_frames=train, split=how)
