"""Both full Bandai Namco datasets as one MotionSet, split for lesson 03's full-scale and cross-dataset runs.

Introduced with ``posekit bench ae-scale`` (:mod:`posekit.bench.ae_scale`, lesson 03,
``notebooks/03_autoencoder_solvers.ipynb``). The datasets are read by path from ``$POSEKIT_DATA_DIR``
and never copied (CC BY-NC 4.0, Bandai Namco Research Inc.). Each clip is checked and normalised as
the mini set's build does (:mod:`posekit.data.bandai_mini`): one fixed 22-joint skeleton, ``joint_Root``
a helper 0.94 m below ``Hips``, ``local_pos=None``. See :func:`scale_motions` and the notes of
:mod:`posekit.bench.ae_scale` for the protocols and frame counts.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..paths import require_shared_data

__all__ = ["PROTOCOLS", "CROSS_VAL_FRACTION", "scale_motions", "describe_motions"]

PROTOCOLS = {
    "full": "train: all of dataset 2 + the dataset-1 clips held_out_split puts in train; val/test: the dataset-1 "
            "clips it holds out (unseen styles and takes of trained contents)",
    "cross": "train: dataset 2 (a seeded ~3 % of its frames, whole clips, held back as val); test: all of "
             "dataset 1 (another capture, contents dataset 2 lacks)",
}
"""Protocol name -> what its split is."""

CROSS_VAL_FRACTION = 0.03
"""Share of dataset-2 frames (whole clips, seeded) the ``cross`` protocol keeps as val."""


def _files(data_dir: Path, dataset: int) -> list[Path]:
    from .bandai import BANDAI_FOLDERS

    folder = data_dir / BANDAI_FOLDERS[f"bandai{dataset}"] / "data"
    files = sorted(folder.glob(f"dataset-{dataset}_*.bvh"))
    if not files:
        raise FileNotFoundError(f"no dataset-{dataset}_*.bvh files in {folder}")
    return files


def _limited(files: list[Path], limit: int | None, dataset: int, protocol: str) -> list[Path]:
    """At most ``limit`` files; for dataset 1 under ``full`` taken in turn from test, val and train (sorted
    by name within each), so that every split keeps clips."""
    if limit is None or limit >= len(files):
        return files
    if dataset == 1 and protocol == "full":
        from .bandai_mini import held_out_split

        by = {s: [f for f in files if held_out_split(f.stem) == s] for s in ("test", "val", "train")}
        out = []
        while len(out) < limit:
            for s in by:
                if by[s] and len(out) < limit:
                    out.append(by[s].pop(0))
        return sorted(out)
    return files[:limit]


def _reference(data_dir: Path):
    """Offsets (22, 3), metres, and parents of the fixed skeleton (the mini set's)."""
    from .bandai_mini import JOINTS, REFERENCE_FILE, ROOT_TO_HIPS
    from ..io.bvh import read_bvh

    ref = read_bvh(data_dir / REFERENCE_FILE, scale=0.01)
    if tuple(ref.skeleton.names) != JOINTS:
        raise ValueError(f"{REFERENCE_FILE}: joints {ref.skeleton.names} are not the Bandai 22-joint skeleton")
    offsets = np.array(ref.skeleton.offsets, dtype=float)
    offsets[0] = 0.0
    offsets[1] = ROOT_TO_HIPS
    return offsets, np.array(ref.skeleton.parents)


def _normalise(ms, offsets, parents, dataset: int, step: int):
    """Check one dataset's MotionSet (as read, per-frame ``local_pos``) against the fixed skeleton and
    return its rotations (F', 22, 4) and root positions (F', 3) at ``step``, per-clip frame counts, and
    the largest offset / bone-length deviations (metres)."""
    from .bandai_mini import JOINTS, LENGTH_TOL, OFFSET_TOL, ROOT_TO_HIPS

    sk = ms.skeleton
    if tuple(sk.names) != JOINTS or not np.array_equal(np.asarray(sk.parents), parents):
        theirs = ", ".join(f"{n}<-{sk.names[p] if p >= 0 else '-'}" for n, p in zip(sk.names, sk.parents))
        raise ValueError(f"dataset {dataset}: its joint hierarchy is not the Bandai 22-joint one of "
                         f"{', '.join(JOINTS)} (file order, parents {list(parents)}); got {theirs}")
    q, lp = ms.local_rot, ms.local_pos if ms.local_pos is not None else np.broadcast_to(sk.offsets, ms.global_pos.shape)
    if np.abs(q[:, 0, :3]).max() > 1e-9:
        c = int(ms.clip_id[np.argmax(np.abs(q[:, 0, :3]).max(-1))])
        raise ValueError(f"{ms.clip_names[c]}: joint_Root rotates; the full-scale set assumes it only translates")
    dev = np.abs(lp[:, 2:] - offsets[2:]).max(axis=(1, 2))
    dlen = np.abs(np.linalg.norm(lp[:, 2:], axis=-1) - np.linalg.norm(offsets[2:], axis=-1)).max(axis=1)
    bad = np.nonzero((dev > OFFSET_TOL) | (dlen > LENGTH_TOL))[0]
    if len(bad):
        f = bad[0]
        raise ValueError(f"{ms.clip_names[ms.clip_id[f]]}: joints below Hips differ from the reference skeleton "
                         f"(position channels by {dev[f]:.2e} m, bone lengths by {dlen[f]:.2e} m; tolerances "
                         f"{OFFSET_TOL:g} m, {LENGTH_TOL:g} m); one MotionSet needs one bone length per bone")
    keep = np.concatenate([ms.clip_frames(c)[::step] for c in range(ms.n_clips)])
    q = q[keep].copy()
    q[:, 0] = (0.0, 0.0, 0.0, 1.0)
    q *= np.where(q[..., 3:] < 0, -1.0, 1.0)  # w >= 0, as the mini set
    root = lp[keep, 0] + lp[keep, 1] - np.asarray(ROOT_TO_HIPS)  # world Hips - ROOT_TO_HIPS
    lengths = np.bincount(ms.clip_id[keep], minlength=ms.n_clips)
    return q, root, lengths, float(dev.max()), float(dlen.max())


def scale_motions(protocol: str = "full", data_dir=None, limit: int | None = None, progress: bool = True,
                  step: int = 1, seed: int = 0):
    """Both full Bandai Namco datasets as one MotionSet with the protocol's train/val/test split.

    Parameters
    ----------
    protocol : {"full", "cross"}
        See :data:`PROTOCOLS` and the module notes.
    data_dir : path, optional
        Folder holding ``bandai-namco-1/`` and ``bandai-namco-2-every4th/``; default ``$POSEKIT_DATA_DIR``.
    limit : int, optional
        At most this many clips per dataset (tests); at least 3. Dataset 1 under ``full`` takes its clips
        in turn from test, val and train so that each split keeps some; otherwise the first files by name.
    progress : bool
        Show tqdm bars while reading the BVH files.
    step : int
        Keep every ``step``-th frame of each clip, from its first (1: every frame, the files' frame rates;
        ``frame_time`` is multiplied by ``step``).
    seed : int
        Seeds the choice of the ``cross`` protocol's val clips.

    Returns
    -------
    MotionSet
        Dataset-1 clips first, then dataset 2, each sorted by name; 22 joints, metres, Y up, facing +Z;
        ``local_rot`` (F, 22, 4) float64 (``w >= 0``), ``root_pos`` (F, 3) metres (``joint_Root``, a helper
        0.94 m below ``Hips``), ``global_pos`` (F, 22, 3) metres by FK, ``local_pos`` None, ``frame_time``
        per clip (1/30 s dataset 1, 2/15 s dataset 2, times ``step``). Extra attributes: ``split``
        (:class:`posekit.data.bandai_mini.BandaiMiniSplit`: sorted ``train``/``val``/``test`` frame
        indices, per-clip split, dataset, content, style and take; ``rule`` is the protocol's text),
        ``protocol``, ``step``, ``offset_dev_max_m`` and ``bone_length_dev_max_m`` (largest change the
        fixed skeleton makes to a file's OFFSETs / bone lengths, metres). Licence: CC BY-NC 4.0,
        Bandai Namco Research Inc.

    Raises
    ------
    ValueError
        An unknown protocol, ``limit < 3``, ``step < 1``, a dataset whose hierarchy is not the 22-joint
        Bandai one, a rotating ``joint_Root`` or a bone whose length differs from the reference.
    """
    from .bandai import BANDAI_ROLES
    from .bandai_mini import JOINTS, BandaiMiniSplit, held_out_split, parse_clip_name
    from .motion import MotionSet
    from .sources import load_bvh_files
    from ..kinematics import fk
    from ..skeleton import Skeleton

    if protocol not in PROTOCOLS:
        raise ValueError(f"unknown protocol {protocol!r}; valid: {', '.join(PROTOCOLS)}")
    if limit is not None and int(limit) < 3:
        raise ValueError(f"limit must be at least 3 clips per dataset (train, val and test need clips), got {limit}")
    if int(step) < 1:
        raise ValueError(f"step must be >= 1, got {step}")
    step = int(step)
    data_dir = require_shared_data(data_dir)
    offsets, parents = _reference(data_dir)
    parts = []
    for d in (1, 2):
        files = _limited(_files(data_dir, d), limit, d, protocol)
        ms = load_bvh_files(files, scale=0.01, roles=BANDAI_ROLES, name=f"bandai{d}", progress=progress)
        parts.append((d, ms.clip_names, ms.frame_time * step, *_normalise(ms, offsets, parents, d, step)))
        del ms
    q = np.concatenate([p[3] for p in parts])
    root = np.concatenate([p[4] for p in parts])
    lengths = np.concatenate([p[5] for p in parts])
    names = [n for p in parts for n in p[1]]
    frame_time = np.concatenate([p[2] for p in parts])
    clip_dataset = np.concatenate([np.full(len(p[1]), p[0]) for p in parts]).astype(np.int64)
    if np.any(lengths == 0):
        raise ValueError(f"clip {names[int(np.argmin(lengths))]} has no frames")
    clip_id = np.repeat(np.arange(len(names)), lengths)
    skel = Skeleton(JOINTS, parents, offsets, roles=BANDAI_ROLES, name=f"bandai-{protocol}")
    global_pos = fk(skel, q, root)[0]

    if protocol == "full":
        clip_split = np.array([held_out_split(n) for n in names])
    else:
        clip_split = np.where(clip_dataset == 1, "test", "train").astype("<U5")
        two = np.nonzero(clip_dataset == 2)[0]
        order = np.random.default_rng(seed).permutation(two)
        cum = np.cumsum(lengths[order])
        n_val = max(1, int(np.searchsorted(cum, CROSS_VAL_FRACTION * cum[-1])) + 1)
        n_val = min(n_val, len(two) - 1)
        clip_split[order[:n_val]] = "val"
    labels = [parse_clip_name(n) for n in names]
    frame_split = clip_split[clip_id]
    split = BandaiMiniSplit(
        *(np.nonzero(frame_split == s)[0] for s in ("train", "val", "test")),
        clip_split=clip_split, clip_dataset=clip_dataset,
        clip_content=np.array([lab[1] for lab in labels]), clip_style=np.array([lab[2] for lab in labels]),
        clip_take=np.array([lab[3] for lab in labels], dtype=np.int64),
        rule=f"{protocol}: {PROTOCOLS[protocol]}",
    )
    out = MotionSet(skel, q, root, global_pos, clip_id, names, frame_time, None,
                    source=f"bandai-{protocol} ({data_dir})")
    out.split = split
    out.protocol = protocol
    out.step = step
    out.offset_dev_max_m = max(p[6] for p in parts)
    out.bone_length_dev_max_m = max(p[7] for p in parts)
    return out


def describe_motions(motions) -> dict:
    """Frame and clip counts of a :func:`scale_motions` set, per split and per dataset (JSON-able).

    Returns
    -------
    dict
        ``frames``, ``clips``, ``seconds`` (duration), ``frames_per_split``, ``clips_per_split``,
        ``frames_per_dataset``, ``clips_per_dataset``, ``split_datasets`` (split -> frames per dataset),
        ``fps_per_dataset``, ``step``, ``offset_dev_max_m``, ``bone_length_dev_max_m``, ``rule``.
    """
    sp = motions.split
    lengths = motions.clip_lengths()
    fds = sp.clip_dataset[motions.clip_id]
    out = {
        "frames": int(motions.n_frames), "clips": int(motions.n_clips), "seconds": round(motions.duration(), 1),
        "frames_per_split": {s: int(len(sp.frames(s))) for s in ("train", "val", "test")},
        "clips_per_split": {s: int(np.sum(sp.clip_split == s)) for s in ("train", "val", "test")},
        "frames_per_dataset": {str(d): int(lengths[sp.clip_dataset == d].sum()) for d in (1, 2)},
        "clips_per_dataset": {str(d): int(np.sum(sp.clip_dataset == d)) for d in (1, 2)},
        "split_datasets": {s: {str(d): int(np.sum(fds[sp.frames(s)] == d)) for d in (1, 2)}
                           for s in ("train", "val", "test")},
        "fps_per_dataset": {str(d): round(float(1 / np.median(motions.frame_time[sp.clip_dataset == d])), 3)
                            for d in (1, 2) if np.any(sp.clip_dataset == d)},
        "step": int(getattr(motions, "step", 1)),
        "offset_dev_max_m": getattr(motions, "offset_dev_max_m", None),
        "bone_length_dev_max_m": getattr(motions, "bone_length_dev_max_m", None),
        "rule": sp.rule,
    }
    return out
