"""The ik benchmark's built-in method plug-ins: rows that are not one registered solver's solves.

Introduced in ``notebooks/01_fabrik.ipynb``. Each function below is registered with
:func:`posekit.bench.ik.register_method` and called once per start condition:

* ``fabrik-as-published`` (group ``paper``) — full-body FABRIK as Aristidou & Lasenby 2011 publish it, without
  posekit's near-extended step (``FabrikSolver(extended=False)``), scored like every solver: the row a claim
  compared with a paper's FABRIK needs (run only next to ``fabrik``);
* ``numpy-fabrik`` (group ``baseline``) — the same full-body FABRIK as :class:`~posekit.ik.FabrikSolver` in
  plain numpy, joint by joint, no compilation: :func:`posekit.ik.fabrik_batched.fabrik_batched` given one
  problem at a time; its latency is the yardstick of the compiled solver (run only next to ``fabrik``);
* ``fabrik-batched`` (group ``batched``) — :func:`posekit.ik.fabrik_batched.fabrik_batched`
  throughput over all cases at once;
* ``ikpy`` (group ``peer``) — the ikpy library on one chain (pelvis -> left hand), beside posekit's
  FABRIK on the same chain; absent when ikpy is not installed.
"""

from __future__ import annotations

import time

import numpy as np

from ..ik.api import EFFECTOR_SETS, Effector
from ..ik.fabrik_batched import fabrik_batched
from ..ik.registry import make_solver
from .ik import PAPER, MethodContext, evaluate_solver, register_method

__all__ = ["as_published_rows", "baseline_rows", "batched_rows", "ikpy_rows", "BASELINE_CASES", "BATCH_SOLVES",
           "PEER_CASES"]

BASELINE_CASES = 200
"""Cases the (slow) numpy baseline solves per effector set."""

BATCH_SOLVES = 20_000
"""About how many problems batched FABRIK solves at once (the cases, repeated)."""

PEER_CASES = 100
"""Cases a peer library solves."""


def as_published_rows(ctx: MethodContext) -> list[dict]:
    """Full-body FABRIK without posekit's near-extended step, on every named effector set, scored and timed by
    :func:`~posekit.bench.ik.evaluate_solver` like the registered solvers."""
    from ..ik.fabrik import FabrikSolver

    solver = FabrikSolver(ctx.cases.skeleton, extended=False)
    rows = []
    for e in ctx.effector_sets:
        row = {"method": "fabrik (as published)", "effectors": e,
               **evaluate_solver(solver, ctx.cases, e, ctx.tolerance, ctx.natural, ctx.natural_floor)}
        if ("fabrik", e) in PAPER:           # the paper's FABRIK time, beside the algorithm it timed
            row["paper_latency_ms"] = PAPER[("fabrik", e)]
        rows.append(row)
    return rows


def baseline_rows(ctx: MethodContext) -> list[dict]:
    """The numpy baseline's latency on the first :data:`BASELINE_CASES` cases of each effector set."""
    cases, s = ctx.cases, ctx.cases.skeleton
    m = min(BASELINE_CASES, len(cases))
    rows = []
    for e in ctx.effector_sets:
        eff = s.indices(EFFECTOR_SETS[e])
        lat = []
        for i in range(m):
            t = time.perf_counter()
            fabrik_batched(s, cases.start_pos[i:i + 1], eff, cases.target_pos[i:i + 1, eff], ctx.tolerance)
            lat.append(time.perf_counter() - t)
        rows.append({"method": "baseline: numpy per-joint FABRIK", "effectors": e, "cases": m,
                     "latency_ms_median": float(np.median(lat) * 1e3)})
    return rows


