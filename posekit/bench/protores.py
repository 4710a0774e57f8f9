"""``posekit bench protores``: ProtoRes's Tables 1 and 2 at CPU scale (Oreshkin et al. 2022), speed, training time.

Introduced in ``notebooks/05_protores.ipynb``. One run scores every method on the shipped 5-point and
random benchmarks (:mod:`posekit.evaluation.effector_cases`) with one metric code
(:mod:`posekit.evaluation.effector_scores`):

* **Table 1** — ProtoRes, Masked-FCR, Transformer (each its shipped weights) and the classical stand-ins
  for FinalIK: FABRIK and DLS from the fitted rest pose;
* **claims** — the paper's orderings, each checked on this run's numbers (True/False);
* **tolerance** — ProtoRes on the random benchmark with every effector's ``Lambda`` set to one value:
  a looser tolerance should give larger effector errors;
* **speed against the roofline** (:mod:`posekit.bench.roofline`), per network, all on one thread: its
  multiply-adds per 5-point pose (from the layer sizes and the effector count), the machine's float32 GEMM
  rate measured on the network's own matrix shapes for a batch of 1,000 poses, the ideal poses per second
  that implies, the measured poses per second of the network's pass on that batch and its fraction of the
  ideal (goal: at least half), and one pose through ``solve`` as the median of every round (goal for
  ProtoRes: 1 ms; the paper reports about 10 ms, 100 FPS, in Unity); and one pose's products at the paper's
  width (1,024), timed on random weights of its shapes;
* **training** — each shipped model's size, steps, minutes and validation error (from its checkpoint);
* **Table 2** — the ablations (no GPD; every joint weighted 1) and their 2,000-step reference, stored in
  ``data_samples/results/protores_ablation.json`` (written by ``posekit train protores-studies``), under
  the shipped ProtoRes as measured in this run.
"""

from __future__ import annotations

import json
import time

import numpy as np

from .plugin import arg, register_benchmark

__all__ = ["run", "GOAL_MS", "GOAL_FRACTION", "PAPER_MS", "ABLATION_FILE", "LEARNED", "RESULTS_FILE", "write_results"]

GOAL_MS = 1.0
"""ProtoRes (the shipped width 256): one 5-point pose through ``solve`` on one thread, median ms."""
GOAL_FRACTION = 0.5
"""Every network: batched poses per second on one thread at least this share of the ideal (the roofline)."""
PAPER_MS = 10.0
"""About 100 FPS for one pose in Unity (the paper's Sec. 5)."""

BATCH = 1000
"""Poses per batch of the throughput rows (whatever ``--cases`` says)."""
ROUNDS_ONE = 300
"""Timed single-pose solves; the row reports their median (every round, not the fastest)."""
ROUNDS_BATCH = 7
"""Timed batched passes (and GEMM rounds); the row reports their median."""
ROUNDS_PAPER = 31
"""Timed rounds of one pose's products at the paper's width (about 10 ms each); the row reports their median."""
RESULTS_FILE = "bench_protores.json"
"""The shipped speed results (``posekit bench protores --speed-only --out data_samples/results/...``)."""

ABLATION_FILE = "protores_ablation.json"
LEARNED = ("protores", "masked-fcr", "transformer")


def _label(arch: str) -> str:
    return {"protores": "ProtoRes", "masked-fcr": "Masked-FCR", "transformer": "Transformer"}[arch]


def _accuracy_row(bench_name, method, sc, seconds, n) -> dict:
    e3 = lambda v: None if v is None else round(v * 1000, 3)  # noqa: E731
    r2 = lambda v: None if v is None else round(v, 2)  # noqa: E731
    return {"table": 1, "benchmark": bench_name, "method": method, "ikd_l2_e3": e3(sc["ikd_l2"]),
            "gpd_l2_e3": e3(sc["gpd_l2"]), "loc_geo": round(sc["loc_geo"], 4), "mpjpe_mm": round(sc["mpjpe_mm"], 1),
            "pos_mm": r2(sc["pos_mm"]), "rot_deg": r2(sc["rot_deg"]), "look_deg": r2(sc["look_deg"]),
            "ms_per_case": round(seconds / n * 1000, 3)}


