"""The Bandai mini set: a compact real pose set shipped in ``data_samples/bandai_mini/``.

Introduced for lessons 03–06 (the learned and data-driven solvers), so that they train and test on
real captures without the full Bandai Namco Research Motion Datasets. Conventions (metres, Y up,
facing +Z, quaternions ``(x, y, z, w)``): :mod:`posekit.conventions`.

* :func:`build_bandai_mini` — reads both datasets by path (``$POSEKIT_DATA_DIR``) and writes
  ``bandai_mini.npz``; run it as ``posekit data build-sample bandai``.
* :func:`load_bandai_mini` — the shipped file as a :class:`~posekit.data.motion.MotionSet` (positions
  by FK at load time) with its clip-level split in ``.split``.
* :func:`bandai_mini_split` — that split (:class:`BandaiMiniSplit`) on its own.
* :func:`held_out_split` — the documented rule that puts each clip in train, val or test.

What the build does to the source files
---------------------------------------
* Frames: dataset 2 (``bandai-namco-2-every4th``, 7.5 fps) keeps every
  ``STEP[2]``-th frame of each clip, dataset 1 (30 fps) every ``STEP[1]``-th, each from its first
  frame; ``frame_time`` of each clip is the resulting seconds per frame.
* Skeleton: the 22 joints of the files, in file order, centimetres -> metres. The build checks, and
  raises otherwise, that every file has this hierarchy, that ``joint_Root`` never rotates, that the
  position channels of every joint below ``Hips`` are constant and equal to the reference OFFSETs
  (within :data:`OFFSET_TOL`; eight dataset-1 files carry a ``LowerLeg_R`` OFFSET 0.40 mm off the
  others, the largest difference), so the set is stored as rotations + one root position and
  loaded with ``local_pos=None``.
* Root: in the files the world position of ``Hips`` is ``joint_Root`` translation + ``Hips``
  translation (``joint_Root`` stays at the origin except in four dataset-1 clips where it carries
  the forward travel). The mini set stores that world position of ``Hips`` minus
  :data:`ROOT_TO_HIPS` as ``root_pos`` (joint 0); ``joint_Root`` gets the identity rotation and the
  fixed offset ``ROOT_TO_HIPS`` to ``Hips``. ``joint_Root`` is therefore a helper point 0.94 m
  below the pelvis that only translates: not part of a pose (leave it out of pose features; the
  ``pelvis`` role is ``Hips``).
* Rotations: local quaternions with ``w >= 0``, stored as float16 and renormalised in float64 on
  load; ``root_pos`` as float32.
"""

from __future__ import annotations

import io
import json
import os
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..kinematics import fk
from ..paths import require_shared_data, samples_dir
from ..skeleton import Skeleton
from .motion import MotionSet
from .bandai import BANDAI_FOLDERS, BANDAI_ROLES

__all__ = [
    "MINI_DIR", "MINI_FILE", "STEP", "ROOT_TO_HIPS", "JOINTS", "CONTENTS_1", "STYLES_1",
    "BandaiMiniSplit", "held_out_split", "build_bandai_mini", "load_bandai_mini", "bandai_mini_split",
    "mini_path", "LICENCE",
]

MINI_DIR = "bandai_mini"
"""Folder of the set inside :func:`posekit.paths.samples_dir`."""

MINI_FILE = "bandai_mini.npz"
"""File name of the set inside :data:`MINI_DIR`."""

LICENCE = ("CC BY-NC 4.0 (non-commercial): trained on the Bandai mini set (data_samples/bandai_mini/), "
           "frames subsampled from the Bandai Namco Research Motion Datasets 1 and 2, (c) Bandai Namco "
           "Research Inc., CC BY-NC 4.0 (Kobayashi et al. 2023, arXiv 2306.08861).")
"""Licence recorded in weights trained on the Bandai mini set."""

FORMAT_VERSION = 1

STEP = {1: 2, 2: 4}
"""Frame step per dataset: dataset 1 (30 fps) -> 15 fps, dataset 2 (7.5 fps) -> 1.875 fps."""

SOURCE_FRAME_TIME = {1: 1 / 30, 2: 4 / 30}
"""Seconds per frame of the source files (dataset 2 is already every 4th frame of 30 fps)."""

