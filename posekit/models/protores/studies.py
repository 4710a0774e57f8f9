"""Lesson 05's measured studies: Table 2's ablations and the width / accuracy / time trade-off of ProtoRes.

Introduced in ``notebooks/05_protores.ipynb``; ``posekit train protores-studies`` runs :func:`run_studies` and
writes ``data_samples/results/protores_ablation.json`` (read by ``posekit bench protores`` and the lesson).

* **Ablations** (the paper's Table 2) — ProtoRes of width 128 with the shipped loss and schedule settings, all for
  :data:`STEPS` steps (a short run, so that the study fits a session): as shipped, (a) without the global
  position decoder (one decoder of twice the blocks predicts the rotations and the pelvis; FK rooted
  there) and (b) with every joint weighted 1 instead of the randomized ``min(W_M, 1/sigma)``; scored on
  the shipped benchmarks, with the shipped ProtoRes (a user's hour of two cores) beside them.
* **Width** — ProtoRes of widths 64, 128 (the ablations' reference run) and 256, the same :data:`STEPS`
  steps: parameters, seconds per step, one-pose time on one thread, and the benchmarks' errors.
* **Seeds** (``--seeds``, :func:`run_seeds`) — the ablations' reference setting (width 128, :data:`STEPS` steps)
  trained with :data:`SEEDS` seeds and nothing else changed, written to ``data_samples/results/protores_seeds.json``:
  how far two training runs of one setting differ, the yardstick lesson 05 reads every ordering against
  (:func:`seed_spread`).
* **Scaling** (``--scaling``, :func:`run_scaling`) — the widths × step counts of :data:`SCALING_GRID`, each a
  full run with its own schedule (warm-up, cosine decay over its own steps), plus the shipped network
  (width 256, 20,000 steps on two processes): error against training compute (parameters × poses seen),
  written to ``data_samples/results/protores_scaling.json`` for lesson 05's scaling curve
  (:func:`posekit.models.protores.scaling.fit_power_law`).

Every run is seeded and single-threaded; ``workers`` runs train side by side, one per core (under ``torchrun``
or on a GPU, :mod:`posekit.learn.distributed`: one after another, each data-parallel).
"""

from __future__ import annotations

import json
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from ...learn.trainers import register_trainer
from ...plugins import arg
from ...provenance import machine, today

__all__ = ["ABLATIONS", "WIDTHS", "STEPS", "SEEDS", "SCALING_GRID", "run_studies", "run_scaling", "run_seeds",
           "seed_spread", "studies_path", "scaling_path", "seeds_path", "score_net", "refresh_shipped"]

ABLATIONS = {"no GPD": {"gpd": False}, "fixed weights": {"weighted": False}}
WIDTHS = (64, 128, 256)
STEPS = 2000
SEEDS = (0, 1, 2)
"""The seeds of the seed study: three runs, three pairs."""
SCALING_GRID = tuple((w, s) for w in (64, 128) for s in (500, 1000, 2000, 4000)) + ((128, 8000),) + tuple(
    (256, s) for s in (500, 1000, 2000))
"""(width, steps) of the scaling study, each one process of one thread; width 128 goes on to 8,000 steps (the
network shipped until 2026-12-03, a quarter hour of one core), width 256 stops at 2,000 steps (4,000 would take
about half an hour of one core on its own). The shipped network adds width 256 at 20,000 steps of two processes."""


def studies_path():
    from ...paths import samples_dir

    return samples_dir() / "results" / "protores_ablation.json"


def scaling_path():
    from ...paths import samples_dir

    return samples_dir() / "results" / "protores_scaling.json"


def seeds_path():
    """``data_samples/results/protores_seeds.json``: the seed study (:func:`run_seeds`)."""
    from ...paths import samples_dir

    return samples_dir() / "results" / "protores_seeds.json"