def _claims(rows) -> list[dict]:
    t1 = {(r["benchmark"], r["method"]): r for r in rows if r.get("table") == 1}
    out = []
    learned = [m for m in map(_label, LEARNED) if ("random", m) in t1]
    for metric in ("ikd_l2_e3", "loc_geo"):
        if len(learned) == 3:
            best = min(learned, key=lambda m: (t1[("random", m)][metric], m))
            out.append({"table": "claims", "claim": f"random benchmark: ProtoRes best learned model on {metric}",
                        "holds": best == "ProtoRes", "detail": f"best: {best}"})
        for m in learned:
            if ("5point", m) in t1 and ("5point", "FABRIK") in t1 and ("5point", "DLS") in t1:
                v, f, d = t1[("5point", m)][metric], t1[("5point", "FABRIK")][metric], t1[("5point", "DLS")][metric]
                out.append({"table": "claims", "claim": f"5-point: {m} below FABRIK and DLS on {metric}",
                            "holds": bool(v < f and v < d), "detail": f"{v} vs {f}, {d}"})
    return out


def _net_pass(solver, batch):
    """A function timing one pass of the network alone on a batch (torch, no wrapper: no checks, float32 FK
    only): returns seconds."""
    import torch

    t = [torch.as_tensor(solver._body_lookup[batch[0]]), torch.as_tensor(batch[1]),
         torch.as_tensor(batch[2], dtype=torch.float32), torch.as_tensor(batch[3], dtype=torch.float32)]

    from .roofline import CLOCK

    def timed() -> float:
        with torch.no_grad():
            start = CLOCK()
            solver.net(*t)
            return CLOCK() - start

    return timed


def _speed_rows(solvers, five) -> list[dict]:
    """One row per network: its arithmetic, the machine's GEMM rate on its shapes, the roofline and the
    measured speeds, all on one thread (:mod:`posekit.bench.roofline`). Products and passes alternate round
    by round, so that on a shared machine both medians see the same load; every time is the thread's CPU time
    (:data:`posekit.bench.roofline.CLOCK`), not the wall clock, which also counts other work's turns."""
    from ..learn.threads import limit_threads
    from .roofline import CLOCK, gemm_rate, gemm_shapes, macs_per_pose, weight_bytes

    rows = []
    effs = five.effectors(0)
    n = BATCH
    for arch, solver in solvers.items():
        cfg = solver.net.config
        args = solver.arrays(solver.resolve(effs))
        n_eff = int(len(args[0]))
        macs = macs_per_pose(cfg, n_eff)
        batch = tuple(a[None].repeat(n, 0) for a in args)
        with limit_threads(1):
            big = gemm_rate(gemm_shapes(cfg, n_eff, n), rounds=ROUNDS_BATCH, between=_net_pass(solver, batch))

            def one_solve() -> float:
                t = CLOCK()
                solver.solve(None, effs)
                return CLOCK() - t

            one = gemm_rate(gemm_shapes(cfg, n_eff, 1), rounds=ROUNDS_ONE, between=one_solve)
        rate = big["macs_per_s"]
        ideal = rate / macs
        measured = n / big["between_median"]
        ms = round(one["between_median"] * 1000, 3)  # judged as shown
        single_goal = arch == "protores"
        rows.append({"table": "speed", "method": _label(arch), "width": cfg.width, "effectors": n_eff,
                     "macs_per_pose": macs, "weights_mb": round(weight_bytes(cfg, n_eff) / 1e6, 1),
                     "gemm_gmacs": round(rate / 1e9, 1), "ideal_poses_per_s": round(ideal),
                     "poses_per_s": round(measured), "fraction_of_ideal": round(measured / ideal, 3),
                     "goal_fraction": GOAL_FRACTION, "fraction_met": bool(round(measured / ideal, 3) >= GOAL_FRACTION),
                     "ms_products_one": round(one["seconds_median"] * 1000, 3),
                     "gemm_gmacs_one": round(one["macs_per_s"] / 1e9, 2),
                     "ms_solve_median": ms, "goal_ms": GOAL_MS if single_goal else None,
                     "ms_met": bool(ms <= GOAL_MS) if single_goal else None, "paper_ms": PAPER_MS})
    rows.append(_paper_width_row(solvers["protores"].net.config, n_eff))
    return rows


PAPER_WIDTH = 1024
"""The paper's ProtoRes width (its Appendix: 1,024 units per layer)."""