ROOT_TO_HIPS = (0.0, 0.94, 0.0)
"""Offset of ``Hips`` from ``joint_Root`` in the mini set, metres (about the standing pelvis height)."""

REFERENCE_FILE = "bandai-namco-1/data/dataset-1_walk_normal_001.bvh"
"""The file whose OFFSETs (below ``Hips``) define the fixed skeleton."""

OFFSET_TOL = 1e-3
"""Largest accepted difference (metres) between a file's OFFSETs / position channels below ``Hips``
and the reference OFFSETs; the bone *lengths* must agree within :data:`LENGTH_TOL`."""

LENGTH_TOL = 1e-6
"""Largest accepted difference (metres) between a file's bone lengths and the reference's."""

JOINTS = (
    "joint_Root", "Hips", "Spine", "Chest", "Neck", "Head",
    "Shoulder_L", "UpperArm_L", "LowerArm_L", "Hand_L", "Shoulder_R", "UpperArm_R", "LowerArm_R", "Hand_R",
    "UpperLeg_L", "LowerLeg_L", "Foot_L", "Toes_L", "UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R",
)
"""The 22 joints of every Bandai file, in file order."""

CONTENTS_1 = ("walk", "run", "dash", "walk-back", "walk-right", "walk-left", "bow", "bye", "guide",
              "byebye", "respond", "call", "punch", "kick", "slash", "dance-long", "dance-short")
"""Dataset 1 contents in the order of its ``cfg/content_label.txt`` (``dance-long`` is absent)."""

STYLES_1 = ("normal", "happy", "sad", "angry", "proud", "not-confident", "masculinity", "feminine",
            "childish", "old", "tired", "active", "musical", "giant", "chimpira")
"""Dataset 1 styles in the order of its ``cfg/style_label.txt``."""

NORMAL_ONLY_1 = ("respond", "call", "punch", "kick", "slash", "dance-long", "dance-short")
"""Dataset 1 contents captured in the ``normal`` style only (one or two takes)."""

MULTI_STYLE_1 = tuple(c for c in CONTENTS_1 if c not in NORMAL_ONLY_1)
"""Dataset 1 contents captured in all 15 styles."""

SPLITS = ("train", "val", "test")

RULE = (
    "Dataset 2: train. Dataset 1, contents with 15 styles (walk, run, dash, walk-back, walk-right, "
    "walk-left, bow, bye, guide, byebye; rank r = 0..9 in that order): the style "
    "STYLES_1[1 + (2r mod 14)] goes to test and STYLES_1[1 + ((2r+1) mod 14)] to val (all takes of it), "
    "the other 13 styles, normal always among them, to train. Dataset 1, normal-only contents: take 001 "
    "to train, take 002 (call, punch, slash) to test; single-take contents (respond, kick, dance-short) "
    "are train-only, so that every content of val and test is also in train."
)
"""The held-out rule of :func:`held_out_split`, in words."""


def mini_path() -> Path:
    """Path of the shipped file, ``samples_dir()/bandai_mini/bandai_mini.npz``."""
    return samples_dir() / MINI_DIR / MINI_FILE


# ---------------------------------------------------------------------------------------------- split
def parse_clip_name(name: str) -> tuple[int, str, str, int]:
    """``"dataset-1_walk-back_happy_001"`` -> ``(1, "walk-back", "happy", 1)``.

    Raises
    ------
    ValueError
        For a name not of the form ``dataset-{1,2}_{content}_{style}_{take}``.
    """
    parts = str(name).split("_")
    if len(parts) != 4 or parts[0] not in ("dataset-1", "dataset-2") or not parts[3].isdigit():
        raise ValueError(f"{name!r}: expected a Bandai clip name dataset-{{1,2}}_CONTENT_STYLE_TAKE")
    return int(parts[0][-1]), parts[1], parts[2], int(parts[3])


