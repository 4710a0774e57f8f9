"""``posekit bench ae-scale``: lesson 03 (Victor et al. 2021) at full scale, on the whole Bandai Namco datasets.

Introduced in ``notebooks/03_autoencoder_solvers.ipynb``. The lesson trains its pose autoencoder and
latent-space solvers on the Bandai mini set (41,391 poses, frames subsampled); this benchmark asks
whether the numbers hold on *every* frame of the two full datasets (read by path from
``$POSEKIT_DATA_DIR``, never copied), and on a harder, cross-dataset split. One run:

1. :func:`scale_motions` builds one :class:`~posekit.data.motion.MotionSet` of both datasets with a
   ``split`` for the protocol;
2. :func:`posekit.models.pose_autoencoder.train.train_ae_solvers` trains the autoencoder, the solvers and the
   chaining-aware copies on its ``train`` frames (validation losses on ``val``), in memory;
3. the trained model is registered under temporary solver names (``neural-scale``, ..., unregistered
   when the run ends) and
   :func:`posekit.bench.ik.run` measures FABRIK and the neural variants on held-out ``test`` cases,
   with the shared metrics of ``posekit bench ik`` (rows are renamed back to ``neural``,
   ``neural-raw``, ``neural-chained``, ``neural-chained-raw``, ``neural-fabrik``).

Protocols (:data:`PROTOCOLS`)
-----------------------------
* ``full`` — train on all of dataset 2 plus the dataset-1 clips that
  :func:`posekit.data.bandai_mini.held_out_split` puts in train; val and test are the dataset-1 clips
  it holds out (the mini set's rule: unseen styles / takes of seen contents). Same rule as the mini
  set, so the test clips are the mini set's test clips, at their full 30 fps.
* ``cross`` — train on dataset 2 only, except a seeded :data:`CROSS_VAL_FRACTION` of its frames
  (whole clips) kept as val; test on *all* of dataset 1: another capture session, other actors'
  styles and contents dataset 2 lacks (bow, punch, kick, dance, ...).

Frame counts (every frame, ``step=1``; 31,914 + 97,295 = 129,209 frames, 174 + 2,902 clips):

========  ==================  =============  ==============
protocol  train               val            test
========  ==================  =============  ==============
full      124,452 (3,051 c)   2,174 (11 c)   2,583 (14 c)
cross     94,363 (2,807 c)    2,932 (95 c)   31,914 (174 c)
========  ==================  =============  ==============

(``c``: clips; ``cross`` val with ``seed=0``.) Dataset 1 is at 30 fps, dataset 2 at 7.5 fps (every 4th
frame of the 30 fps capture, as shipped in ``bandai-namco-2-every4th``).

How the two datasets become one MotionSet
-----------------------------------------
Both datasets have the same 22-joint hierarchy (:data:`posekit.data.bandai_mini.JOINTS`; checked, a
``ValueError`` otherwise). In the files every joint has position channels: ``joint_Root`` and ``Hips``
carry the world placement, and the ``Hips`` OFFSET varies by file. Concatenated as read, the set would
need per-frame ``local_pos`` (F, 22, 3), and ``start="rest"`` of the benchmark would be refused
(:func:`posekit.data.cases.build_cases`) whenever a held-out clip is one of the eight dataset-1 files
whose ``LowerLeg_R`` OFFSET is 0.40 mm off the others (``call_normal_002`` is a ``full`` test clip; under
``cross`` all eight are). So, exactly as the mini set's build does (see :mod:`posekit.data.bandai_mini`),
each clip is checked and normalised: ``joint_Root`` must never rotate; the position channels of every
joint below ``Hips`` must equal the reference OFFSETs (``dataset-1_walk_normal_001.bvh``) within
:data:`~posekit.data.bandai_mini.OFFSET_TOL` and keep their bone lengths within
:data:`~posekit.data.bandai_mini.LENGTH_TOL`; ``root_pos`` becomes the world ``Hips`` position minus
:data:`~posekit.data.bandai_mini.ROOT_TO_HIPS` and ``joint_Root`` a fixed helper 0.94 m below the
pelvis. The set then has ``local_pos=None`` (every bone has one length), the mini set's skeleton
(``Skeleton.same_as`` holds, so weights transfer either way) and float64 rotations (no float16). The
largest offset change this makes is reported (``offset_dev_max_m``).

Cost
----
Measured with the default training settings (:data:`posekit.models.pose_autoencoder.train.DEFAULTS`) on a shared
2-core machine, one torch thread: ``full`` 12.1 min (reading 24 s, training 11.3 min, benchmark 25 s),
``cross`` 10.2 min (15 s, 9.5 min, 23 s); about 1.3 GB of memory. The autoencoder's epochs grow with
the training frames (about 4-5 s each here, 80 of them), the solvers' with ``pairs`` (fixed). Training
runs on ``threads`` torch threads (default 1): on a shared machine, more threads than free cores made
one training step 300 ms instead of 4 ms. ``step`` subsamples frames (every ``step``-th frame of each
clip) when a run is too slow.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from ..data.bandai_full import CROSS_VAL_FRACTION, PROTOCOLS, describe_motions, scale_motions
from ..data.cases import START_CONDITIONS, build_cases
from ..ik.api import EFFECTOR_SETS
from ..paths import samples_dir
from ..provenance import machine, today
from .ik import TABLE_LABELS
from .ik import run as ik_run
from .plugin import arg, register_benchmark

__all__ = ["PROTOCOLS", "CROSS_VAL_FRACTION", "VARIANTS", "TABLES", "scale_motions", "describe_motions",
           "run_scale", "default_out"]

VARIANTS = {
    "neural": dict(post="bones"),
    "neural-raw": dict(post="none"),
    "neural-chained": dict(chain=True),
    "neural-chained-raw": dict(chain=True, post="none"),
    "neural-fabrik": dict(post="fabrik"),
}
"""The neural rows of a run: row name -> :class:`~posekit.models.pose_autoencoder.solver.NeuralIKSolver` options. The
chained variants are measured on effector sets that the chain covers with more than one stage (5
effectors; on the 2 hands they are the plain solver), as in ``posekit bench ik``."""

TEMP_SUFFIX = "-scale"
"""Suffix of the temporary solver names the in-memory model is registered under (``neural-scale``, ...)."""

DEFAULT_EFFECTORS = ("2", "5")
DEFAULT_STARTS = ("rest", "same-clip", "other-clip")


# ------------------------------------------------------------------------------------------------ run
def _register(model) -> dict:
    """Register the in-memory model under temporary names; returns {temporary name: row name}."""
    from ..ik.registry import register
    from ..models.pose_autoencoder.solver import NeuralIKSolver

    names = {}
    for row_name, opts in VARIANTS.items():
        temp = row_name + TEMP_SUFFIX

        def factory(skeleton, opts=opts):
            return NeuralIKSolver(skeleton, model=model, **opts)

        register(temp, factory, kinds=("position",), needs_start=True, replace=True, lesson="posekit bench ae-scale",
                 description=f"{row_name} with the model trained by the last ae-scale run (in memory)")
        names[temp] = row_name
    return names


def default_out(protocol: str) -> Path:
    """Where a run's JSON goes by default: ``data_samples/results/ae_scale_{protocol}.json``."""
    return samples_dir() / "results" / f"ae_scale_{protocol}.json"


