"""The ``posekit`` command line.

``posekit data inspect PATH [--json]``
    A BVH file, a folder of them, a ``.npz`` or a dataset name (``sample``, ``bandai1``, ``bandai2``):
    joints, parents, frame count, frame time, clip count.
``posekit data convert IN.bvh OUT.npz [--scale S]``
    Writes ``names`` (J), ``parents`` (J), ``positions`` (F, J, 3: global joint positions in file
    units times S) and ``frame_time``.
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
``posekit train --list``
    Every trainable model: the files it makes, the lesson that loads them, about how long it takes.
``posekit train invrig [--methods M,...] [--samples N] [--epochs E] [--seed S] [--out DIR]``
    Makes the inverse-rig network weights shipped in ``data_samples/weights`` (seeded).
``posekit train ae-solvers [--seed S] [--out FILE] [--ae-epochs N] ...``
    Makes lesson 03's autoencoder and latent-space solvers, ``data_samples/weights/ae_solvers.pt``.
``posekit train aegan [--seed S] [--out FILE] [--steps N] [--dense] ...``
    Makes lesson 04's AE-GAN (encoder, generator, two discriminators), ``data_samples/weights/aegan.pt``.
``posekit data build-benchmark protores [--cases N] [--seed S]``
    Rebuilds lesson 05's 5-point and random effector benchmarks in ``data_samples/benchmarks/``.
``posekit train protores [--arch protores|masked-fcr|transformer] [--no-gpd] [--fixed-weights] ...``
    Makes lesson 05's ProtoRes (or a baseline), ``data_samples/weights/protores*.pt``.

``posekit exercises list|solutions ...`` and ``posekit course slides|build|mark ...``
    The instructor kit (:mod:`posekit.course.commands`): solutions, slides, the course page.

Errors in input files print ``file:line: message`` and exit with status 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np


def _inspect(args) -> int:
    from .data.rigs import rig_report, standing_height
    from .data.sources import open_dataset

    ms = open_dataset(args.path, scale=args.scale, progress=not args.json and sys.stderr.isatty())
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


def _build_benchmark(args) -> int:
    from .bench.effector_cases import BENCHMARKS, build_benchmark, save_benchmark

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
        from .data.bandai_mini import build_bandai_mini

        try:
            r = build_bandai_mini(args.data_dir, out=args.out, workers=args.workers, progress=sys.stderr.isatty())
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


# every model `posekit train` makes: name -> (what it writes, which lesson loads it, about how long)
_TRAINABLE = {
    "invrig": ("data_samples/weights/invrig_nn_{uniform,gaussian,mvn,gmm,pca}.pt",
               "inverse-rig networks, one per supersampling method (Holden et al. 2017)",
               "lesson 02 (02_inverse_rig_mapping.ipynb) and posekit bench invrig",
               "about 40 s on 2 idle cores (8 s per method)"),
    "ae-solvers": ("data_samples/weights/ae_solvers.pt (CC BY-NC 4.0, like the Bandai mini set it is trained on)",
                   "pose autoencoder + latent-space solvers hands, feet, head, all five, chaining-aware copies "
                   "(Victor & Meyer 2020)",
                   "lesson 03 (03_autoencoder_solvers.ipynb), the neural solvers, posekit bench ik",
                   "about 7 minutes on one core (it trains on one thread: 7 min 13 s measured)"),
    "ae-studies": ("data_samples/weights/ae_solvers_studies.json",
                   "lesson 03's measured choices: autoencoder size and decoder, the loss weight k, chaining",
                   "lesson 03 (03_autoencoder_solvers.ipynb)", "about 9 minutes on one core (9 min 22 s measured)"),
    "aegan": ("data_samples/weights/aegan.pt (CC BY-NC 4.0, like the Bandai mini set it is trained on)",
              "AE-GAN pose latent space with structured prediction layers (Victor & Meyer, JFIG 2020)",
              "lesson 04 (04_aegan_latent_space.ipynb), the latent-opt solvers, posekit bench ik",
              "about 9-11 minutes on one core (it trains on one thread: 8 min 35 s measured idle, 11 min "
              "beside another training)"),
    "protores": ("data_samples/weights/protores.pt, protores_masked_fcr.pt, protores_transformer.pt (CC BY-NC 4.0, "
                 "like the Bandai mini set they are trained on); one per --arch",
                 "ProtoRes and its Masked-FCR and Transformer baselines (Oreshkin et al. 2021)",
                 "lesson 05 (05_protores.ipynb), the protores solvers, posekit bench protores",
                 "about 11-12 minutes each on one core (it trains on one thread)"),
    "protores-studies": ("data_samples/results/protores_ablation.json",
                         "lesson 05's Table 2 ablations (no GPD, fixed weights) and the width study",
                         "lesson 05 (05_protores.ipynb), posekit bench protores",
                         "about 15 minutes on 2 cores (five 2,000-step runs, two side by side)"),
}


def _train_list(args) -> int:
    """``posekit train --list`` (and ``posekit train``): every trainable model and what it makes."""
    print("posekit train NAME makes (seeded, reproducible):")
    w = max(12, max(map(len, _TRAINABLE)) + 2)
    for name, (files, what, lesson, time) in _TRAINABLE.items():
        print(f"\n  {name:<{w}}{what}\n    makes   {files}\n    used by {lesson}\n    takes   {time}")
    print("\nposekit train NAME --help shows its options.")
    return 0


def _train_invrig(args) -> int:
    from .invrig.train import train_all

    if args.list:
        return _train_list(args)

    paths = train_all(methods=args.methods.split(","), samples=args.samples, epochs=args.epochs, seed=args.seed,
                      out=args.out, progress=sys.stderr.isatty())
    for m, p in paths.items():
        print(f"wrote {p} ({p.stat().st_size / 1e3:.0f} kB)")
    return 0


def _train_ae_solvers(args) -> int:
    from .data.sources import open_dataset
    from .models.pose_autoencoder.train import DEFAULTS, train_ae_solvers

    settings = {k: getattr(args, k) for k in DEFAULTS if getattr(args, k) != DEFAULTS[k]}
    motions = open_dataset(args.data, progress=sys.stderr.isatty())
    out = Path(args.out) if args.out else None
    from .learn.threads import single_thread

    with single_thread():  # these small layers gain little from a second thread, and one thread repeats exactly
        model, report = train_ae_solvers(motions, seed=args.seed, out=out, tied=args.tied, latent=args.latent,
                                         progress=sys.stderr.isatty(), **settings)
    from .models.pose_autoencoder.train import weights_path

    path = out or weights_path()
    sec = report["seconds"]
    print(f"trained in {sec['total']:.0f} s (" + ", ".join(f"{k} {v:.0f} s" for k, v in sec.items() if k != "total")
          + ")")
    print(f"autoencoder validation MSE {report['autoencoder']['val'][-1]:.5f} (z-scored units); solvers: "
          + ", ".join(f"{g} {c['val'][-1]:.5f}" for g, c in report["solvers"].items()))
    print(f"wrote {path} ({path.stat().st_size / 1e3:.0f} kB)")
    return 0


def _train_ae_studies(args) -> int:
    from .models.pose_autoencoder.studies import run_studies, studies_path

    from .learn.threads import single_thread

    out = Path(args.out) if args.out else studies_path()
    with single_thread():
        res = run_studies(seed=args.seed, out=out, progress=sys.stderr.isatty(), ae_epochs=args.ae_epochs)
    for r in res["autoencoder"]:
        print(f"autoencoder d={r['latent']:<3} {r['decoder']:<7} held-out reconstruction {r['test_mm']:.1f} mm")
    print(f"wrote {out} in {res['seconds']:.0f} s")
    return 0


def _train_aegan(args) -> int:
    from .data.sources import open_dataset
    from .models.aegan.networks import AEGANConfig
    from .models.aegan.train import DEFAULTS, train_aegan, weights_path

    settings = {k: getattr(args, k) for k in DEFAULTS if getattr(args, k) != DEFAULTS[k]}
    motions = open_dataset(args.data, progress=sys.stderr.isatty())
    out = Path(args.out) if args.out else None
    from .data.metrics import body_joints

    config = AEGANConfig(len(body_joints(motions.skeleton)), structured=not args.dense)
    model, report = train_aegan(motions, seed=args.seed, out=out, config=config, progress=sys.stderr.isatty(),
                                **settings)
    path = out or weights_path()
    c = report["curves"]
    print(f"trained {report['steps']} steps in {report['seconds']:.0f} s; held-out reconstruction "
          f"{report['val_rec_mm']:.1f} mm; last interval: pose discriminator accuracy {c['acc_x'][-1]:.2f}, "
          f"latent discriminator accuracy {c['acc_z'][-1]:.2f}")
    print(f"wrote {path} ({path.stat().st_size / 1e3:.0f} kB)")
    return 0


def _train_protores(args) -> int:
    from .data.metrics import body_joints
    from .data.bandai_mini import load_bandai_mini
    from .models.protores.networks import ProtoResConfig
    from .models.protores.train import DEFAULTS, train_protores, weights_path

    settings = {k: getattr(args, k) for k in DEFAULTS if hasattr(args, k) and getattr(args, k) != DEFAULTS[k]}
    if args.fixed_weights:
        settings["weighted"] = False
    motions = load_bandai_mini()
    config = ProtoResConfig(len(body_joints(motions.skeleton)), arch=args.arch, width=args.width, gpd=not args.no_gpd)
    out = Path(args.out) if args.out else None
    net, report = train_protores(motions, arch=args.arch, seed=args.seed, out=out, config=config,
                                 progress=sys.stderr.isatty(), **settings)
    v = report["val"]
    print(f"trained {args.arch} ({report['parameters']} parameters) {report['steps']} steps in "
          f"{report['seconds']:.0f} s ({report['seconds_per_step'] * 1000:.0f} ms/step); validation: L_ikd-L2 "
          f"{v['ikd_l2'] * 1000:.2f}e-3 m^2, L_loc-geo {v['loc_geo']:.3f} rad, MPJPE {v['mpjpe_mm']:.1f} mm")
    path = out or weights_path(args.arch)
    print(f"wrote {path} ({path.stat().st_size / 1e3:.0f} kB)")
    return 0


def _train_protores_studies(args) -> int:
    from .models.protores.studies import run_studies, studies_path

    out = Path(args.out) if args.out else studies_path()
    res = run_studies(seed=args.seed, out=out, workers=args.workers, progress=sys.stderr.isatty())
    for r in res["rows"] + res["width"]:
        print(f"{r['method']:<28} random L_ikd-L2 {r['random_ikd_l2_e3']:.3f}e-3 m^2, "
              f"L_loc-geo {r['random_loc_geo']:.3f}; "
              f"5-point {r['5point_ikd_l2_e3']:.3f}e-3, {r['5point_loc_geo']:.3f}; {r['train_min']} min")
    print(f"wrote {out} in {res['seconds']} s")
    return 0


def build_parser() -> argparse.ArgumentParser:
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
    p = dsub.add_parser("convert", help="BVH -> .npz of global joint positions")
    p.add_argument("input")
    p.add_argument("output")
    p.add_argument("--scale", type=float, default=1.0, help="multiply positions by S (0.01: cm -> m)")
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
    tsub = train.add_subparsers(dest="cmd", metavar="NAME", help=", ".join(_TRAINABLE))
    p = tsub.add_parser("invrig", help="inverse-rig networks, one per supersampling method (lesson 02)")
    p.add_argument("--methods", default="uniform,gaussian,mvn,gmm,pca",
                   help="comma-separated supersampling methods (default: uniform,gaussian,mvn,gmm,pca)")
    p.add_argument("--samples", type=int, default=20_000, help="training samples per method (default: 20000)")
    p.add_argument("--epochs", type=int, default=20, help="(default: 20)")
    p.add_argument("--seed", type=int, default=0, help="(default: 0)")
    p.add_argument("--out", default=None, help="folder (default data_samples/weights)")
    p.set_defaults(fn=_train_invrig)
    from .models.pose_autoencoder.train import DEFAULTS as AE

    p = tsub.add_parser("ae-solvers", help="pose autoencoder + latent-space solvers (lesson 03, Victor & Meyer 2020)")
    p.add_argument("--data", default="bandai-mini", help="training data: bandai-mini (default, its own split), "
                   "or any posekit data set name / path (split by clip)")
    for key, what in (("ae_epochs", "autoencoder epochs"), ("ae_lr", "autoencoder learning rate (Adam)"),
                      ("solver_epochs", "epochs per solver"), ("solver_lr", "solver learning rate (Adam)"),
                      ("chain_epochs", "epochs of each chaining-aware fine-tuning"),
                      ("pairs", "training (start, target) pairs, at most 1 s apart"), ("batch", "mini-batch size"),
                      ("k", "weight of the non-target joints in the solver loss, Eq. (1)")):
        p.add_argument("--" + key.replace("_", "-"), dest=key, type=type(AE[key]), default=AE[key],
                       help=f"{what} (default: {AE[key]})")
    p.add_argument("--latent", type=int, default=64, help="size d of the latent code (default: 64)")
    p.add_argument("--tied", action="store_true", help="the decoder reuses the transposed encoder weights, no biases, "
                   "as in the authors' code (default: untied, its own weights and biases: measured better in "
                   "lesson 03)")
    p.add_argument("--seed", type=int, default=0, help="(default: 0)")
    p.add_argument("--out", default=None, help="checkpoint file (default data_samples/weights/ae_solvers.pt)")
    p.set_defaults(fn=_train_ae_solvers)
    p = tsub.add_parser("ae-studies",
                        help="lesson 03's studies on the shipped autoencoder (d, tied/untied, k, chaining)")
    p.add_argument("--ae-epochs", type=int, default=40,
                   help="epochs of each autoencoder of the size study (default: 40)")
    p.add_argument("--seed", type=int, default=0, help="(default: 0)")
    p.add_argument("--out", default=None, help="JSON file (default data_samples/weights/ae_solvers_studies.json)")
    p.set_defaults(fn=_train_ae_studies)
    from .models.aegan.train import DEFAULTS as GAN

    p = tsub.add_parser("aegan", help="AE-GAN pose latent space with SPL layers (lesson 04, Victor & Meyer, JFIG 2020)")
    p.add_argument("--data", default="bandai-mini", help="training data: bandai-mini (default, its own split), "
                   "or any posekit data set name / path (split by clip)")
    for key, what in (("steps", "training steps"), ("batch", "pose discriminator samples per step (encoder/"
                      "generator see 2x, the latent discriminator 3x)"),
                      ("lr_dx", "pose discriminator learning rate (Adam)"), ("lr", "the other networks' learning rate"),
                      ("w_x", "weight of the pose reconstruction loss"), ("w_z", "weight of the code reconstruction "
                      "loss"), ("smooth", "label of real samples (one-sided label smoothing)"),
                      ("beta1", "Adam beta1"), ("log_every", "steps per point of the loss curves")):
        p.add_argument("--" + key.replace("_", "-"), dest=key, type=type(GAN[key]), default=GAN[key],
                       help=f"{what} (default: {GAN[key]})")
    p.add_argument("--dense", action="store_true", help="dense layers of equal width instead of SPLs (a comparison)")
    p.add_argument("--seed", type=int, default=0, help="(default: 0)")
    p.add_argument("--out", default=None, help="checkpoint file (default data_samples/weights/aegan.pt)")
    p.set_defaults(fn=_train_aegan)
    from .models.protores.networks import ARCHS
    from .models.protores.train import DEFAULTS as PR, STEPS

    p = tsub.add_parser("protores", help="ProtoRes or one of its baselines: effectors -> pose (lesson 05, Oreshkin "
                        "et al. 2021)")
    p.add_argument("--arch", choices=ARCHS, default="protores",
                   help="encoder: protores (default), masked-fcr or transformer (the paper's baselines)")
    p.add_argument("--steps", type=int, default=None,
                   help="training steps (default: " + ", ".join(f"{k} {v}" for k, v in STEPS.items()) + ")")
    for key, what in (("batch", "poses per step"), ("lr", "learning rate (Adam)"), ("warmup", "warm-up steps"),
                      ("w_pos", "W_pos, weight of the two position losses"), ("w_max", "W_M, largest effector weight"),
                      ("log_every", "steps per point of the curves")):
        p.add_argument("--" + key.replace("_", "-"), dest=key, type=type(PR[key]), default=PR[key],
                       help=f"{what} (default: {PR[key]})")
    p.add_argument("--width", type=int, default=128, help="units per layer (default: 128; the paper: 1024)")
    p.add_argument("--no-gpd", action="store_true", help="no global position decoder (Table 2's ablation)")
    p.add_argument("--fixed-weights", action="store_true",
                   help="every joint weighted 1 instead of the randomized min(W_M, 1/sigma) (Table 2's ablation)")
    p.add_argument("--seed", type=int, default=0, help="(default: 0)")
    p.add_argument("--out", default=None, help="checkpoint file (default data_samples/weights/protores*.pt)")
    p.set_defaults(fn=_train_protores)
    p = tsub.add_parser("protores-studies", help="lesson 05's ablations (no GPD, fixed weights) and width study")
    p.add_argument("--workers", type=int, default=2, help="runs side by side, one thread each (default: 2)")
    p.add_argument("--seed", type=int, default=0, help="(default: 0)")
    p.add_argument("--out", default=None, help="JSON file (default data_samples/results/protores_ablation.json)")
    p.set_defaults(fn=_train_protores_studies)
    from .course.commands import add_commands

    add_commands(sub)
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
