"""Compile every solver's kernels into the cache once, before anyone waits for them: ``posekit warm``.

The numba kernels behind the solvers (FABRIK, CCD, DLS, the learned solvers' numpy paths and their exact
finishes) are compiled at their first call and cached on disk (:mod:`posekit._jit`), keyed on every source
file. On a fresh clone, or after any change to the package, the first solve of each lesson would compile
(1-9 s per solver) and every process starting at the same time would compile the same kernels again: the
notebook kernels and test workers of ``make test``, a class's studio kernels. ``make lab``, ``make studio``
and ``make test`` run this first: it solves one small case with every registered solver in two processes
(the classical solvers in one, the learned ones in the other), so every later process loads the kernels in
milliseconds. When the cache already holds this source version's kernels it returns at once.
"""

from __future__ import annotations

import json
import time
from concurrent.futures import ProcessPoolExecutor

__all__ = ["warm", "MARKER"]

MARKER = "warm.json"
"""File written in the cache folder once every solver's kernels are in it (what was compiled, and what not)."""


def _solve_each(names: list) -> dict:
    """Solve one case, and a batch of two, with each named solver; returns name -> None or why it was skipped."""
    import numpy as np

    from .data.cases import build_cases
    from .ik.api import Effector, effector_errors_batch, effector_set
    from .kinematics import fk
    from .ik.registry import make_solver, solver_info

    cases, out = {}, {}
    for name in names:
        info = solver_info(name)
        try:
            if info.data not in cases:
                if info.data == "bandai-mini":
                    from .data.bandai_mini import load_bandai_mini as load
                else:
                    from .data import load_sample as load
                cases[info.data] = build_cases(load(), 3, seed=0)
            c = cases[info.data]
            solver = make_solver(name, c.skeleton)
            effectors = effector_set(c.skeleton, "5", c.target_pos[0])
            if "rotation" in info.kinds:
                effectors.append(Effector("head", np.eye(3), kind="rotation"))
            if "look_at" in info.kinds:
                effectors.append(Effector("left_hand", c.target_pos[0][0] + 1.0, kind="look_at"))
            starts = [c.pose(k) for k in range(2)] if info.needs_start else [None, None]
            solver.solve(starts[0], effectors)
            solver.solve_batch(starts, [effectors, effectors])
            if name == names[0]:  # the scores' batched error kernel (benchmarks, lesson tables)
                P, R = fk(c.skeleton, c.start_rot[:2], c.start_root[:2], c.start_local_pos[:2]
                          if c.start_local_pos is not None else None)
                effector_errors_batch(c.skeleton, P, R, effectors)
            out[name] = None
        except Exception as err:  # noqa: BLE001 - a solver that cannot run here (no weights) is reported, not fatal
            out[name] = f"{type(err).__name__}: {err}"
    return out


def warm(workers: int = 2, force: bool = False) -> dict:
    """Compile every registered solver's kernels into the cache (see the module docstring).

    Parameters
    ----------
    workers : int
        Processes compiling side by side (1: in this process).
    force : bool
        Compile again even when the cache says it is done.

    Returns
    -------
    dict
        ``cache`` (the folder, or None when caching is off), ``done`` (True when it was already warm),
        ``seconds``, ``solvers`` (how many were solved) and ``skipped`` (name -> why).
    """
    from ._jit import HAVE_NUMBA, cache_dir
    from .ik.registry import solver_info, solver_names

    folder = cache_dir() if HAVE_NUMBA else None
    if folder is None:
        return {"cache": None, "done": False, "seconds": 0.0, "solvers": 0, "skipped": {}}
    marker = folder / MARKER
    if marker.exists() and not force:
        return {**json.loads(marker.read_text()), "cache": str(folder), "done": True}
    t0 = time.perf_counter()
    names = solver_names()
    learned = [n for n in names if solver_info(n).data]
    groups = [[n for n in names if n not in learned], learned]  # about 16 s and 24 s of one core, cold
    if workers > 1:
        with ProcessPoolExecutor(max_workers=min(workers, len(groups))) as pool:
            results = list(pool.map(_solve_each, groups))
    else:
        results = [_solve_each(g) for g in groups]
    outcome = {k: v for r in results for k, v in r.items()}
    report = {"seconds": round(time.perf_counter() - t0, 1), "solvers": sum(v is None for v in outcome.values()),
              "skipped": {k: v for k, v in outcome.items() if v is not None}}
    marker.write_text(json.dumps(report, indent=1))
    return {**report, "cache": str(folder), "done": False}