def _command(protocol, n_cases, seed, limit, step, threads, settings) -> str:
    if settings or threads != 1:
        kw = ", ".join([f"n_cases={n_cases}", f"seed={seed}"] + [f"limit={limit}"] * (limit is not None)
                       + [f"step={step}"] * (step != 1) + [f"threads={threads}"] * (threads != 1)
                       + [f"{k}={v!r}" for k, v in settings.items()])
        return f"python -c \"from posekit.bench.ae_scale import run_scale; run_scale({protocol!r}, {kw})\""
    parts = [f"--protocol {protocol}", f"--cases {n_cases}", f"--seed {seed}"]
    parts += [f"--limit {limit}"] * (limit is not None) + [f"--step {step}"] * (step != 1)
    return "posekit bench ae-scale " + " ".join(parts)


def _jsonable(v):
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    return v


def run_scale(protocol: str = "full", n_cases: int = 1000, seed: int = 0, out=None, progress: bool = True,
              limit: int | None = None, step: int = 1, data_dir=None, threads: int | None = 1,
              effector_sets=DEFAULT_EFFECTORS, starts=DEFAULT_STARTS, **train_settings) -> dict:
    """Train lesson 03's networks on a full-scale protocol and benchmark them against FABRIK.

    Parameters
    ----------
    protocol : {"full", "cross"}
    n_cases : int
        Held-out (start, target) cases per start condition (the same targets under every start).
    seed : int
        Seeds the training, the case draw and the ``cross`` val clips.
    out : str, Path, None or False
        The JSON file to write (folders created); None: :func:`default_out`; False: none.
    progress : bool
        tqdm bars (reading, training, benchmark).
    limit : int, optional
        At most this many clips per dataset (:func:`scale_motions`; for tests).
    step : int
        Keep every ``step``-th frame of each clip (:func:`scale_motions`).
    data_dir : path, optional
        Default ``$POSEKIT_DATA_DIR``.
    threads : int or None
        torch threads while training (None: leave torch's setting); the benchmark itself runs on one
        thread, as ``posekit bench ik``.
    effector_sets, starts : sequence of str
        Effector sets and start conditions of the benchmark; a start that
        :func:`~posekit.data.cases.build_cases` refuses for this data (e.g. ``other-clip`` with a single
        test clip) is skipped and the reason recorded in ``skipped_starts``.
    **train_settings
        Any of :data:`posekit.models.pose_autoencoder.train.DEFAULTS` (default: those).

    Returns
    -------
    dict
        JSON-able: ``protocol``, ``description``, ``data`` (:func:`describe_motions`), ``train`` (split,
        poses, final train/val losses, seconds per stage), ``train_seconds``, ``settings`` (the training
        settings used), ``command`` (reproduces the run), ``n_cases``, ``seed``, ``threads``,
        ``starts``, ``skipped_starts`` ({start: reason}), ``seconds`` (load, train, bench, total),
        ``rows`` (one per method, effector set and start, ``posekit bench ik``'s keys; ``method`` is
        ``fabrik`` or a :data:`VARIANTS` name, every row also has ``protocol``) and ``out`` (the file
        written, or None).

    Raises
    ------
    ValueError
        Bad arguments (see :func:`scale_motions`), or every start condition refused.
    """
    from ..learn.threads import limit_threads
    from ..models.pose_autoencoder.networks import chain_groups
    from ..models.pose_autoencoder.train import DEFAULTS, train_ae_solvers

    bad = set(train_settings) - set(DEFAULTS)
    if bad:
        raise ValueError(f"run_scale: unknown training setting(s) {sorted(bad)}; valid: {sorted(DEFAULTS)}")
    t0 = time.perf_counter()
    motions = scale_motions(protocol, data_dir=data_dir, limit=limit, progress=progress, step=step, seed=seed)
    t_load = time.perf_counter() - t0
    data = describe_motions(motions)

    skipped, ok = {}, []
    for st in starts:
        try:
            build_cases(motions, int(n_cases), seed, st)
            ok.append(st)
        except ValueError as err:  # refused for this data: recorded, not fatal
            skipped[st] = str(err)
    if not ok:
        raise ValueError(f"every start condition was refused on {motions.source!r}: {skipped}")

    t1 = time.perf_counter()
    with limit_threads(threads):
        model, report = train_ae_solvers(motions, seed=seed, out=False, progress=progress,
                                         data_label=f"bandai-{protocol}", **train_settings)
    t_train = time.perf_counter() - t1

    t2 = time.perf_counter()
    names = _register(model)
    try:
        rows = ik_run(motions, solvers=("fabrik", *names), effector_sets=tuple(effector_sets), n_cases=int(n_cases),
                      start=tuple(ok), seed=seed, methods="none", progress=progress)
    finally:  # the in-memory model leaves the registry with the run (else `bench all` would meet it)
        from ..ik.registry import unregister

        for temp in names:
            unregister(temp)
    kept = []
    for r in rows:
        r["method"] = names.get(r["method"], r["method"])
        one_stage = len(chain_groups(EFFECTOR_SETS[r["effectors"]])) < 2
        if VARIANTS.get(r["method"], {}).get("chain") and one_stage:
            continue  # a one-stage chain is the plain solver: not a row (as in posekit bench ik)
        r["protocol"] = protocol
        kept.append(r)
    t_bench = time.perf_counter() - t2

    st = {**DEFAULTS, **train_settings}
    result = {
        "protocol": protocol,
        "description": PROTOCOLS[protocol],
        "data": data,
        "train": {
            "split": report.get("split"), "train_poses": report.get("train_poses"),
            "val_poses": report.get("val_poses"),
            "final_loss": {k: {"train": v["train"][-1], "val": v["val"][-1] if v.get("val") else None}
                           for k, v in [("autoencoder", report["autoencoder"]), *report["solvers"].items()]},
            "seconds": report["seconds"],
        },
        "train_seconds": float(report["seconds"]["total"]),
        "settings": st,
        "command": _command(protocol, int(n_cases), seed, limit, step, threads, train_settings),
        "n_cases": int(n_cases), "seed": int(seed), "threads": threads,
        "starts": ok, "skipped_starts": skipped,
        "seconds": {"load": round(t_load, 2), "train": round(t_train, 2), "bench": round(t_bench, 2),
                    "total": round(time.perf_counter() - t0, 2)},
        "rows": kept,
        "licence": "results of networks trained on the Bandai Namco Research Motion Datasets 1 and 2 "
                   "(c) Bandai Namco Research Inc., CC BY-NC 4.0",
        "date": today(), "machine": machine(),
    }
    result = _jsonable(result)
    global _LAST
    _LAST = result
    result["out"] = None
    if out is not False:
        path = Path(out) if out is not None else default_out(protocol)
        path.parent.mkdir(parents=True, exist_ok=True)
        result["out"] = str(path)
        path.write_text(json.dumps(result, indent=1, allow_nan=True) + "\n")
    return result


