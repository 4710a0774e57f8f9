"""The ``posekit`` command line.

``posekit data inspect PATH [--json]``
    A BVH file, a folder of them, a ``.npz`` or a dataset name (``sample``, ``bandai1``, ``bandai2``):
    joints, parents, frame count, frame time, clip count.
``posekit data convert IN OUT.npz [--scale S]``
    A BVH file or folder (one clip per file) to a motion file every posekit command reads (``data inspect``,
    ``bench ... --data``, ``train ... --data``, the studio): :meth:`posekit.data.MotionSet.save`'s arrays, and
    for readers that want positions only ``names`` (J), ``parents`` (J) and ``positions`` (F, J, 3: global joint
    positions in metres, like every loader: the file's unit detected from the skeleton's height unless
    ``--scale`` gives metres per file unit); ``frame_time`` (C,) is per clip.
``posekit data build-sample [--pybullet-data DIR] [--out FILE]``
    Rebuilds ``data_samples/deepmimic_humanoid.npz`` from pybullet's wheel (extra ``build-data``).
``posekit bench fk [--poses N] [--repeats R] [--json]``
    FK throughput and load time, side by side with the baseline and the goal.
``posekit bench ik [--solvers fabrik,ccd,dls|all] [--effectors 2,5] [--start same-clip,other-clip,rest]``
``[--data sample|bandai-mini|bandai1|PATH] [--cases N] [--wide] [--json]``
    Every registered IK solver on the same held-out real poses, per start condition: latency,
    memory, effector/pose/rotation/bone errors, naturalness.
``posekit bench invrig [--json]``
    Inverse rig mapping: joint and ground-truth errors and frames/s of every method (lesson 02).
``posekit bench NAME``
    Any benchmark registered with :func:`posekit.bench.plugin.register_benchmark`.
``posekit data build-benchmark protores [--cases N] [--seed S]``
    Rebuilds lesson 05's 5-point and random effector benchmarks in ``data_samples/benchmarks/``.
``posekit train --list``
    Every trainable model: the files it makes, the lesson that loads them, about how long it takes.
``posekit train NAME [...]``
    Makes the weights a lesson ships (seeded): any trainer registered with
    :func:`posekit.learn.trainers.register_trainer` (``invrig``, ``ae-solvers``, ``ae-studies``, ``aegan``,
    ``protores``, ``protores-studies``; :mod:`posekit.catalogue` lists them in lesson order).

``posekit exercises list|solutions ...`` and ``posekit course slides|build|mark ...``
    The instructor kit (:mod:`posekit.course.commands`): solutions, slides, the course page.

Errors in input files print ``file:line: message`` and exit with status 2; warnings print as one line,
``posekit: warning: message``.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

import numpy as np


def _inspect(args) -> int:
    from .io.rigs import rig_report, standing_height
    from .data.sources import open_dataset

    ms = open_dataset(args.path, scale=args.scale, progress=True)
    skel = ms.skeleton
    rig = getattr(ms, "rig", None) or rig_report(skel.names, skel.roles)
    units = getattr(ms, "units", None)  # set when read from BVH
    info = {
        "source": ms.source,
        "joints": skel.n_joints,
        "names": list(skel.names),
        "parents": [int(p) for p in skel.parents],
        "frames": ms.n_frames,
        "clips": ms.n_clips,
        "frame_time": float(np.median(ms.frame_time)) if ms.n_clips else None,
        "frame_time_min": float(ms.frame_time.min()) if ms.n_clips else None,
        "frame_time_max": float(ms.frame_time.max()) if ms.n_clips else None,
        "seconds": round(ms.duration(), 3),
        "roles": skel.roles,
        "rig": rig.rig,
        "missing_roles": list(rig.missing),
        "unit": units.unit if units else None,
        "scale": units.scale if units else None,
        "height_m": round(units.height if units else standing_height(skel.names, skel.parents, skel.offsets,
                                                                    skel.roles), 4),
    }
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    print(f"source      {info['source']}")
    print(f"joints      {info['joints']}")
    print(f"frames      {info['frames']}  ({info['seconds']:.1f} s)")
    ft = info["frame_time"]
    spread = "" if info["frame_time_min"] == info["frame_time_max"] else \
        f"  (clips range {info['frame_time_min']:.6g}-{info['frame_time_max']:.6g})"
    print(f"frame time  {ft:.6g} s  ({1 / ft:.1f} fps){spread}" if ft else "frame time  -")
    print(f"clips       {info['clips']}")
    print(f"units       {units.describe() if units else 'metres (stored)'}")
    print(f"height      {info['height_m']:.2f} m (head joint above the feet, rest pose)")
    print(f"rig         {rig.describe()}")
    role_of = {}
    for r, n in skel.roles.items():
        role_of.setdefault(n, []).append(r)
    print("hierarchy (index name  parent  roles)")
    for j, (n, p) in enumerate(zip(skel.names, skel.parents)):
        print(f"  {j:3d} {n:<24s} {int(p):3d}  {', '.join(role_of.get(n, []))}".rstrip())
    return 0


def _convert(args) -> int:
    from .data.sources import open_dataset

    ms = open_dataset(args.input, scale=args.scale)  # metres, like every loader: the unit detected unless --scale
    out = Path(args.output)
    if out.suffix.lower() != ".npz":
        raise ValueError(f"{out}: the output must end in .npz (posekit's commands read .npz motion files)")
    arrays = ms.arrays()
    if ms.n_clips == 1:  # one file: frame_time a number, as before (MotionSet.load reads either)
        arrays["frame_time"] = np.array(float(ms.frame_time[0]))
    np.savez_compressed(out, **arrays, names=np.array(ms.skeleton.names, dtype=str), parents=ms.skeleton.parents,
                        positions=ms.global_pos)
    units = getattr(ms, "units", None)
    print(f"wrote {out}: {ms.n_frames} frames, {ms.n_clips} clip(s), {ms.skeleton.n_joints} joints, positions in metres "
          f"({units.describe() if units else 'as stored'}); every posekit command that takes --data or a path "
          "reads it")
    return 0


def _build_benchmark(args) -> int:
    from .evaluation.effector_cases import BENCHMARKS, build_benchmark, save_benchmark

    for name in BENCHMARKS:
        b = build_benchmark(name, n_cases=args.cases, seed=args.seed)
        path = save_benchmark(b, seed=args.seed)
        print(f"wrote {path}: {len(b)} cases, {b.n.min()}-{b.n.max()} effectors ({', '.join(b.kinds_present())}), "
              f"{path.stat().st_size / 1e3:.0f} kB")
    return 0


def _build_sample(args) -> int:
    from .io.deepmimic import build_arrays
    from .paths import samples_dir

    if getattr(args, "which", "deepmimic") == "bandai":
        from .data.bandai_mini_build import build_bandai_mini

        try:
            r = build_bandai_mini(args.data_dir, out=args.out, workers=args.workers, progress=True)
        except (FileNotFoundError, ValueError) as e:
            print(f"posekit: {e}", file=sys.stderr)
            return 2
        per = ", ".join(f"{s} {r['frames_per_split'][s]} frames / {r['clips_per_split'][s]} clips"
                        for s in ("train", "val", "test"))
        print(f"wrote {r['path']}: {r['frames']} frames, {r['clips']} clips ({per}), "
              f"{r['bytes'] / 1e6:.2f} MB in {r['seconds']:.1f} s; float16 position error "
              f"max {r['float16_pos_err_max'] * 1e3:.2f} mm, mean {r['float16_pos_err_mean'] * 1e3:.3f} mm")
        return 0
    base = args.pybullet_data
    if base is None:
        try:
            import pybullet_data
        except ImportError:
            print("posekit: pybullet is not installed; run `pip install -e .[build-data]` or pass "
                  "--pybullet-data DIR (a folder holding humanoid/ and data/motions/)", file=sys.stderr)
            return 2
        base = pybullet_data.getDataPath()
    arrays = build_arrays(base)
    out = Path(args.out) if args.out else samples_dir() / "deepmimic_humanoid.npz"
    np.savez_compressed(out, **arrays)
    print(f"wrote {out}: {len(arrays['local_rot'])} frames, {len(arrays['clip_names'])} clips, "
          f"{out.stat().st_size / 1e3:.0f} kB")
    return 0


def _bench(args) -> int:
    """``posekit bench NAME``: run a registered benchmark (:mod:`posekit.bench.plugin`), print its
    tables or ``--json``."""
    from .bench.plugin import get_benchmark
    from .bench.report import to_json

    b = get_benchmark(args.benchmark)
    rows = b.run(args)
    print(to_json(rows) if args.json else b.render(rows, args))
    return 0


def _train_list(args) -> int:
    """``posekit train --list`` (and ``posekit train``): every registered trainer and what it makes."""
    from .learn.trainers import get_trainer, trainer_names

    names = trainer_names()
    print("posekit train NAME makes (seeded, reproducible):")
    w = max(12, max(map(len, names)) + 2)
    for name in names:
        t = get_trainer(name)
        print(f"\n  {name:<{w}}{t.what}\n    makes   {t.makes}\n    used by {t.used_by}\n    takes   {t.takes}")
    print("\nposekit train NAME --help shows its options.")
    return 0


def _train(args) -> int:
    """``posekit train NAME``: run a registered trainer (:mod:`posekit.learn.trainers`)."""
    import contextlib
    import os

    from .learn.distributed import launched_world, start
    from .learn.trainers import get_trainer

    if args.list:
        return _train_list(args)
    from .learn.trainers import check_out

    check_out(get_trainer(args.trainer), args)  # a place to write refused before the device, the data, any training
    if launched_world() <= 1:
        with start(args.device):  # the device checked before any data is read
            return get_trainer(args.trainer).run(args)
    # One of torchrun's processes. It leaves with os._exit once its process group is left, without the
    # interpreter's finalization: gloo's worker threads outlive destroy_process_group while a
    # DistributedDataParallel has ever held the group, and one that frees the last collective's work during
    # finalization needs the GIL for that work's Python tensors and aborts the process ("terminate called
    # without an active exception", SIGABRT, after the checkpoint was written: 2 of 58 two-process runs here).
    def joined(args):
        with start(args.device) as run:  # the device checked, the processes joined, before any data is read
            if run.main:
                return get_trainer(args.trainer).run(args)
            with open(os.devnull, "w") as quiet, contextlib.redirect_stdout(quiet):  # one report, rank 0's
                return get_trainer(args.trainer).run(args)

    try:
        rc = _status(joined, args)
    except BaseException:
        import traceback

        traceback.print_exc()
        rc = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(int(rc or 0))


def _warm(args) -> int:
    """``posekit warm``: :func:`posekit.warm.warm`, one line on what it did."""
    from .warm import warm

    r = warm(workers=args.workers, force=args.force)
    if r["cache"] is None:
        print("posekit warm: kernel caching is off (POSEKIT_NUMBA_CACHE, or no numba): nothing to compile ahead")
    elif r["done"]:
        print(f"posekit warm: kernels already compiled in {r['cache']}")
    else:
        print(f"posekit warm: compiled the kernels of {r['solvers']} solvers in {r['seconds']:.0f} s into {r['cache']}")
    for name, why in r["skipped"].items():
        print(f"posekit warm: warning: {name} not compiled ahead: {why}", file=sys.stderr)
    return 0


def build_parser(group: str | None = None) -> argparse.ArgumentParser:
    """The whole command line; with ``group`` (the command's first word), the trainers' subcommands only when it is
    ``train`` or ``docs`` (whose CLI page lists them): they import torch, a second and a half that every other
    command (``posekit course autograde``, run once per lesson by an instructor) would wait for."""
    parser = argparse.ArgumentParser(prog="posekit", description="posekit: data tools and benchmarks")
    sub = parser.add_subparsers(dest="group", required=True)

    data = sub.add_parser("data", help="inspect, convert and build pose data")
    dsub = data.add_subparsers(dest="cmd", required=True)
    p = dsub.add_parser("inspect", help="joints, parents, frames, frame time and clips of a dataset")
    p.add_argument("path", help="BVH file, folder of BVH files, .npz, or sample/bandai1/bandai2")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument("--scale", type=float, default=None,
                   help="file units to metres for BVH (default: detected from the skeleton's height)")
    p.set_defaults(fn=_inspect)
    p = dsub.add_parser("convert", help="BVH file or folder -> one .npz motion file that every posekit command "
                        "reads (data inspect, bench --data, train --data, the studio)",
                        description="Writes the skeleton (skeleton_names, skeleton_parents, skeleton_offsets, "
                        "skeleton_roles), the joint rotations (local_rot, root_pos), global joint positions in "
                        "metres (global_pos, and positions with names and parents for readers that want positions "
                        "only), clip_id, clip_names and frame_time (seconds per frame of each clip).")
    p.add_argument("input", help="a BVH file or a folder of BVH files (one clip per file, one skeleton)")
    p.add_argument("output", help="the .npz to write")
    p.add_argument("--scale", type=float, default=None,
                   help="file units to metres (0.01: cm -> m; default: detected from the skeleton's height)")
    p.set_defaults(fn=_convert)
    p = dsub.add_parser("build-sample", help="rebuild data_samples/deepmimic_humanoid.npz from pybullet "
                        "(default) or data_samples/bandai_mini/bandai_mini.npz from the Bandai Namco datasets")
    p.add_argument("which", nargs="?", default="deepmimic", choices=("deepmimic", "bandai"),
                   help="deepmimic (default): the DeepMimic sample; bandai: the Bandai mini set")
    p.add_argument("--pybullet-data", default=None, help="pybullet_data folder (default: the installed wheel's)")
    p.add_argument("--data-dir", default=None,
                   help="bandai: folder holding bandai-namco-1/ and bandai-namco-2-every4th/ "
                        "(default $POSEKIT_DATA_DIR)")
    p.add_argument("--workers", type=int, default=None, help="bandai: processes reading BVH (default: all CPUs)")
    p.add_argument("--out", default=None)
    p.set_defaults(fn=_build_sample)
    p = dsub.add_parser("build-benchmark", help="rebuild lesson 05's effector benchmarks (5-point and random) "
                        "in data_samples/benchmarks/ from the Bandai mini set's test clips")
    p.add_argument("which", choices=("protores",), help="protores: the 5-point and random benchmarks")
    p.add_argument("--cases", type=int, default=1000, help="cases per benchmark (default: 1000)")
    p.add_argument("--seed", type=int, default=0, help="(default: 0)")
    p.set_defaults(fn=_build_benchmark)

    from .bench.plugin import HelpFormatter, add_arguments, benchmark_names, get_benchmark

    bench = sub.add_parser("bench", help="benchmarks: tables and JSON")
    bsub = bench.add_subparsers(dest="cmd", required=True)
    for name in benchmark_names():  # every registered benchmark plug-in is a subcommand
        b = get_benchmark(name)
        p = bsub.add_parser(name, help=b.help, description=b.help, formatter_class=HelpFormatter)
        add_arguments(p, b)
        p.set_defaults(fn=_bench, benchmark=name)

    train = sub.add_parser("train", help="make the weights the lessons ship (seeded); --list names them")
    train.add_argument("--list", action="store_true", help="list every trainable model, what it makes and which "
                       "lesson loads it (also what `posekit train` alone prints)")
    train.set_defaults(fn=_train_list)
    if group in (None, "train", "docs"):
        from .learn.trainers import get_trainer, trainer_names
        from .plugins import add_arguments

        tsub = train.add_subparsers(dest="cmd", metavar="NAME", help=", ".join(trainer_names()))
        for name in trainer_names():  # every registered trainer is a subcommand
            t = get_trainer(name)
            p = tsub.add_parser(name, help=t.help)
            add_arguments(p, t.args, default_in_help=False)
            p.add_argument("--device", default="cpu", help="where to train: cpu (default), cuda or cuda:N; under "
                           "torchrun every process trains its share of each batch (data-parallel, docs/training.md)")
            p.set_defaults(fn=_train, trainer=name)
    p = sub.add_parser("warm", help="compile every solver's kernels into the cache (make lab, studio and test run it "
                       "first; quick once the cache holds them)")
    p.add_argument("--workers", type=int, default=2, help="processes compiling side by side (default: 2)")
    p.add_argument("--force", action="store_true", help="compile again even when the cache is warm")
    p.set_defaults(fn=_warm)
    from .course.commands import add_commands

    add_commands(sub)
    from .docs import add_commands as add_docs_commands

    add_docs_commands(sub, parser)
    return parser


def _one_line(message, category, filename, lineno, line=None) -> str:
    """A warning as one line a person reads, without the Python source line beneath it."""
    return f"posekit: warning: {message}\n"


def _status(fn, args) -> int:
    """``fn(args)``'s exit status; bad input (a ValueError, a missing or unreadable file) is printed as one line,
    ``posekit: error: ...``, status 2."""
    try:
        return fn(args)
    except (ValueError, FileNotFoundError, OSError) as e:
        print(f"posekit: error: {e}", file=sys.stderr)
        return 2


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    group = next((a for a in argv if not a.startswith("-")), None)  # the top level has no option taking a value
    args = build_parser(group).parse_args(argv)
    shown, warnings.formatwarning = warnings.formatwarning, _one_line  # how a warning is printed, not whether
    try:
        return _status(args.fn, args)
    finally:
        warnings.formatwarning = shown


if __name__ == "__main__":
    sys.exit(main())