def score_net(net, motions=None) -> dict:
    """Both benchmarks' L_ikd-L2 (1e-3 m^2), L_loc-geo (rad) and MPJPE (mm) of a network, and its one-pose time."""
    from ...learn.threads import limit_threads
    from ...evaluation.effector_cases import BENCHMARKS, load_benchmark
    from ...evaluation.effector_scores import scores
    from .solver import ProtoResSolver, run_learned

    solver = ProtoResSolver(net.skeleton, net=net)
    out = {}
    with limit_threads(1):
        for name in BENCHMARKS:
            b = load_benchmark(name, motions)
            r = run_learned(solver, b)
            sc = scores(b, r["global_pos"], r["local_rot"], r["global_rot"], r["gpd_pos"])
            out[f"{name}_ikd_l2_e3"] = round(sc["ikd_l2"] * 1000, 3)
            out[f"{name}_loc_geo"] = round(sc["loc_geo"], 4)
            out[f"{name}_mpjpe_mm"] = round(sc["mpjpe_mm"], 1)
        args = solver.arrays(solver.resolve(b.effectors(0)))
        for _ in range(5):
            solver.predict(*args)
        ts = []
        for _ in range(50):
            t = time.perf_counter()
            solver.predict(*args)
            ts.append(time.perf_counter() - t)
    out["ms_predict"] = round(float(np.median(ts)) * 1000, 2)
    return out


def _job(job):
    from ...data.bandai_mini import load_bandai_mini
    from ...data.metrics import body_joints
    from .networks import ProtoResConfig
    from .train import train_protores

    label, cfg_kw, settings, seed = job
    motions = load_bandai_mini()
    cfg = ProtoResConfig(len(body_joints(motions.skeleton)), **cfg_kw)
    net, rep = train_protores(motions, seed=seed, out=False, progress=False, config=cfg, **settings)
    return {"method": label, **score_net(net, motions), "parameters": net.n_parameters(), "steps": rep["steps"],
            "train_min": round(rep["train_seconds"] / 60, 1), "ms_per_step": round(rep["seconds_per_step"] * 1000),
            "val_mpjpe_mm": round(rep["val"]["mpjpe_mm"], 1)}


def _shipped_row(motions) -> dict:
    """The shipped ProtoRes scored like a study run (its training report gives steps, time and processes:
    ``train_min`` is each process's training time, ``processes`` how many trained side by side)."""
    from .solver import load_protores

    shipped = load_protores("protores")
    rep = shipped.checkpoint["extra"]["report"]
    return {"method": "ProtoRes (shipped)", **score_net(shipped, motions),
            "parameters": shipped.n_parameters(), "steps": rep["steps"], "width": shipped.config.width,
            "batch": int(rep["settings"]["batch"]), "processes": int(rep.get("processes", 1)),
            "train_min": round(rep["train_seconds"] / 60, 1), "command": shipped.checkpoint["command"],
            "ms_per_step": round(rep["seconds_per_step"] * 1000), "val_mpjpe_mm": round(rep["val"]["mpjpe_mm"], 1)}


def _with_compute(row: dict, batch: int) -> dict:
    """``row`` with ``batch`` (poses per step, over every process) and ``compute``: parameters × poses seen."""
    row.setdefault("batch", batch)
    row["compute"] = float(row["parameters"]) * row["steps"] * row["batch"]
    return row


def refresh_shipped(motions=None) -> dict:
    """Score the shipped ProtoRes again and put it in place of the shipped row of both study files (the
    ablations' and the scaling curve's), keeping every trained run: what ``posekit train protores-studies
    --shipped`` runs after new shipped weights, in a minute instead of the studies' half hours."""
    from ...data.bandai_mini import load_bandai_mini

    row = _shipped_row(load_bandai_mini() if motions is None else motions)
    trained = lambda res: [r for r in res["rows"] if r["method"] != row["method"]]  # noqa: E731
    ablation, scaling = (json.loads(p.read_text()) for p in (studies_path(), scaling_path()))
    ablation["rows"] = [dict(row)] + trained(ablation)
    scaling["rows"] = sorted(trained(scaling) + [_with_compute(dict(row), scaling["batch"])],
                             key=lambda r: (r["width"], r["steps"]))
    for path, res in ((studies_path(), ablation), (scaling_path(), scaling)):
        path.write_text(json.dumps(res, indent=1) + "\n")
    return row