def held_out_split(name: str) -> str:
    """Which set a clip belongs to (``"train"``, ``"val"`` or ``"test"``), from its name alone.

    The rule (:data:`RULE`): dataset 2 is all train. In dataset 1, each content captured in 15 styles
    holds out one style for test and another for val, rotating through the 14 non-normal styles in
    the cfg order, so test styles (happy, angry, not-confident, feminine, old, active, giant) and val
    styles (sad, proud, masculinity, childish, tired, musical, chimpira) never overlap and ``normal``
    stays in train. Of the normal-only contents, take 002 (call, punch, slash) is test, take 001 is
    train; contents with a single take (respond, kick, dance-short) are train-only. Every content of
    val and test is therefore seen in training, but none of their takes.

    Parameters
    ----------
    name : str
        Clip name ``dataset-{1,2}_{content}_{style}_{take}`` (the BVH file stem).
    """
    dataset, content, style, take = parse_clip_name(name)
    if dataset == 2:
        return "train"
    if content in NORMAL_ONLY_1:
        return "test" if take >= 2 else "train"
    if content not in MULTI_STYLE_1:
        raise ValueError(f"{name!r}: unknown dataset-1 content {content!r}; known: {', '.join(CONTENTS_1)}")
    if style not in STYLES_1:
        raise ValueError(f"{name!r}: unknown dataset-1 style {style!r}; known: {', '.join(STYLES_1)}")
    r = MULTI_STYLE_1.index(content)
    if style == STYLES_1[1 + (2 * r) % 14]:
        return "test"
    if style == STYLES_1[1 + (2 * r + 1) % 14]:
        return "val"
    return "train"


@dataclass
class BandaiMiniSplit:
    """Clip-level train/val/test split of the mini set.

    Attributes
    ----------
    train, val, test : ndarray of int, shape (F_set,)
        Sorted frame indices into the :class:`MotionSet` of each set; every clip lies in one set.
    clip_split : ndarray of str, shape (C,)
        ``"train"``, ``"val"`` or ``"test"`` per clip.
    clip_dataset : ndarray of int, shape (C,)
        1 or 2: which Bandai Namco dataset the clip comes from.
    clip_content, clip_style : ndarray of str, shape (C,)
        Content (motion type: ``walk``, ``punch``, ...) and style labels of each clip.
    clip_take : ndarray of int, shape (C,)
        Take number (the ``_001`` of the file name).
    rule : str
        The held-out rule (:data:`RULE`).
    """

    train: np.ndarray
    val: np.ndarray
    test: np.ndarray
    clip_split: np.ndarray
    clip_dataset: np.ndarray
    clip_content: np.ndarray
    clip_style: np.ndarray
    clip_take: np.ndarray
    rule: str = field(default=RULE, repr=False)

    def frames(self, name: str) -> np.ndarray:
        """Frame indices of ``"train"``, ``"val"`` or ``"test"``."""
        if name not in SPLITS:
            raise ValueError(f"unknown split {name!r}; valid: {', '.join(SPLITS)}")
        return getattr(self, name)

    def clips(self, name: str) -> np.ndarray:
        """Clip indices of ``"train"``, ``"val"`` or ``"test"``."""
        if name not in SPLITS:
            raise ValueError(f"unknown split {name!r}; valid: {', '.join(SPLITS)}")
        return np.nonzero(self.clip_split == name)[0]


def _split_from_arrays(z, clip_id: np.ndarray) -> BandaiMiniSplit:
    clip_split = np.asarray(z["clip_split"]).astype(str)
    frame_split = clip_split[clip_id]
    return BandaiMiniSplit(
        *(np.nonzero(frame_split == s)[0] for s in SPLITS),
        clip_split=clip_split,
        clip_dataset=np.asarray(z["clip_dataset"]).astype(np.int64),
        clip_content=np.asarray(z["clip_content"]).astype(str),
        clip_style=np.asarray(z["clip_style"]).astype(str),
        clip_take=np.asarray(z["clip_take"]).astype(np.int64),
    )