# ------------------------------------------------------------------------------------------------ the CLI
_LAST: dict | None = None

TABLES = [
    ("Accuracy (medians over cases; effector: the worst of a case; bone error: the worst case)",
     ["method", "effectors", "effector_error_mm_median", "converged_fraction", "bone_length_error_mm_max",
      "latency_ms_median"]),
    ("Pose (medians over cases; body joints, pelvis-relative; floor: the true pose's own naturalness)",
     ["method", "effectors", "mpjpe_mm_median", "natural_mm_median", "natural_floor_mm_median"]),
]
"""The tables ``posekit bench ae-scale`` prints per start condition: (title, JSON keys)."""


def out_argument(value):
    """``--out`` as :func:`run_scale` takes it: None (not given) -> the default file; ``none``, ``false`` or
    ``-`` -> False (write nothing); anything else -> that path."""
    if value is not None and str(value).lower() in ("false", "none", "-"):
        return False
    return value


def _cli_run(args) -> list[dict]:

    show = True  # on stderr: a bar in a terminal, a line every few seconds in a log (posekit.progress)
    out = out_argument(args.out)
    result = run_scale(args.protocol, n_cases=args.cases, seed=args.seed, out=out, progress=show, limit=args.limit,
                       step=args.step)
    return result["rows"]


