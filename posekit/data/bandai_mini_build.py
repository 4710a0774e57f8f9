"""Building the Bandai mini set (:mod:`posekit.data.bandai_mini`) from the full Bandai Namco datasets.

Run as ``posekit data build-sample bandai``; the datasets are read by path (``$POSEKIT_DATA_DIR``) and
never copied.

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
from pathlib import Path

import numpy as np

from ..kinematics import fk
from ..paths import require_shared_data
from ..skeleton import Skeleton
from .bandai import BANDAI_FOLDERS, BANDAI_ROLES
from .bandai_mini import (FORMAT_VERSION, JOINTS, LENGTH_TOL, OFFSET_TOL, REFERENCE_FILE, ROOT_TO_HIPS,
                          SOURCE_FRAME_TIME, SPLITS, STEP, held_out_split, mini_path, parse_clip_name)

__all__ = ["build_bandai_mini"]


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