# ---------------------------------------------------------------------------------------------- load
def load_bandai_mini(path=None) -> MotionSet:
    """The shipped Bandai mini set, with positions by FK and its clip-level split.

    Parameters
    ----------
    path : path, optional
        A file written by :func:`build_bandai_mini`; default :func:`mini_path`.

    Returns
    -------
    MotionSet
        22 joints (joint 0 ``joint_Root`` is a helper point, see the module notes), metres, Y up,
        facing +Z; ``local_rot`` (F, 22, 4) float64 unit quaternions, ``root_pos`` (F, 3) metres,
        ``global_pos`` (F, 22, 3) metres by FK, ``local_pos`` None (every bone has its rest length),
        ``frame_time`` per clip (1/15 s for dataset 1, 8/15 s for dataset 2). The attribute
        ``split`` holds the :class:`BandaiMiniSplit`. Licence: CC BY-NC 4.0, Bandai Namco Research Inc.

    Raises
    ------
    FileNotFoundError
        When the file is missing (rebuild with ``posekit data build-sample bandai``).
    """
    path = Path(path) if path is not None else mini_path()
    if not path.is_file():
        raise FileNotFoundError(f"{path} is missing; rebuild it with `posekit data build-sample bandai` "
                                "(needs the Bandai Namco datasets under $POSEKIT_DATA_DIR)")
    with np.load(path, allow_pickle=False) as z:
        skel = Skeleton.from_arrays(z)
        q = z["local_rot"].astype(np.float64)
        q /= np.linalg.norm(q, axis=-1, keepdims=True)
        root_pos = z["root_pos"].astype(np.float64)
        lengths = z["clip_lengths"].astype(np.int64)
        clip_id = np.repeat(np.arange(len(lengths)), lengths)
        names = [str(n) for n in z["clip_names"]]
        frame_time = z["frame_time"].astype(np.float64)
        split = _split_from_arrays(z, clip_id)
    global_pos = fk(skel, q, root_pos)[0]
    ms = MotionSet(skel, q, root_pos, global_pos, clip_id, names, frame_time, None,
                   source=f"bandai-mini ({path})")
    ms.split = split
    return ms


def bandai_mini_split(motions_or_path=None) -> BandaiMiniSplit:
    """The clip-level split of the mini set.

    Parameters
    ----------
    motions_or_path : MotionSet or path, optional
        A set returned by :func:`load_bandai_mini` (its ``split``), or a file; default the shipped
        file (reads only the small label arrays).
    """
    if isinstance(motions_or_path, MotionSet):
        split = getattr(motions_or_path, "split", None)
        if split is None:
            raise ValueError("this MotionSet carries no Bandai mini split; load it with load_bandai_mini()")
        return split
    path = Path(motions_or_path) if motions_or_path is not None else mini_path()
    with np.load(path, allow_pickle=False) as z:
        lengths = z["clip_lengths"].astype(np.int64)
        return _split_from_arrays(z, np.repeat(np.arange(len(lengths)), lengths))


# ---------------------------------------------------------------------------------------------- build
def _reference(data_dir: Path):
    """Offsets (J, 3) in metres of the fixed skeleton and its bone lengths (J,)."""
    from ..io.bvh import read_bvh

    ref = read_bvh(data_dir / REFERENCE_FILE, scale=0.01)
    if tuple(ref.skeleton.names) != JOINTS:
        raise ValueError(f"{REFERENCE_FILE}: unexpected joints {ref.skeleton.names}")
    offsets = np.array(ref.skeleton.offsets)
    offsets[0] = 0.0
    offsets[1] = ROOT_TO_HIPS
    return offsets, ref.skeleton.parents.copy()


def _read_clip(args):
    """Read one BVH file, check its skeleton and return its subsampled rotations and root (float64)."""
    from ..io.bvh import read_bvh

    path, dataset, offsets, parents = args
    m = read_bvh(path, scale=0.01)
    sk = m.skeleton
    if tuple(sk.names) != JOINTS or not np.array_equal(sk.parents, parents):
        raise ValueError(f"{path}: joint hierarchy differs from the Bandai 22-joint skeleton")
    if abs(m.frame_time - SOURCE_FRAME_TIME[dataset]) > 1e-6:
        raise ValueError(f"{path}: Frame Time {m.frame_time} s, expected {SOURCE_FRAME_TIME[dataset]:.6f}")
    lp, q = m.local_pos, m.local_rot
    if m.n_frames == 0:
        raise ValueError(f"{path}: no frames")
    # joint_Root never rotates, so the world position of Hips is joint_Root + Hips translation
    if np.abs(q[:, 0, :3]).max() > 1e-9:
        raise ValueError(f"{path}: joint_Root rotates; the mini set assumes it only translates")
    # every joint below Hips: position channels constant and equal to the reference OFFSETs
    dev_off = float(np.abs(sk.offsets[2:] - offsets[2:]).max())
    dev_pos = float(np.abs(lp[:, 2:] - offsets[2:]).max())
    ref_len = np.linalg.norm(offsets[2:], axis=-1)
    dev_len = float(np.abs(np.linalg.norm(lp[:, 2:], axis=-1) - ref_len).max())
    if dev_off > OFFSET_TOL or dev_pos > OFFSET_TOL or dev_len > LENGTH_TOL:
        raise ValueError(f"{path}: joints below Hips differ from the reference skeleton (OFFSET by {dev_off:.2e} m, "
                         f"position channels by {dev_pos:.2e} m, bone lengths by {dev_len:.2e} m); "
                         "the mini set needs constant bone lengths")
    step = STEP[dataset]
    q = q[::step].copy()
    q[:, 0] = (0.0, 0.0, 0.0, 1.0)
    q *= np.where(q[..., 3:] < 0, -1.0, 1.0)  # w >= 0
    hips_world = lp[::step, 0] + lp[::step, 1]
    root = hips_world - np.asarray(ROOT_TO_HIPS)
    return q, root, max(dev_off, dev_pos), dev_len


