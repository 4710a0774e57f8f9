"""``posekit bench protores``: ProtoRes's Tables 1 and 2 at CPU scale (Oreshkin et al. 2022), speed, training time.

Introduced in ``notebooks/05_protores.ipynb``. One run scores every method on the shipped 5-point and
random benchmarks (:mod:`posekit.evaluation.effector_cases`) with one metric code
(:mod:`posekit.evaluation.effector_scores`):

* **Table 1** — ProtoRes, Masked-FCR, Transformer (each its shipped weights) and the classical stand-ins
  for FinalIK: FABRIK and DLS from the fitted rest pose;
* **claims** — the paper's orderings, each checked on this run's numbers (True/False);
* **tolerance** — ProtoRes on the random benchmark with every effector's ``Lambda`` set to one value:
  a looser tolerance should give larger effector errors;
* **speed** — one pose through ``solve`` and through the array path on one thread (goal 2 ms; the paper
  reports about 10 ms, 100 FPS, in Unity), and poses per second in batches of 1,000 (goal 20,000);
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

__all__ = ["run", "GOAL_MS", "GOAL_POSES_PER_S", "PAPER_MS", "ABLATION_FILE", "LEARNED"]

GOAL_MS = 2.0
GOAL_POSES_PER_S = 20_000
PAPER_MS = 10.0
"""About 100 FPS for one pose in Unity (the paper's Sec. 5)."""

BATCH = 1000
"""Poses per batch of the throughput rows (whatever ``--cases`` says)."""

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


def _net_seconds(solver, batch) -> float:
    """Seconds of the network's own pass on a batch (torch, no wrapper: no checks, float32 FK only)."""
    import torch

    t = [torch.as_tensor(solver._body_lookup[batch[0]]), torch.as_tensor(batch[1]),
         torch.as_tensor(batch[2], dtype=torch.float32), torch.as_tensor(batch[3], dtype=torch.float32)]
    with torch.no_grad():
        solver.net(*t)
        start = time.perf_counter()
        solver.net(*t)
        return time.perf_counter() - start


def _speed_rows(solvers, five) -> list[dict]:
    from ..learn.threads import limit_threads

    rows = []
    effs = five.effectors(0)
    for arch, solver in solvers.items():
        args = solver.arrays(solver.resolve(effs))
        n = BATCH
        with limit_threads(1):
            for _ in range(5):
                solver.solve(None, effs)
            ts = []
            for _ in range(100):
                t = time.perf_counter()
                solver.solve(None, effs)
                ts.append(time.perf_counter() - t)
            tp = []
            for _ in range(100):
                t = time.perf_counter()
                solver.predict(*args)
                tp.append(time.perf_counter() - t)
            batch = tuple(a[None].repeat(n, 0) for a in args)
            solver.predict(*batch)  # warm-up of the batched (torch) path
            t = time.perf_counter()
            solver.predict(*batch)
            one = time.perf_counter() - t
            net_one = _net_seconds(solver, batch)
        solver.predict(*batch)
        t = time.perf_counter()
        solver.predict(*batch)
        allt = time.perf_counter() - t
        net_all = _net_seconds(solver, batch)
        rows.append({"table": "speed", "method": _label(arch), "ms_solve": round(float(np.median(ts)) * 1000, 2),
                     "ms_predict": round(float(np.median(tp)) * 1000, 2), "goal_ms": GOAL_MS, "paper_ms": PAPER_MS,
                     "poses_per_s_1_thread": round(n / one), "poses_per_s_all_threads": round(n / allt),
                     "net_poses_per_s_1_thread": round(n / net_one), "net_poses_per_s_all_threads": round(n / net_all),
                     "goal_poses_per_s": GOAL_POSES_PER_S})
    return rows


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


def run(cases: int | None = None, classical: bool = True, speed: bool = True, progress: bool = False) -> list[dict]:
    """Every table of the module docstring; one dict per row. ``cases`` limits each benchmark (default all)."""
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
    ("Speed: one 5-point pose on one thread (solve: the Solver API; predict: the arrays) and batches of 1,000\n"
     "(predict: whole poses, float64 FK and quaternions; net: the network's pass alone)",
     ["method", "ms_solve", "ms_predict", "goal_ms", "paper_ms", "poses_per_s_1_thread", "poses_per_s_all_threads",
      "net_poses_per_s_1_thread", "net_poses_per_s_all_threads", "goal_poses_per_s"], {"table": "speed"}),
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
          "ms_solve": "solve ms", "ms_predict": "predict ms", "goal_ms": "goal ms", "paper_ms": "paper ms",
          "poses_per_s_1_thread": "poses/s 1 thr", "poses_per_s_all_threads": "poses/s all",
          "net_poses_per_s_1_thread": "net 1 thr", "net_poses_per_s_all_threads": "net all",
          "goal_poses_per_s": "goal poses/s", "train_min": "train min", "ms_per_step": "ms/step",
          "val_mpjpe_mm": "val world joint mm", "random_ikd_l2_e3": "random L_ikd", "random_loc_geo": "random L_loc",
          "5point_ikd_l2_e3": "5-pt L_ikd", "5point_loc_geo": "5-pt L_loc"}


def _cli_run(args) -> list[dict]:
    import contextlib

    from ..paths import use_weights

    with use_weights(args.weights) if args.weights else contextlib.nullcontext():  # a bad folder: refused first
        return run(cases=args.cases, classical=not args.no_classical, speed=not args.no_speed)


register_benchmark(
    "protores", _cli_run,
    help="ProtoRes: Tables 1 and 2 of Oreshkin et al. 2022 at CPU scale, tolerance, speed and training time",
    args=[arg("--cases", type=int, default=None, help="cases per benchmark (default: all 1,000)"),
          arg("--no-classical", action="store_true", help="skip FABRIK and DLS"),
          arg("--no-speed", action="store_true", help="skip the timing rows"),
          arg("--weights", default=None,
              help="a folder of ProtoRes checkpoints trained on the Bandai mini set (protores.pt, "
                   "protores_masked_fcr.pt, protores_transformer.pt; each one it lacks is the shipped one), e.g. "
                   "the folder posekit train protores --out wrote into")],
    tables=TABLES, labels=LABELS, header=_header, lesson="notebooks/05_protores.ipynb")