def _header(rows, args) -> str:
    p = rows[0]["protocol"] if rows else getattr(args, "protocol", "full")
    lines = [f"Lesson 03 at full scale, protocol {p}: {PROTOCOLS.get(p, '')}"]
    r = _LAST if _LAST and _LAST.get("protocol") == p else None
    if r:
        f, c = r["data"]["frames_per_split"], r["data"]["clips_per_split"]
        lines.append(f"frames (clips): train {f['train']:,} ({c['train']:,}), val {f['val']:,} ({c['val']:,}), "
                     f"test {f['test']:,} ({c['test']:,}); training {r['train_seconds'] / 60:.1f} min; "
                     f"{r['n_cases']} test cases per start; JSON: {r['out'] or 'not written'}")
        for st, why in r["skipped_starts"].items():
            lines.append(f"start {st} skipped: {why}")
    lines.append("errors in mm; MPJPE and natural: body joints, pelvis-relative; neural rows: the model trained "
                 "by this run")
    return "\n".join(lines)


def _group_title(start: str) -> str:
    return f"Start: {start} ({START_CONDITIONS.get(start, start)})"


register_benchmark(
    "ae-scale", _cli_run,
    help="lesson 03 at full scale: autoencoder + latent solvers trained on the full Bandai sets vs FABRIK",
    args=[
        arg("--protocol", choices=tuple(PROTOCOLS), default="full",
            help="full: dataset 2 + dataset-1 train clips, test held-out dataset-1 styles; cross: train dataset 2, "
                 "test all of dataset 1"),
        arg("--cases", type=int, default=1000, help="held-out (start, target) cases per start condition"),
        arg("--seed", type=int, default=0, help="seed of the training, the cases and the cross val clips"),
        arg("--limit", type=int, default=None, help="at most this many clips per dataset (quick checks)"),
        arg("--step", type=int, default=1, help="keep every step-th frame of each clip"),
        arg("--out", default=None,
            help="JSON file of the run (default: data_samples/results/ae_scale_PROTOCOL.json; none: do not write)"),
    ],
    tables=TABLES, labels=TABLE_LABELS, header=_header, group_by="start", group_title=_group_title, wide=True,
    lesson="notebooks/03_autoencoder_solvers.ipynb")