def _pool_map(jobs, workers: int) -> list:
    """Run study jobs: side by side in a process pool on the CPU, else (torchrun or a GPU) one after another,
    each on every process, data-parallel."""
    from ...learn.distributed import current

    run = current()
    if run.distributed or run.device.type != "cpu" or workers <= 1:
        return [_job(j) for j in jobs]
    with ProcessPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(_job, jobs))


def run_scaling(seed: int = 0, out=None, workers: int = 2, grid=SCALING_GRID) -> dict:
    """Train and score every (width, steps) of ``grid`` and the shipped network (see the module docstring);
    write the JSON (``out=False``: none). Each row adds ``width``, ``batch`` and ``compute`` (parameters ×
    poses seen, the usual proxy of training FLOPs up to a constant factor)."""
    from ...data.bandai_mini import load_bandai_mini
    from ...learn.distributed import current
    from .train import DEFAULTS

    t0 = time.perf_counter()
    batch = DEFAULTS["batch"]
    jobs = sorted(((f"width {w}, {s} steps", {"width": w}, {"steps": s}, seed) for w, s in grid),
                  key=lambda j: -j[1]["width"] ** 2 * j[2]["steps"])  # longest first
    rows = _pool_map(jobs, workers)
    for r, (w, s) in zip(rows, [(j[1]["width"], j[2]["steps"]) for j in jobs]):
        r["width"] = w
    rows.append(_shipped_row(load_bandai_mini()))
    for r in rows:
        _with_compute(r, batch)
    rows.sort(key=lambda r: (r["width"], r["steps"]))
    res = {"rows": rows, "seed": seed, "batch": batch, "seconds": round(time.perf_counter() - t0),
           "command": f"posekit train protores-studies --scaling --seed {seed}", "date": today(), "machine": machine()}
    if out is not False and current().main:
        path = scaling_path() if out is None else out
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(res, indent=1) + "\n")
    return res


def run_studies(seed: int = 0, out=None, workers: int = 2, progress: bool = True) -> dict:
    """Train and score the studies of the module docstring; write the JSON (``out=False``: none)."""
    from ...data.bandai_mini import load_bandai_mini
    from ...learn.distributed import current

    t0 = time.perf_counter()
    jobs = [(f"width {w}", {"width": w}, {"steps": STEPS}, seed) for w in (256, 64, 128)]  # longest first
    jobs += [(f"ProtoRes, {k}", {k2: v for k2, v in kw.items() if k2 == "gpd"},
              {"steps": STEPS, **{k2: v for k2, v in kw.items() if k2 != "gpd"}}, seed) for k, kw in ABLATIONS.items()]
    run = current()
    done = _pool_map(jobs, workers)
    width = lambda r: int(r["method"][6:]) if r["method"].startswith("width") else 0  # noqa: E731
    done.sort(key=lambda r: (not r["method"].startswith("width"), width(r)))
    full = _shipped_row(load_bandai_mini())
    ref = dict(next(r for r in done if r["method"] == "width 128"), method=f"ProtoRes ({STEPS} steps)")
    res = {"rows": [full, ref] + [r for r in done if r["method"].startswith("ProtoRes")],
           "width": [r for r in done if r["method"].startswith("width")], "seed": seed,
           "steps": STEPS, "seconds": round(time.perf_counter() - t0),
           "command": f"posekit train protores-studies --seed {seed}", "date": today(), "machine": machine()}
    if out is not False and run.main:
        path = studies_path() if out is None else out
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(res, indent=1) + "\n")
    return res


def run_seeds(seeds=SEEDS, out=None, workers: int = 2, width: int = 128, steps: int = STEPS) -> dict:
    """Train and score the reference setting once per seed (see the module docstring); write the JSON
    (``out=False``: none)."""
    from ...learn.distributed import current

    t0 = time.perf_counter()
    rows = _pool_map([(f"width {width}, seed {s}", {"width": width}, {"steps": steps}, s) for s in seeds], workers)
    for r, s in zip(rows, seeds):
        r["seed"] = s
    res = {"rows": rows, "width": width, "steps": steps, "seeds": list(seeds), "seconds": round(time.perf_counter() - t0),
           "command": f"posekit train protores-studies --seeds {','.join(map(str, seeds))}", "date": today(),
           "machine": machine()}
    if out is not False and current().main:
        path = seeds_path() if out is None else out
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(res, indent=1) + "\n")
    return res