def _clip_files(data_dir: Path, names=None):
    """[(path, dataset)] in build order: dataset 1 files sorted by name, then dataset 2."""
    out = []
    for dataset in (1, 2):
        folder = data_dir / BANDAI_FOLDERS[f"bandai{dataset}"] / "data"
        files = sorted(folder.glob(f"dataset-{dataset}_*.bvh"))
        if not files:
            raise FileNotFoundError(f"no dataset-{dataset}_*.bvh files in {folder}")
        out += [(f, dataset) for f in files]
    if names is not None:
        wanted = set(names)
        out = [(f, d) for f, d in out if f.stem in wanted]
        missing = wanted - {f.stem for f, _ in out}
        if missing:
            raise FileNotFoundError(f"clips not found under {data_dir}: {', '.join(sorted(missing)[:5])}")
    return out


def _check_labels(path: Path, dataset: int, content: str, style: str):
    """The JSON label of a clip names the same content and style as its file name."""
    js = path.with_suffix(".json")
    if not js.is_file():
        return
    lab = json.loads(js.read_text())
    cfg = path.parent.parent / "cfg"
    for key, value, fname in (("content", content, "content_label.txt"), ("style", style, "style_label.txt")):
        f = cfg / fname
        if f.is_file() and key in lab:
            labels = [s.strip() for s in f.read_text().split() if s.strip()]
            if labels[int(lab[key])] != f"dataset-{dataset}_{value}":
                raise ValueError(f"{js}: {key} {lab[key]} is {labels[int(lab[key])]!r}, the file name says {value!r}")


