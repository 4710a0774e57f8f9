"""Lesson 04's rows of ``posekit bench ik``: latent optimisation's variants and its batched throughput.

Introduced in ``notebooks/04_aegan_latent_space.ipynb``. Registered with
:func:`posekit.bench.ik.register_method`, they run when ``latent-opt`` is among the run's solvers, on the
same cases and with the same metric code as every solver (``posekit bench ik --solvers
fabrik,dls,neural,latent-opt --effectors 2,5 --start rest,same-clip,other-clip``):

* ``latent-variants`` — ``latent-opt-raw`` (the generator's pose, no post-processing),
  ``latent-opt-adam`` and ``latent-opt-adam-raw`` (Adam instead of L-BFGS);
* ``latent-batched`` (group ``batched``) — :meth:`posekit.models.aegan.solver.LatentOptSolver.predict` on
  every case at once (batched L-BFGS, each problem stopping on its own), one thread: solves per second
  and microseconds per pose.
"""

from __future__ import annotations

import time

import numpy as np

from ..ik.api import EFFECTOR_SETS, effector_set
from ..ik.registry import make_solver
from .ik import MethodContext, evaluate_solver, register_method

__all__ = ["variant_rows", "batched_rows", "VARIANTS"]

VARIANTS = ("latent-opt-raw", "latent-opt-adam", "latent-opt-adam-raw")
"""The registered variants of ``latent-opt`` the plug-in adds (each skipped when already a solver of the run)."""


def variant_rows(ctx: MethodContext) -> list[dict]:
    """The variants of :data:`VARIANTS` on each effector set of the run."""
    rows = []
    for name in VARIANTS:
        if name in ctx.solvers:
            continue
        solver = make_solver(name, ctx.cases.skeleton)
        for e in ctx.effector_sets:
            rows.append({"method": name, "effectors": e,
                         **evaluate_solver(solver, ctx.cases, e, ctx.tolerance, ctx.natural, ctx.natural_floor)})
    return rows


def batched_rows(ctx: MethodContext) -> list[dict]:
    """Every case of the run solved in one batched call (L-BFGS), without and with post-processing; the
    accuracy columns score those poses, so they can be set beside the one-at-a-time rows."""
    cases, s = ctx.cases, ctx.cases.skeleton
    rows = []
    for name in ("latent-opt-raw", "latent-opt"):
        solver = make_solver(name, s)
        for e in ctx.effector_sets:
            joints = s.indices(EFFECTOR_SETS[e])
            targets = cases.target_pos[:, joints]
            solver.predict(cases.start_pos[:4], joints, targets[:4], ctx.tolerance)  # warm-up
            t = time.perf_counter()
            pos, _, iters, _ = solver.predict(cases.start_pos, joints, targets, ctx.tolerance)
            dt = time.perf_counter() - t
            effs = [effector_set(s, e, cases.target_pos[i], ctx.tolerance) for i in range(len(cases))]
            rows.append({"method": f"{name} batched", "effectors": e, "cases": len(cases),
                         "solves_per_s": round(len(cases) / dt), "us_per_pose": round(dt / len(cases) * 1e6, 1),
                         "iterations_median": float(np.median(iters)), **ctx.score(pos, effs)})
    return rows


register_method("latent-variants", variant_rows, group="latent", needs=("latent-opt",),
                description="latent optimisation without post-processing and with L-BFGS (lesson 04)")
register_method("latent-batched", batched_rows, group="batched", needs=("latent-opt",),
                description="latent optimisation of all cases at once: solves/s and us per pose (lesson 04)")