def _paper_width_row(config, n_eff: int) -> dict:
    """One pose's products at the paper's width, measured: ProtoRes's matrix shapes at :data:`PAPER_WIDTH` for
    ``n_eff`` effectors (our skeleton's joints), random float32 weights of those shapes (no such network is
    trained here), one thread, the median of every round. Its weights do not stay in the caches as ours do, so
    the rate of our width's products does not transfer to it: this row times it."""
    from dataclasses import replace

    from ..learn.threads import limit_threads
    from .roofline import gemm_rate, gemm_shapes, macs_per_pose, weight_bytes

    cfg = replace(config, width=PAPER_WIDTH)
    with limit_threads(1):
        one = gemm_rate(gemm_shapes(cfg, n_eff, 1), rounds=ROUNDS_PAPER)
    return {"table": "speed-paper", "method": f"ProtoRes at the paper's width ({PAPER_WIDTH})", "width": PAPER_WIDTH,
            "effectors": n_eff, "macs_per_pose": macs_per_pose(cfg, n_eff),
            "weights_mb": round(weight_bytes(cfg, n_eff) / 1e6, 1),
            "ms_products_one": round(one["seconds_median"] * 1000, 3),
            "gemm_gmacs_one": round(one["macs_per_s"] / 1e9, 2), "paper_ms": PAPER_MS}


def _training_rows(solvers) -> list[dict]:
    from ..models.protores.networks import weights_path

    rows = []
    for arch, solver in solvers.items():
        rep = solver.net.checkpoint["extra"].get("report", {})
        path = weights_path(arch)
        rows.append({"table": "training", "method": _label(arch), "parameters": solver.net.n_parameters(),
                     "kB": round(path.stat().st_size / 1024) if path.is_file() else None,
                     "steps": rep.get("steps"), "processes": rep.get("processes", 1),
                     "train_min": round(rep.get("train_seconds", np.nan) / 60, 1),
                     "ms_per_step": round(rep.get("seconds_per_step", np.nan) * 1000),
                     "val_mpjpe_mm": round(rep.get("val", {}).get("mpjpe_mm", np.nan), 1)})
    return rows


def _ablation_rows(rows, training) -> list[dict]:
    """Table 2: the shipped ProtoRes as measured in this run, then the stored 2,000-step runs."""
    from ..paths import samples_dir

    t1 = {(r["benchmark"], r["method"]): r for r in rows if r.get("table") == 1}
    out = []
    if ("random", "ProtoRes") in t1 and ("5point", "ProtoRes") in t1:
        tr = next((r for r in training if r["method"] == "ProtoRes"), {})
        out.append({"table": 2, "method": f"ProtoRes (shipped, {tr.get('steps')} steps)",
                    **{f"{b}_{k}": t1[(b, "ProtoRes")][k] for b in ("random", "5point")
                       for k in ("ikd_l2_e3", "loc_geo")},
                    "train_min": tr.get("train_min")})
    path = samples_dir() / "results" / ABLATION_FILE
    if not path.is_file():
        return out + [{"table": 2, "method": "(no stored ablations: run `posekit train protores-studies`)"}]
    res = json.loads(path.read_text())
    return out + [{"table": 2, **r} for r in res["rows"] if not r["method"].startswith("ProtoRes (shipped")]


def run(cases: int | None = None, classical: bool = True, speed: bool = True, progress: bool = False,
        speed_only: bool = False) -> list[dict]:
    """Every table of the module docstring; one dict per row. ``cases`` limits each benchmark (default all);
    ``speed_only``: the speed rows alone (no accuracy, tolerance, training or ablation rows)."""
    from ..data.bandai_mini import load_bandai_mini
    from ..evaluation.effector_cases import BENCHMARKS, load_benchmark
    from ..evaluation.effector_scores import run_classical, scores
    from ..models.protores.solver import run_learned
    from ..models.protores.networks import tolerance_to_sigma
    from ..models.protores.solver import ProtoResSolver

    motions = load_bandai_mini()
    s = motions.skeleton
    benches = {}
    for name in BENCHMARKS:
        b = load_benchmark(name, motions)
        benches[name] = b if cases is None else b.first(cases)
    solvers = {arch: ProtoResSolver(s, arch=arch) for arch in LEARNED}
    if speed_only:
        return _speed_rows(solvers, benches["5point"])
    rows = []
    from ..learn.threads import limit_threads

    for name, b in benches.items():
        for arch, solver in solvers.items():
            with limit_threads(1):
                t = time.perf_counter()
                r = run_learned(solver, b)
                sec = time.perf_counter() - t
            rows.append(_accuracy_row(name, _label(arch), scores(b, r["global_pos"], r["local_rot"], r["global_rot"],
                                                                 r["gpd_pos"]), sec, len(b)))
        if classical:
            for method, label in (("fabrik", "FABRIK"), ("dls", "DLS")):
                r = run_classical(method, b, motions, progress=progress)
                rows.append(_accuracy_row(name, label, scores(b, r["global_pos"], r["local_rot"], r["global_rot"]),
                                          r["seconds"], len(b)))
    rows += _claims(rows)
    b = benches["random"]
    for lam in (0.0, 0.5, 0.7, 0.8, 0.9, 1.0):
        r = run_learned(solvers["protores"], b, tolerance=lam)
        sc = scores(b, r["global_pos"], r["local_rot"], r["global_rot"])
        rows.append({"table": "tolerance", "lambda": lam, "sigma": round(tolerance_to_sigma(lam), 5),
                     "pos_mm": round(sc["pos_mm"], 2),
                     "rot_deg": round(sc["rot_deg"], 2), "look_deg": round(sc["look_deg"], 2),
                     "mpjpe_mm": round(sc["mpjpe_mm"], 1)})
    if speed:
        rows += _speed_rows(solvers, benches["5point"])
    training = _training_rows(solvers)
    rows += training
    rows += _ablation_rows(rows, training)
    return rows