def seed_spread(rows, key: str) -> float:
    """The largest relative difference of ``key`` (a lower-is-better error) between two of the seed study's runs:
    ``max |a - b| / min(a, b)`` over every pair (:func:`posekit.evaluation.measures.run_spread`)."""
    from itertools import combinations

    from ...evaluation.measures import run_spread

    return run_spread(*((a[key], b[key]) for a, b in combinations(rows, 2)))


def _cli(args) -> int:
    """``posekit train protores-studies``."""
    from pathlib import Path

    if args.shipped:
        row = refresh_shipped()
        print(f"the shipped ProtoRes ({row['command']}): random L_ikd-L2 {row['random_ikd_l2_e3']:.3f}e-3 m^2, "
              f"5-point {row['5point_ikd_l2_e3']:.3f}e-3; wrote {studies_path()} and {scaling_path()}")
        return 0
    if args.seeds:
        seeds = tuple(int(s) for s in args.seeds.split(",") if s.strip())
        out = Path(args.out) if args.out else seeds_path()
        res = run_seeds(seeds, out=out, workers=args.workers)
        for r in res["rows"]:
            print(f"{r['method']:<22} random L_ikd-L2 {r['random_ikd_l2_e3']:.3f}e-3 m^2, 5-point "
                  f"{r['5point_ikd_l2_e3']:.3f}e-3; world joint {r['random_mpjpe_mm']:.1f} / {r['5point_mpjpe_mm']:.1f} mm; "
                  f"{r['train_min']} min")
        print(f"wrote {out} in {res['seconds']} s")
        return 0
    if args.scaling:
        out = Path(args.out) if args.out else scaling_path()
        res = run_scaling(seed=args.seed, out=out, workers=args.workers)
        for r in res["rows"]:
            print(f"width {r['width']:>4} {r['steps']:>5} steps ({r['compute']:.2e} parameter-poses): "
                  f"random L_ikd-L2 {r['random_ikd_l2_e3']:.3f}e-3 m^2, 5-point {r['5point_ikd_l2_e3']:.3f}e-3; "
                  f"{r['train_min']} min")
        print(f"wrote {out} in {res['seconds']} s")
        return 0
    out = Path(args.out) if args.out else studies_path()
    res = run_studies(seed=args.seed, out=out, workers=args.workers, progress=True)
    for r in res["rows"] + res["width"]:
        print(f"{r['method']:<28} random L_ikd-L2 {r['random_ikd_l2_e3']:.3f}e-3 m^2, "
              f"L_loc-geo {r['random_loc_geo']:.3f}; "
              f"5-point {r['5point_ikd_l2_e3']:.3f}e-3, {r['5point_loc_geo']:.3f}; {r['train_min']} min")
    print(f"wrote {out} in {res['seconds']} s")
    return 0


register_trainer(
    "protores-studies", _cli, help="lesson 05's ablations (no GPD, fixed weights) and width study",
    makes="data_samples/results/protores_ablation.json",
    what="lesson 05's Table 2 ablations (no GPD, fixed weights) and the width study",
    used_by="lesson 05 (05_protores.ipynb), posekit bench protores",
    takes="about 15 minutes on 2 cores (five 2,000-step runs, two side by side)",
    out=".json",
    args=[arg("--workers", type=int, default=2, help="runs side by side, one thread each (default: 2)"),
          arg("--seed", type=int, default=0, help="(default: 0)"),
          arg("--scaling", action="store_true",
              help="the scaling study instead: widths x step counts, the longest study (its time is the file's "
                   "seconds), written to data_samples/results/protores_scaling.json"),
          arg("--seeds", default=None, metavar="S,S,...",
              help="the seed study instead: the reference setting (width 128, 2,000 steps) once per seed, "
                   "written to data_samples/results/protores_seeds.json (lesson 05's yardstick; its time is the "
                   "file's seconds)"),
          arg("--shipped", action="store_true",
              help="no training: score the shipped ProtoRes again into both files' shipped row (after new weights)"),
          arg("--out", default=None, help="JSON file (default data_samples/results/protores_ablation.json, or "
                                          "protores_scaling.json with --scaling)")])
