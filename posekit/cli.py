"""The ``posekit`` command line.

``posekit data inspect PATH [--json]``
    A BVH file, a folder of them, a ``.npz`` or a dataset name (``sample``, ``bandai1``, ``bandai2``):
    joints, parents, frame count, frame time, clip count.
``posekit data convert IN.bvh OUT.npz [--scale S]``
    Writes ``names`` (J), ``parents`` (J), ``positions`` (F, J, 3: global joint positions in file
    units times S) and ``frame_time``.
``posekit data build-sample [--pybullet-data DIR] [--out FILE]``
    Rebuilds ``data_samples/deepmimic_humanoid.npz`` from pybullet's wheel (extra ``build-data``).
``posekit bench fk [--json]``
    FK throughput and load time, side by side with the baseline and the goal.
``posekit bench ik [--solvers fabrik,ccd,dls] [--effectors 2,5] [--data sample|bandai1|PATH] [--json]``
    Every IK solver on the same held-out real poses: latency, memory, effector/pose/bone errors.
``posekit bench invrig [--json]``
    Inverse rig mapping: joint and ground-truth errors and frames/s of every method (lesson 02).
``posekit train invrig``
    Makes the inverse-rig network weights shipped in ``data_samples/weights`` (seeded).

Errors in input files print ``file:line: message`` and exit with status 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np


def _inspect(args) -> int:
    from .data.sources import open_dataset

    ms = open_dataset(args.path, scale=args.scale, progress=not args.json and sys.stderr.isatty())
    skel = ms.skeleton
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
    print("hierarchy (index name  parent)")
    for j, (n, p) in enumerate(zip(skel.names, skel.parents)):
        print(f"  {j:3d} {n:<24s} {int(p):3d}")
    return 0


def _convert(args) -> int:
    from .io.bvh import read_bvh

    m = read_bvh(args.input)
    positions = m.global_positions() * args.scale
    out = Path(args.output)
    np.savez_compressed(
        out,
        names=np.array(m.skeleton.names, dtype=str),
        parents=m.skeleton.parents,
        positions=positions,
        frame_time=np.array(m.frame_time),
    )
    print(f"wrote {out}: {positions.shape[0]} frames, {positions.shape[1]} joints, positions x {args.scale:g}")
    return 0


def _build_sample(args) -> int:
    from .io.deepmimic import build_arrays
    from .paths import samples_dir

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


def _bench_fk(args) -> int:
    from .bench import fk as bench_fk
    from .bench.report import format_table, to_json

    rows = bench_fk.run(n_poses=args.poses, repeats=args.repeats)
    if args.json:
        print(to_json(rows))
    else:
        print("Forward kinematics, one thread (best of repeats)")
        print(format_table([r for r in rows if "poses_per_s" in r],
                           ["method", "joints", "poses", "poses_per_s", "goal_poses_per_s"]))
        print()
        print(format_table([r for r in rows if "seconds" in r], ["method", "poses", "seconds", "goal_seconds"]))
    return 0


def _bench_ik(args) -> int:
    from .bench import ik as bench_ik
    from .bench.report import format_table, to_json
    from .data.sources import open_dataset

    motions = open_dataset(args.data, scale=args.scale, progress=not args.json and sys.stderr.isatty())
    rows = bench_ik.run(motions, solvers=args.solvers.split(","), effector_sets=args.effectors.split(","),
                        n_cases=args.cases, start=args.start, seed=args.seed, peers=not args.no_peers,
                        progress=not args.json and sys.stderr.isatty())
    if args.json:
        print(to_json(rows))
        return 0
    print(f"IK benchmark: {rows[0]['data']}, {args.cases} held-out cases, start = {args.start}, one thread")
    print("(latency and memory of one solve; errors in mm; converged = every effector within 1 mm)")
    cols = [c for c in bench_ik.TABLE_COLUMNS if any(c in r for r in rows)]
    print(format_table([r for r in rows if "note" not in r], cols))
    for r in rows:
        if "note" in r:
            print(f"note: {r['method']}: {r['note']}")
    return 0


def _bench_invrig(args) -> int:
    from .bench import invrig
    from .bench.report import format_table, to_json

    rows = invrig.run(seed=args.seed, budget=args.budget, weights=args.weights)
    if args.json:
        print(to_json(rows))
        return 0
    setup = rows[-1]
    print(f"Inverse rig mapping on the held-out test clips ({rows[0]['frames']} frames), one thread; "
          f"GPR: multiquadric, theta0 = {setup['theta0']:.3g}, {setup['gpr_budget']} subsampled poses, "
          f"fitted in {setup['fit_s']:.1f} s")
    print("joint error: cm; ground-truth error: control error in training standard deviations")
    print("\nTable 1 (paper: {}-{} frames/s with Maya in the loop)".format(*setup["paper_frames_per_s"]))
    print(format_table([r for r in rows if r["table"] == 1],
                       ["method", "joint_error", "ground_truth_error", "total_s", "frames_per_s", "clamped_values"]))
    print("\nTable 2: the network by supersampling method")
    print(format_table([r for r in rows if r["table"] == 2],
                       ["method", "joint_error", "ground_truth_error", "joint_error_with_jacobian"]))
    print("\nDrift (Fig. 11): three 1,000-frame test clips solved frame by frame")
    print(format_table([r for r in rows if r["table"] == 3],
                       ["method", "joint_error_first_200", "joint_error_last_200", "ground_truth_error_first_200",
                        "ground_truth_error_last_200", "frames_per_s"]))
    return 0


def _train_invrig(args) -> int:
    from .regression.train import train_all

    paths = train_all(methods=args.methods.split(","), samples=args.samples, epochs=args.epochs, seed=args.seed,
                      out=args.out, progress=sys.stderr.isatty())
    for m, p in paths.items():
        print(f"wrote {p} ({p.stat().st_size / 1e3:.0f} kB)")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="posekit", description="posekit: data tools and benchmarks")
    sub = parser.add_subparsers(dest="group", required=True)

    data = sub.add_parser("data", help="inspect, convert and build pose data")
    dsub = data.add_subparsers(dest="cmd", required=True)
    p = dsub.add_parser("inspect", help="joints, parents, frames, frame time and clips of a dataset")
    p.add_argument("path", help="BVH file, folder of BVH files, .npz, or sample/bandai1/bandai2")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument("--scale", type=float, default=None, help="file units to metres for BVH (default 1)")
    p.set_defaults(fn=_inspect)
    p = dsub.add_parser("convert", help="BVH -> .npz of global joint positions")
    p.add_argument("input")
    p.add_argument("output")
    p.add_argument("--scale", type=float, default=1.0, help="multiply positions by S (0.01: cm -> m)")
    p.set_defaults(fn=_convert)
    p = dsub.add_parser("build-sample", help="rebuild data_samples/deepmimic_humanoid.npz from pybullet")
    p.add_argument("--pybullet-data", default=None, help="pybullet_data folder (default: the installed wheel's)")
    p.add_argument("--out", default=None)
    p.set_defaults(fn=_build_sample)

    bench = sub.add_parser("bench", help="benchmarks: tables and JSON")
    bsub = bench.add_subparsers(dest="cmd", required=True)
    p = bsub.add_parser("fk", help="forward-kinematics throughput against the baseline and the goal")
    p.add_argument("--json", action="store_true")
    p.add_argument("--poses", type=int, default=20_000)
    p.add_argument("--repeats", type=int, default=5)
    p.set_defaults(fn=_bench_fk)
    p = bsub.add_parser("ik", help="IK solvers on held-out real poses, side by side (Victor & Meyer Table 1 style)")
    p.add_argument("--solvers", default="fabrik,ccd,dls", help="comma-separated: fabrik, fabrik-constrained, ccd, dls")
    p.add_argument("--effectors", default="2,5", help="comma-separated effector sets: 2, 5, 5point")
    p.add_argument("--cases", type=int, default=1000)
    p.add_argument("--start", choices=["frame", "rest"], default="frame")
    p.add_argument("--data", default="sample", help="sample, bandai1, bandai2, or a BVH file/folder")
    p.add_argument("--scale", type=float, default=None, help="file units to metres for a BVH path")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--no-peers", action="store_true", help="skip ikpy")
    p.add_argument("--json", action="store_true")
    p.set_defaults(fn=_bench_ik)
    p = bsub.add_parser("invrig", help="inverse rig mapping: Tables 1 and 2 of Holden et al. 2017 on our rig")
    p.add_argument("--json", action="store_true")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--budget", type=int, default=500, help="GPR training poses after greedy subsampling")
    p.add_argument("--weights", default=None, help="folder of invrig_nn_*.pt (default data_samples/weights)")
    p.set_defaults(fn=_bench_invrig)

    train = sub.add_parser("train", help="make the weights the lessons ship (seeded)")
    tsub = train.add_subparsers(dest="cmd", required=True)
    p = tsub.add_parser("invrig", help="inverse-rig networks, one per supersampling method (lesson 02)")
    p.add_argument("--methods", default="uniform,gaussian,mvn,gmm,pca")
    p.add_argument("--samples", type=int, default=20_000)
    p.add_argument("--epochs", type=int, default=20)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default=None, help="folder (default data_samples/weights)")
    p.set_defaults(fn=_train_invrig)
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.fn(args)
    except (ValueError, FileNotFoundError, OSError) as e:
        print(f"posekit: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
