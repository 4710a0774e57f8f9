"""The Bandai mini set: a compact real pose set shipped in ``data_samples/bandai_mini/``.

Introduced for lessons 03–06 (the learned and data-driven solvers), so that they train and test on
real captures without the full Bandai Namco Research Motion Datasets. Conventions (metres, Y up,
facing +Z, quaternions ``(x, y, z, w)``): :mod:`posekit.conventions`.

* :func:`~posekit.data.bandai_mini_build.build_bandai_mini` — reads both datasets by path
  (``$POSEKIT_DATA_DIR``) and writes ``bandai_mini.npz``; run it as ``posekit data build-sample bandai``
  (:mod:`posekit.data.bandai_mini_build` says what the build does to the source files).
* :func:`load_bandai_mini` — the shipped file as a :class:`~posekit.data.motion.MotionSet` (positions
  by FK at load time) with its clip-level split in ``.split``.
* :func:`bandai_mini_split` — that split (:class:`BandaiMiniSplit`) on its own.
* :func:`held_out_split` — the documented rule that puts each clip in train, val or test.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..kinematics import fk
from ..paths import samples_dir
from ..skeleton import Skeleton
from .motion import MotionSet

__all__ = [
    "MINI_DIR", "MINI_FILE", "STEP", "ROOT_TO_HIPS", "JOINTS", "CONTENTS_1", "STYLES_1",
    "BandaiMiniSplit", "held_out_split", "load_bandai_mini", "bandai_mini_split",
    "mini_path", "LICENCE", "weights_licence",
]

MINI_DIR = "bandai_mini"
"""Folder of the set inside :func:`posekit.paths.samples_dir`."""

MINI_FILE = "bandai_mini.npz"
"""File name of the set inside :data:`MINI_DIR`."""

LICENCE = ("CC BY-NC 4.0 (non-commercial): trained on the Bandai mini set (data_samples/bandai_mini/), "
           "frames subsampled from the Bandai Namco Research Motion Datasets 1 and 2, (c) Bandai Namco "
           "Research Inc., CC BY-NC 4.0 (Kobayashi et al. 2023, arXiv 2306.08861).")
"""Licence recorded in weights trained on the Bandai mini set."""


def weights_licence(label: str) -> str:
    """The licence to record in weights trained on the data set ``label`` (a ``posekit`` data set name):
    :data:`LICENCE` for the mini set, the full Bandai sets' CC BY-NC 4.0 for ``bandai1`` / ``bandai2``,
    else a pointer to the data's own licence."""
    if label == "bandai-mini":
        return LICENCE
    if "bandai" in label.lower():
        return (f"CC BY-NC 4.0 (non-commercial): trained on {label}, the Bandai Namco Research Motion Dataset "
                "(c) Bandai Namco Research Inc., CC BY-NC 4.0 (Kobayashi et al. 2023, arXiv 2306.08861).")
    return "see the data's licence"

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
        A file written by :func:`~posekit.data.bandai_mini_build.build_bandai_mini`; default :func:`mini_path`.

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