def _write_npz(path: Path, arrays: dict):
    """``np.savez_compressed`` with fixed zip timestamps, so two builds give identical bytes."""
    tmp = path.with_name(path.name + ".tmp")
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for key, arr in arrays.items():
            info = zipfile.ZipInfo(f"{key}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            buf = io.BytesIO()
            np.lib.format.write_array(buf, np.asarray(arr), allow_pickle=False)
            zf.writestr(info, buf.getvalue(), compresslevel=9)
    os.replace(tmp, path)


def build_bandai_mini(data_dir=None, out=None, names=None, workers: int | None = None,
                      progress: bool = False) -> dict:
    """Build the mini set from the full Bandai Namco datasets (read by path, never copied).

    Parameters
    ----------
    data_dir : path, optional
        Folder holding ``bandai-namco-1/`` and ``bandai-namco-2-every4th/``; default ``$POSEKIT_DATA_DIR``.
    out : path, optional
        File to write; default :func:`mini_path` (the shipped file). Missing folders are created.
    names : iterable of str, optional
        Build only these clips (BVH file stems); every clip's arrays are computed from that clip
        alone, so a subset equals the same clips of the full build (used by the tests).
    workers : int, optional
        Processes reading the BVH files; default the number of CPUs. The output does not depend on it.
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    dict
        ``path``, ``frames``, ``clips``, ``bytes``, ``seconds`` (build time), ``frames_per_split``,
        ``clips_per_split``, ``clips_per_dataset``, ``float16_pos_err_max`` / ``_mean`` (metres:
        FK of the stored float16 quaternions + float32 root vs the float64 values, over all joints
        and frames), ``offset_dev_max`` (metres: largest difference of a file's OFFSETs / position
        channels below Hips from the reference) and ``bone_length_dev_max`` (metres).

    Raises
    ------
    ValueError
        When a file breaks an assumption of the format (hierarchy, frame time, rotating
        ``joint_Root``, a bone below ``Hips`` whose length changes), naming the file.
    """
    t0 = time.perf_counter()
    data_dir = require_shared_data(data_dir)
    out = Path(out) if out is not None else mini_path()
    out.parent.mkdir(parents=True, exist_ok=True)
    offsets, parents = _reference(data_dir)
    files = _clip_files(data_dir, names)
    labels = []
    for f, d in files:
        ds, content, style, take = parse_clip_name(f.stem)
        if ds != d:
            raise ValueError(f"{f}: file name says dataset {ds}, folder is dataset {d}")
        _check_labels(f, d, content, style)
        labels.append((ds, content, style, take, held_out_split(f.stem)))
    jobs = [(f, d, offsets, parents) for f, d in files]
    workers = (os.cpu_count() or 1) if workers is None else int(workers)
    if workers > 1 and len(jobs) > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(max_workers=min(workers, len(jobs))) as ex:
            it = ex.map(_read_clip, jobs, chunksize=16)
            if progress:
                from tqdm.auto import tqdm

                it = tqdm(it, total=len(jobs), desc="reading BVH", unit="file")
            results = list(it)
    else:
        it = jobs
        if progress:
            from tqdm.auto import tqdm

            it = tqdm(jobs, desc="reading BVH", unit="file")
        results = [_read_clip(j) for j in it]

    q64 = np.concatenate([r[0] for r in results])
    root64 = np.concatenate([r[1] for r in results])
    lengths = np.array([len(r[0]) for r in results], dtype=np.int32)
    q16 = q64.astype(np.float16)
    root32 = root64.astype(np.float32)

    skel = Skeleton(JOINTS, parents, offsets, roles=BANDAI_ROLES, name="bandai-mini")
    # float16 error: FK of what the loader returns vs FK of the float64 values
    qn = q16.astype(np.float64)
    qn /= np.linalg.norm(qn, axis=-1, keepdims=True)
    err = np.linalg.norm(fk(skel, qn, root32.astype(np.float64))[0] - fk(skel, q64, root64)[0], axis=-1)

    ds = np.array([lab[0] for lab in labels], dtype=np.int8)
    split = np.array([lab[4] for lab in labels])
    arrays = {
        "format_version": np.array(FORMAT_VERSION, dtype=np.int32),
        **skel.to_arrays(),
        "local_rot": q16,
        "root_pos": root32,
        "clip_lengths": lengths,
        "clip_names": np.array([f.stem for f, _ in files]),
        "frame_time": np.array([STEP[d] * SOURCE_FRAME_TIME[d] for _, d in files], dtype=np.float64),
        "clip_dataset": ds,
        "clip_content": np.array([lab[1] for lab in labels]),
        "clip_style": np.array([lab[2] for lab in labels]),
        "clip_take": np.array([lab[3] for lab in labels], dtype=np.int16),
        "clip_split": split,
        "source_step": np.array([STEP[d] for _, d in files], dtype=np.int16),
    }
    _write_npz(out, arrays)
    frame_split = np.repeat(split, lengths)
    return {
        "path": str(out),
        "frames": int(lengths.sum()),
        "clips": len(files),
        "bytes": out.stat().st_size,
        "seconds": round(time.perf_counter() - t0, 2),
        "frames_per_split": {s: int(np.sum(frame_split == s)) for s in SPLITS},
        "clips_per_split": {s: int(np.sum(split == s)) for s in SPLITS},
        "clips_per_dataset": {d: int(np.sum(ds == d)) for d in (1, 2)},
        "frames_per_dataset": {d: int(lengths[ds == d].sum()) for d in (1, 2)},
        "float16_pos_err_max": float(err.max()),
        "float16_pos_err_mean": float(err.mean()),
        "offset_dev_max": max(r[2] for r in results),
        "bone_length_dev_max": max(r[3] for r in results),
    }