def batched_rows(ctx: MethodContext) -> list[dict]:
    """Batched FABRIK over every case at once (repeated to about :data:`BATCH_SOLVES` problems)."""
    cases, s = ctx.cases, ctx.cases.skeleton
    rows = []
    for e in ctx.effector_sets:
        eff = s.indices(EFFECTOR_SETS[e])
        reps = max(1, BATCH_SOLVES // len(cases))
        start = np.tile(cases.start_pos, (reps, 1, 1))
        targets = np.tile(cases.target_pos[:, eff], (reps, 1, 1))
        t = time.perf_counter()
        _, conv, _ = fabrik_batched(s, start, eff, targets, ctx.tolerance)
        dt = time.perf_counter() - t
        rows.append({"method": "fabrik batched", "effectors": e, "cases": len(start),
                     "solves_per_s": round(len(start) / dt), "converged_fraction": float(conv.mean())})
    return rows


def ikpy_rows(ctx: MethodContext) -> list[dict]:
    """ikpy (a peer library) on one chain, pelvis -> left hand, beside posekit's FABRIK on the same
    chain (when ``fabrik`` is in the run)."""
    try:
        import ikpy
        from ikpy.chain import Chain
        from ikpy.link import OriginLink, URDFLink
    except ImportError:  # a peer that is not installed is simply absent
        return []
    from ..rotations import quat_to_euler

    cases, s, tolerance = ctx.cases, ctx.cases.skeleton, ctx.tolerance
    n = min(PEER_CASES, len(cases))
    chain_j = s.chain("left_hand", "pelvis")
    links = [OriginLink()]
    for j in chain_j[:-1]:
        off = s.offsets[j] if j != chain_j[0] else np.zeros(3)
        for k, axis in enumerate(np.eye(3)):
            links.append(URDFLink(name=f"{s.names[j]}_{'xyz'[k]}", origin_translation=off if k == 0 else np.zeros(3),
                                  origin_orientation=np.zeros(3), rotation=axis))
    links.append(URDFLink(name=s.names[chain_j[-1]], origin_translation=s.offsets[chain_j[-1]],
                          origin_orientation=np.zeros(3), joint_type="fixed"))
    mask = [False] + [True] * (3 * (len(chain_j) - 1)) + [False]
    chain = Chain(links, active_links_mask=mask)
    ours = make_solver("fabrik", s) if "fabrik" in ctx.solvers else None
    hand = s.index("left_hand")
    lat, err, lat_pk, err_pk = [], [], [], []
    for i in range(n):
        pel = cases.start_pos[i, chain_j[0]]
        target = cases.target_pos[i, hand]
        angles = [0.0]
        for j in chain_j[:-1]:  # three revolute links x, y, z per joint: intrinsic XYZ Euler angles
            angles += list(quat_to_euler(cases.start_rot[i, j], "XYZ"))
        angles.append(0.0)
        # ikpy's base frame is the pelvis position with the world axes: the pelvis rotation is its
        # first three joints, as for posekit's solvers
        t = time.perf_counter()
        sol = chain.inverse_kinematics(target - pel, initial_position=np.array(angles))
        lat.append(time.perf_counter() - t)
        err.append(np.linalg.norm(chain.forward_kinematics(sol)[:3, 3] + pel - target))
        if ours is not None:
            t = time.perf_counter()
            res = ours.solve(cases.pose(i), [Effector(hand, target, tolerance=tolerance)])
            lat_pk.append(time.perf_counter() - t)
            err_pk.append(np.linalg.norm(res.pose.global_pos[hand] - target))
    version = getattr(ikpy, "__version__", "?")
    row = lambda name, l, e: {"method": name, "effectors": "left_hand", "cases": len(l),
                              "latency_ms_median": float(np.median(l) * 1e3),
                              "effector_error_mm_median": float(np.median(e) * 1e3),
                              "converged_fraction": float(np.mean(np.array(e) <= tolerance))}
    rows = [row(f"ikpy {version} (one chain)", lat, err)]
    if ours is not None:
        rows.append(row("fabrik (same chain)", lat_pk, err_pk))
    return rows


register_method("fabrik-as-published", as_published_rows, group="paper", needs=("fabrik",),
                description="full-body FABRIK as Aristidou & Lasenby 2011 publish it, without the near-extended step")
register_method("numpy-fabrik", baseline_rows, group="baseline", needs=("fabrik",),
                description="the same FABRIK in plain numpy, one joint at a time (the speed yardstick)")
register_method("fabrik-batched", batched_rows, group="batched", needs=("fabrik",),
                description="batched FABRIK: solves/s over all cases at once")
register_method("ikpy", ikpy_rows, group="peer",
                description="ikpy on the pelvis -> left hand chain, beside FABRIK on the same chain")