def _header(rows, args) -> str:
    n = {r["benchmark"]: None for r in rows if r.get("table") == 1}
    if not n:
        return ("ProtoRes and its baselines (Oreshkin et al. 2022): speed on one thread against the machine's "
                "arithmetic; every time is the thread's CPU time (other work's turns on a shared core left out). Goals: ProtoRes one pose <= {GOAL_MS:g} ms (median); every network batched >= "
                f"{GOAL_FRACTION:.0%} of its ideal poses/s.")
    return ("ProtoRes benchmarks (Oreshkin et al. 2022) on held-out Bandai mini-set poses: "
            + ", ".join(n) + ". L_ikd-L2 and L_gpd-L2: 1e-3 m^2 (MSE over every body joint's coordinates); "
            "L_loc-geo: radians; effector errors: medians. Learned models: one pass each; FABRIK and DLS start "
            "from the rest pose fitted rigidly to the position targets (FABRIK gets the position effectors only)."
            + (f" Weights: {args.weights} (the shipped file for each model it lacks)." if getattr(args, "weights", None)
               else ""))


TABLES = [
    ("Table 1, 5-point benchmark (chest, hands, feet)",
     ["method", "ikd_l2_e3", "gpd_l2_e3", "loc_geo", "mpjpe_mm", "pos_mm", "ms_per_case"],
     {"table": 1, "benchmark": "5point"}),
    ("Table 1, random benchmark (6-12 effectors of three kinds)",
     ["method", "ikd_l2_e3", "gpd_l2_e3", "loc_geo", "mpjpe_mm", "pos_mm", "rot_deg", "look_deg", "ms_per_case"],
     {"table": 1, "benchmark": "random"}),
    ("The paper's claims on this run", ["claim", "holds", "detail"], {"table": "claims"}),
    ("Tolerance: ProtoRes on the random benchmark, every effector's Lambda set to one value",
     ["lambda", "sigma", "pos_mm", "rot_deg", "look_deg", "mpjpe_mm"], {"table": "tolerance"}),
    ("Speed against the roofline, one thread: multiply-adds per 5-point pose (layer sizes x effectors), the\n"
     "float32 GEMM rate on the network's own shapes (batch of 1,000), the ideal poses/s it allows, the measured\n"
     "poses/s of the network's pass on that batch (median of rounds) and its fraction of the ideal",
     ["method", "width", "effectors", "macs_per_pose", "weights_mb", "gemm_gmacs", "ideal_poses_per_s",
      "poses_per_s", "fraction_of_ideal", "goal_fraction", "fraction_met"], {"table": "speed"}),
    ("One 5-point pose on one thread, medians of every round: the network's products alone for one pose (and\n"
     "the GEMM rate they reach), then a whole pose through solve",
     ["method", "ms_products_one", "gemm_gmacs_one", "ms_solve_median", "goal_ms", "ms_met", "paper_ms"],
     {"table": "speed"}),
    ("The paper's width, one pose's products alone on one thread (its shapes with random weights; median of every\n"
     "round): what the roofline allows a width-1,024 network here, against the paper's time per pose on its GPU",
     ["method", "width", "effectors", "macs_per_pose", "weights_mb", "ms_products_one", "gemm_gmacs_one", "paper_ms"],
     {"table": "speed-paper"}),
    ("Training (from each shipped checkpoint: processes of one thread each, minutes of each process)",
     ["method", "parameters", "kB", "steps", "processes", "train_min", "ms_per_step", "val_mpjpe_mm"],
     {"table": "training"}),
    ("Table 2, ablations (random and 5-point benchmarks; the 2,000-step runs are stored results)",
     ["method", "random_ikd_l2_e3", "random_loc_geo", "5point_ikd_l2_e3", "5point_loc_geo", "train_min"],
     {"table": 2}),
]

