"""Mocap dialects a user brings, written here (no CMU or boxing file ships): a CMU-style folder (31 joints in CMU
units, ten zero-length bones such as Hips -> LHipJoint) and a 21-joint Holden-style folder in centimetres.

The rigs are :mod:`tests.io.test_rigs`'s; these helpers write several clips of one rig, enough held-out clips for
every start condition of the benchmarks (a clip-level 80/10/10 split of 20 clips holds out two)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.io.test_rigs import HOLDEN21, HOLDEN21_PARENTS, cmu_rig, write_rig

_HOLDEN_OFFSETS = {"Hips": (0, 95, 0), "LeftUpLeg": (9, -5, 0), "LeftLeg": (0, -42, 0), "LeftFoot": (0, -41, 0),
                   "LeftToeBase": (0, -7, 13), "Spine": (0, 12, 0), "Spine1": (0, 14, 0), "Neck1": (0, 16, 0),
                   "Head": (0, 12, 3), "LeftArm": (16, 10, 0), "LeftForeArm": (27, 0, 0), "LeftHand": (25, 0, 0),
                   "LeftHandIndex1": (8, 0, 0)}


def holden21_rig():
    """Holden et al.'s 21-joint layout in centimetres (no zero-length bone)."""
    out = []
    for n, p in zip(HOLDEN21, HOLDEN21_PARENTS):
        o = _HOLDEN_OFFSETS.get(n) or _HOLDEN_OFFSETS[n.replace("Right", "Left")]
        if n.startswith("Right"):
            o = (-o[0], o[1], o[2])
        out.append((n, None if p < 0 else HOLDEN21[p], o))
    return out


def write_clips(folder, rig, clips: int = 20, frames: int = 30, seed: int = 0) -> Path:
    """``clips`` BVH files of ``rig`` (smooth random motion, 120 fps) in ``folder`` (created)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    for c in range(clips):
        write_rig(folder / f"take_{c:02d}.bvh", rig, rng, frames=frames)
    return folder


def cmu_folder(folder, **kw) -> Path:
    """A CMU-style folder: 31 joints, CMU units, zero-length bones (Hips -> LHipJoint and nine more)."""
    return write_clips(folder, cmu_rig(), **kw)


def holden_folder(folder, **kw) -> Path:
    """A 21-joint folder in centimetres."""
    return write_clips(folder, holden21_rig(), **kw)
