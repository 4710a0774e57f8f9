"""Lesson 03's rows of ``posekit bench ik``: the neural solver's variants and its batched throughput.

Introduced in ``notebooks/03_autoencoder_solvers.ipynb``. Registered with
:func:`posekit.bench.ik.register_method`, they run when ``neural`` is among the run's solvers, on the
same cases and with the same metric code as every solver (so ``posekit bench ik --solvers fabrik,neural
--effectors 2,5`` prints Victor et al.'s Table 1 side by side in one run):

* ``neural-variants`` — ``neural-raw`` (the decoded pose, no post-processing), ``neural-fabrik`` (that
  pose as FABRIK's start) and, for sets the chain covers with more than one stage (5 effectors),
  ``neural-chained`` and ``neural-chained-raw`` (hands -> feet -> head, Sec. 3.5);
* ``neural-batched`` (group ``batched``) — :meth:`posekit.models.pose_autoencoder.solver.NeuralIKSolver.predict` on
  every case at once (repeated to about :data:`BATCH_SOLVES` problems), one thread: solves per second
  and microseconds per pose, with and without post-processing; and ``neural networks only``, one
  pose at a time through root frame, encoder, solver and decoder (the compiled single-pose path,
  without the Solver API's checks: the part the paper's 1.47 / 3.36 ms time).
"""

from __future__ import annotations

import time

import numpy as np

from ..ik.api import EFFECTOR_SETS
from ..ik.registry import make_solver
from .ik import MethodContext, evaluate_solver, register_method

__all__ = ["variant_rows", "batched_rows", "VARIANTS", "BATCH_SOLVES"]

BATCH_SOLVES = 20_000
"""About how many problems one batched call solves (the cases, repeated)."""

VARIANTS = ("neural-raw", "neural-fabrik", "neural-chained", "neural-chained-raw")
"""The registered variants of ``neural`` the plug-in adds (each skipped when already a solver of the run)."""


def _covered(solver, ctx: MethodContext):
    """``(set name, joints)`` of the run's effector sets the solver has networks for."""
    for e in ctx.effector_sets:
        joints = solver.skeleton.indices(EFFECTOR_SETS[e])
        try:
            solver.plan(joints)
        except ValueError:  # no network for this joint set: no row
            continue
        yield e, joints


def variant_rows(ctx: MethodContext) -> list[dict]:
    """The variants of :data:`VARIANTS` on each effector set their solvers cover."""
    cases, s = ctx.cases, ctx.cases.skeleton
    rows = []
    for name in VARIANTS:
        if name in ctx.solvers:
            continue
        solver = make_solver(name, s)
        for e, joints in _covered(solver, ctx):
            if solver.chain and len(solver.plan(joints)) < 2:  # a one-stage chain is the plain solver
                continue
            rows.append({"method": name, "effectors": e,
                         **evaluate_solver(solver, cases, e, ctx.tolerance, ctx.natural, ctx.natural_floor)})
    return rows


def batched_rows(ctx: MethodContext) -> list[dict]:
    """Batched throughput of the neural solver, without and with post-processing; and one pose at a time
    through the networks only (root frame, encode, solve, decode: what the paper times), without the
    Solver API's effector checks and result."""
    cases, s = ctx.cases, ctx.cases.skeleton
    rows = []
    raw = make_solver("neural-raw", s)
    for e, joints in _covered(raw, ctx):
        raw.predict_one(cases.start_pos[0], joints, cases.target_pos[0, joints])  # warm-up (JIT)
        lat = []
        for i in range(len(cases)):
            start, target = cases.start_pos[i], cases.target_pos[i, joints]
            t = time.perf_counter()
            raw.predict_one(start, joints, target)
            lat.append(time.perf_counter() - t)
        rows.append({"method": "neural networks only", "effectors": e, "cases": len(cases),
                     "latency_ms_median": float(np.median(lat) * 1e3)})
    for name in ("neural-raw", "neural"):
        solver = make_solver(name, s)
        for e, joints in _covered(solver, ctx):
            reps = max(1, BATCH_SOLVES // len(cases))
            start = np.tile(cases.start_pos, (reps, 1, 1))
            targets = np.tile(cases.target_pos[:, joints], (reps, 1, 1))
            solver.predict(start[:8], joints, targets[:8])  # warm-up
            t = time.perf_counter()
            solver.predict(start, joints, targets)
            dt = time.perf_counter() - t
            rows.append({"method": f"{name} batched", "effectors": e, "cases": len(start),
                         "solves_per_s": round(len(start) / dt), "us_per_pose": round(dt / len(start) * 1e6, 2)})
    return rows


register_method("neural-variants", variant_rows, group="neural", needs=("neural",),
                description="neural without post-processing, chained, and as FABRIK's start (lesson 03)")
register_method("neural-batched", batched_rows, group="batched", needs=("neural",),
                description="the neural solver on all cases at once: solves/s and us per pose (lesson 03)")