# column headers from the one glossary (posekit.evaluation.measures): this benchmark's joint error is the world-frame
# mean, not MPJPE
LABELS = {"ikd_l2_e3": "L_ikd-L2", "gpd_l2_e3": "L_gpd-L2", "loc_geo": "L_loc-geo", "mpjpe_mm": "world joint mm",
          "pos_mm": "pos mm", "rot_deg": "rot deg", "look_deg": "look deg", "ms_per_case": "ms/case",
          "goal_ms": "goal ms", "paper_ms": "paper ms", "width": "width", "effectors": "N",
          "macs_per_pose": "MACs/pose", "weights_mb": "weights MB", "gemm_gmacs": "GEMM GMAC/s",
          "ideal_poses_per_s": "ideal poses/s", "poses_per_s": "poses/s", "fraction_of_ideal": "of ideal",
          "goal_fraction": "goal", "fraction_met": "met", "ms_solve_median": "solve ms (median)",
          "ms_products_one": "products ms", "gemm_gmacs_one": "GMAC/s", "ms_met": "met", "train_min": "train min", "ms_per_step": "ms/step",
          "val_mpjpe_mm": "val world joint mm", "random_ikd_l2_e3": "random L_ikd", "random_loc_geo": "random L_loc",
          "5point_ikd_l2_e3": "5-pt L_ikd", "5point_loc_geo": "5-pt L_loc"}


def _command(args) -> str:
    """The ``posekit bench protores`` command line of ``args`` (recorded in ``--out``'s file)."""
    parts = ["posekit bench protores"]
    if args.cases is not None:
        parts.append(f"--cases {args.cases}")
    parts += [flag for flag, on in (("--no-classical", args.no_classical), ("--no-speed", args.no_speed),
                                    ("--speed-only", args.speed_only)) if on]
    if args.weights:
        parts.append(f"--weights {args.weights}")
    if args.out:
        parts.append(f"--out {args.out}")
    return " ".join(parts)


def _load() -> float | None:
    """The 1-minute load average (``os.getloadavg``; None where the system has none)."""
    import os

    try:
        return round(os.getloadavg()[0], 2)
    except (AttributeError, OSError):
        return None


def write_results(rows: list[dict], path, command: str, load: float | None = None) -> None:
    """``rows`` with their provenance (:func:`posekit.provenance.stamp`) as JSON at ``path`` (folders made);
    ``load``: the 1-minute load average when the run began (other work on the machine slows every timing)."""
    from pathlib import Path

    from ..provenance import stamp

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"benchmark": "protores", **stamp(command), "load_avg_1min_before": load,
                                "clock": "thread CPU time (time.thread_time)",
                                "goal_ms": GOAL_MS,
                                "goal_fraction": GOAL_FRACTION, "rows": rows}, indent=1) + "\n", encoding="utf-8")


def _cli_run(args) -> list[dict]:
    import contextlib

    from ..paths import use_weights

    if args.speed_only and args.no_speed:
        raise ValueError("--speed-only and --no-speed exclude each other: give one of them")
    load = _load()
    with use_weights(args.weights) if args.weights else contextlib.nullcontext():  # a bad folder: refused first
        rows = run(cases=args.cases, classical=not args.no_classical, speed=not args.no_speed,
                   speed_only=args.speed_only)
    if args.out:
        write_results(rows, args.out, _command(args), load)
    return rows


register_benchmark(
    "protores", _cli_run,
    help="ProtoRes: Tables 1 and 2 of Oreshkin et al. 2022 at CPU scale, tolerance, speed and training time",
    args=[arg("--cases", type=int, default=None, help="cases per benchmark (default: all 1,000)"),
          arg("--no-classical", action="store_true", help="skip FABRIK and DLS"),
          arg("--no-speed", action="store_true", help="skip the timing rows"),
          arg("--speed-only", action="store_true",
              help="only the speed rows (multiply-adds, GEMM rate, ideal and measured poses/s, one-pose median)"),
          arg("--out", default=None,
              help="also write the rows, with the command, machine and date, to this JSON file (lesson 05 reads "
                   f"data_samples/results/{RESULTS_FILE})"),
          arg("--weights", default=None,
              help="a folder of ProtoRes checkpoints trained on the Bandai mini set (protores.pt, "
                   "protores_masked_fcr.pt, protores_transformer.pt; each one it lacks is the shipped one), e.g. "
                   "the folder posekit train protores --out wrote into")],
    tables=TABLES, labels=LABELS, header=_header, lesson="notebooks/05_protores.ipynb")
