"""Where poses come from: the shipped DeepMimic sample, BVH files and folders, the Bandai Namco sets.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``. Data locations: :mod:`posekit.paths`.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ..io.bvh import read_bvh
from ..kinematics import fk
from ..paths import require_shared_data, samples_dir
from ..skeleton import Skeleton, joint_set_difference
from .bandai import BANDAI_FOLDERS, BANDAI_ROLES
from .motion import MotionSet
from ..io.rigs import guess_units, unit_warning

__all__ = [
    "SAMPLE_FILE",
    "load_sample", "load_bvh_files", "load_bandai", "skeleton_preset", "open_dataset", "dataset_names",
    "hierarchy_difference",
]

SAMPLE_FILE = "deepmimic_humanoid.npz"
"""File name of the embedded default data inside :func:`posekit.paths.samples_dir`."""

def load_sample() -> MotionSet:
    """The embedded default: 15 DeepMimic humanoid clips, 18 joints, metres, facing +Z.

    Built by ``posekit data build-sample`` from pybullet's wheel; provenance and licence in
    ``data_samples/README.md``.
    """
    path = samples_dir() / SAMPLE_FILE
    if not path.is_file():
        raise FileNotFoundError(f"{path} is missing; rebuild it with `posekit data build-sample` "
                                "(needs `pip install -e .[build-data]`)")
    return MotionSet.load(path, source="deepmimic (data_samples)")


def load_bvh_files(paths, scale: float | None = None, roles: dict | None = None, name: str = "",
                   drop_tpose: bool = False, progress: bool = False) -> MotionSet:
    """Read BVH files of one skeleton into a :class:`MotionSet`, one clip per file.

    The files must share one hierarchy (joint names and parents); their OFFSETs may differ, as for
    clips of different subjects: the skeleton's offsets are the first file's, and
    ``MotionSet.local_pos`` (F, J, 3) carries every clip's own offsets, so ``global_pos`` is right
    for every clip.

    Parameters
    ----------
    paths : sequence of path
    scale : float, optional
        File units to metres (0.01 for centimetres). Default: detected from the median standing
        height of the files (:func:`posekit.io.rigs.guess_units`), with a warning when the unit is
        not metres; one scale for all files.
    roles : dict, optional
        Canonical roles -> joint names; default guessed from the names
        (:func:`posekit.io.rigs.guess_roles`); given roles replace guessed ones.
    drop_tpose : bool
        Drop each file's first frame.
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    MotionSet
        Lengths in metres. Two extra attributes: ``units`` (:class:`posekit.io.rigs.UnitGuess`:
        unit, scale, height) and ``rig`` (:class:`posekit.io.rigs.RolesReport`: rig name, roles,
        missing roles).

    Raises
    ------
    ValueError
        When the files do not share one hierarchy, naming the first file that differs and how.
    """
    paths = [Path(p) for p in paths]
    if not paths:
        raise ValueError("no BVH files given")
    it = paths
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(paths, desc="reading BVH", unit="file")
    motions = []
    for p in it:
        m = read_bvh(p, scale=1.0, roles=roles, name=name, drop_tpose=drop_tpose)
        if motions:
            why = hierarchy_difference(motions[0].skeleton, m.skeleton)
            if why:
                raise ValueError(f"{p}: its joint hierarchy differs from {paths[0]}'s: {why}; one MotionSet "
                                 "holds one skeleton (clips may differ in OFFSETs only)")
        motions.append(m)
    units = guess_units(float(np.median([m.units.file_height for m in motions])), scale)
    if scale is None:
        message = unit_warning(units, str(paths[0].parent if len(paths) > 1 else paths[0]))
        if message:
            warnings.warn(message, UserWarning, stacklevel=2)
    s = units.scale
    raw = motions[0].skeleton
    skel = Skeleton(raw.names, raw.parents, raw.offsets * s, raw.roles, raw.name,
                    {k: v * s for k, v in raw.end_sites.items()})
    local_rot = np.concatenate([m.local_rot for m in motions])
    local_pos = np.concatenate([m.local_pos for m in motions]) * s
    clip_id = np.concatenate([np.full(m.n_frames, i) for i, m in enumerate(motions)])
    animated = bool(np.any(np.abs(local_pos[:, 1:] - skel.offsets[1:]) > 1e-9)) if len(local_pos) else False
    lp = local_pos if animated else None
    root_pos = local_pos[:, 0]
    global_pos = fk(skel, local_rot, root_pos, lp)[0]
    ms = MotionSet(skel, local_rot, root_pos, global_pos, clip_id, [p.stem for p in paths],
                   np.array([m.frame_time for m in motions]), lp,
                   source=str(paths[0].parent if len(paths) > 1 else paths[0]))
    ms.units = units
    ms.rig = motions[0].rig
    return ms


def hierarchy_difference(first: Skeleton, other: Skeleton) -> str:
    """How ``other``'s joint hierarchy (names and parents) differs from ``first``'s; "" when equal."""
    a, b = first.names, other.names
    if len(a) != len(b):
        return "; ".join([f"{len(b)} joints instead of {len(a)}", *joint_set_difference(a, b, show=5)])
    renamed = [j for j in range(len(a)) if a[j] != b[j]]
    if renamed:
        j = renamed[0]
        return (f"{len(renamed)} joint name(s) differ, the first is joint {j}: {b[j]!r} here, {a[j]!r} "
                "in the first file")
    moved = [j for j in range(len(a)) if first.parents[j] != other.parents[j]]
    if moved:
        j = moved[0]
        return (f"{len(moved)} joint(s) hang from other parents, the first is {a[j]!r}: under "
                f"{b[other.parents[j]]!r} here, under {a[first.parents[j]]!r} in the first file")
    return ""


def load_bandai(which: int = 1, data_dir=None, limit: int | None = None, progress: bool = True,
                pattern: str = "*.bvh") -> MotionSet:
    """Bandai Namco Research Motion Dataset 1 or 2 (every 4th frame), read by path, never copied.

    Parameters
    ----------
    which : {1, 2}
    data_dir : path, optional
        Folder holding ``bandai-namco-1/`` and ``bandai-namco-2-every4th/``; default
        ``$POSEKIT_DATA_DIR``.
    limit : int, optional
        Read only the first ``limit`` files (sorted by name).
    pattern : str
        Glob of the files to read, e.g. ``"*_walk_*.bvh"``.

    Returns
    -------
    MotionSet
        22 joints, metres (the files are in centimetres), 30 fps (dataset 1) or 7.5 fps (dataset 2).
        Licence: CC BY-NC 4.0, Bandai Namco Research Inc.
    """
    key = f"bandai{which}"
    if key not in BANDAI_FOLDERS:
        raise ValueError(f"which must be 1 or 2, got {which!r}")
    folder = require_shared_data(data_dir) / BANDAI_FOLDERS[key] / "data"
    files = sorted(folder.glob(pattern))[:limit]
    if not files:
        raise FileNotFoundError(f"no BVH files matching {pattern!r} in {folder}")
    ms = load_bvh_files(files, scale=0.01, roles=BANDAI_ROLES, name=key, progress=progress)
    ms.source = f"{key} ({folder})"
    return ms


def skeleton_preset(name: str, data_dir=None) -> Skeleton:
    """Skeleton of a dataset: ``"deepmimic"`` (shipped) or ``"bandai"`` (read from the first BVH
    header of dataset 1 under ``data_dir`` / ``$POSEKIT_DATA_DIR``; the hierarchy is identical in
    every Bandai file)."""
    if name in ("deepmimic", "sample"):
        with np.load(samples_dir() / SAMPLE_FILE) as z:
            return Skeleton.from_arrays(z)
    if name in ("bandai", "bandai1", "bandai2"):
        folder = require_shared_data(data_dir) / BANDAI_FOLDERS.get(name, "bandai-namco-1") / "data"
        first = next(iter(sorted(folder.glob("*.bvh"))), None)
        if first is None:
            raise FileNotFoundError(f"no BVH file in {folder}")
        return read_bvh(first, scale=0.01, roles=BANDAI_ROLES, name="bandai").skeleton
    raise ValueError(f"unknown skeleton preset {name!r}; valid: deepmimic, bandai")


def dataset_names() -> list[str]:
    """Names accepted by :func:`open_dataset` besides paths."""
    return ["sample", "deepmimic", "bandai-mini", "bandai1", "bandai2"]


def open_dataset(spec, scale: float | None = None, data_dir=None, progress: bool = False,
                 roles: dict | None = None) -> MotionSet:
    """Open a dataset by name (``sample``/``deepmimic``, ``bandai-mini`` (shipped, see
    :func:`posekit.data.load_bandai_mini`), ``bandai1``, ``bandai2``), a BVH file, a
    folder of BVH files, or a ``.npz`` written by :meth:`MotionSet.save`.

    ``scale`` (file units to metres) and ``roles`` (role -> joint name) apply to BVH paths; by
    default both are detected (see :func:`load_bvh_files`).
    """
    s = str(spec)
    if s in ("sample", "deepmimic"):
        return load_sample()
    if s == "bandai-mini":
        from .bandai_mini import load_bandai_mini

        return load_bandai_mini()
    if s in BANDAI_FOLDERS:
        return load_bandai(int(s[-1]), data_dir=data_dir, progress=progress)
    p = Path(s)
    if p.is_dir():
        files = sorted(p.glob("*.bvh"))
        if not files:
            raise FileNotFoundError(f"{p}: folder holds no .bvh files")
        return load_bvh_files(files, scale=scale, roles=roles, progress=progress)
    if p.is_file():
        if p.suffix.lower() == ".npz":
            return MotionSet.load(p)
        return load_bvh_files([p], scale=scale, roles=roles)
    raise FileNotFoundError(f"{s!r} is neither a dataset name ({', '.join(dataset_names())}) nor an existing "
                            "BVH file, folder or .npz")
