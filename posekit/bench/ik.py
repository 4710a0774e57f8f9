"""``posekit bench ik``: every IK solver on the same held-out real poses, side by side in one run.

Introduced in ``notebooks/01_fabrik.ipynb``. Cases come from :func:`posekit.data.cases.build_cases`:
targets are real poses of the *test* clips (the set's own split, or a clip-level split), the
effectors are the true positions of a named set of joints, and the start is another frame of the
target's clip within 1 s (``same-clip``), a frame of another held-out clip (``other-clip``) or the
rest pose (``rest``), pelvis on pelvis in the root frame. The targets are the same under every start
condition, and every row says which start condition it was measured on (``start``).

What it runs
------------
* **Solvers** — any name in :func:`posekit.ik.registry.solver_names` (``--solvers``), built with
  :func:`posekit.ik.registry.make_solver` and called one case at a time with ``solve(start, effectors)``:
  a solver registered by a later lesson or a student's notebook is benchmarked without editing this
  file (``--solvers all`` runs every registered solver that honours position effectors).
* **Methods** — rows that are not one solver's solves: the plain numpy FABRIK baseline, batched
  FABRIK throughput, peer libraries (ikpy). Each is a plug-in registered with :func:`register_method`
  (the built-in ones live in :mod:`posekit.bench.ik_methods`) and called once per start condition with
  a :class:`MethodContext`.

Metrics (JSON keys; definitions in :mod:`posekit.evaluation.pose_scores`, the same code for every solver):
``latency_ms_median`` (one solve, one thread, in the thread's CPU time:
:data:`posekit.bench.roofline.CLOCK`), ``effector_error_mm_median`` (worst effector of a
case), ``mpjpe_mm_median`` (body joints, pelvis-relative), ``bone_length_error_mm_max``,
``rotation_error_deg_median`` (solvers that return rotations), ``natural_mm_median`` (distance to the
nearest training pose) and ``natural_floor_mm_median`` (the true pose's own), ``converged_fraction``
(every effector within 1 mm), ``iterations_median``, ``memory_kb`` (peak Python allocation of one
solve, tracemalloc), ``model_kb`` / ``solver_kb`` (a learned solver's networks in float32: all that
one solve runs / the solver networks alone), ``solves_per_s`` and ``us_per_pose`` (batched),
``paper_latency_ms`` and ``paper_kb`` (Victor et al. 2021, Table 1), ``start``.
"""

from __future__ import annotations

import tracemalloc
import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .. import catalogue
from ..data.cases import START_ALIASES, START_CONDITIONS, Cases, build_cases, start_condition
from ..data.metrics import NaturalnessIndex
from ..evaluation.pose_scores import score_poses
from ..ik.api import EFFECTOR_SETS, effector_set
from ..ik.registry import make_solver, solver_info, solver_names
from ..plugins import Registry
from .plugin import arg, register_benchmark
from .verdicts import footer as verdict_footer
from .roofline import CLOCK

__all__ = ["Method", "MethodContext", "register_method", "unregister_method", "method_names", "get_method",
           "resolve_solvers", "evaluate_solver", "case_effectors", "effector_set_names", "SolverRefused", "RANDOM",
           "EFFECTOR_CHOICES", "weights_and_data", "SKIP_RULE",
           "run", "PAPER", "PAPER_KB", "TABLES", "TABLE_LABELS", "default_data"]

PAPER = {
    ("fabrik", "2"): 6.56,  # Victor et al. 2021, Table 1: full-body FABRIK runtime, ms
    ("fabrik", "5"): 6.74,
    ("neural", "2"): 1.47,  # ... and their neural solver (autoencoder + one solver)
    ("neural", "5"): 3.36,
}
"""Paper figures shown beside ours (runtime in ms)."""

PAPER_KB = {("neural", "2"): 442, ("neural", "5"): 826}
"""Victor et al. 2021, Table 1: memory of the neural solver, kB."""


# ---------------------------------------------------------------------------------------- methods
@dataclass
class MethodContext:
    """What a method plug-in gets, once per start condition.

    Attributes
    ----------
    cases : Cases
        The cases of this start condition (``cases.start``).
    effector_sets : tuple of str
        The run's effector sets (:data:`posekit.ik.EFFECTOR_SETS` names).
    solvers : tuple of str
        The run's solvers.
    tolerance : float, metres
    natural : NaturalnessIndex or None
    natural_floor : ndarray, shape (N,), metres, or None
        The true poses' own naturalness distance.
    """

    cases: Cases
    effector_sets: tuple
    solvers: tuple
    tolerance: float
    natural: NaturalnessIndex | None = None
    natural_floor: np.ndarray | None = None

    def score(self, result_pos, effectors, result_rot=None, cases: Cases | None = None) -> dict:
        """The shared accuracy metrics of poses a method produced (``score_poses(...).summary()``),
        for the first ``len(result_pos)`` cases."""
        c = self.cases if cases is None else cases
        n = len(result_pos)
        floor = None if self.natural_floor is None else self.natural_floor[:n]
        return score_poses(_head(c, n), result_pos, effectors, result_rot, self.natural, floor).summary()


def _head(cases: Cases, n: int) -> Cases:
    if n == len(cases):
        return cases
    cut = lambda a: None if a is None or np.ndim(a) == 0 else a[:n]
    return Cases(cases.skeleton, cases.start_rot[:n], cases.start_root[:n], cut(cases.start_local_pos),
                 cases.start_pos[:n], cases.target_pos[:n], cases.start, cases.source, cut(cases.target_rot),
                 cut(cases.target_root), cut(cases.target_local_pos), cut(cases.start_frame),
                 cut(cases.target_frame), cases.train_frames, cases.split)


@dataclass(frozen=True)
class Method:
    """A method plug-in of the ik benchmark (see :func:`register_method`)."""

    key: str
    run: Callable
    group: str = "extra"
    needs: tuple = ()
    description: str = ""


_METHODS = Registry("ik method", catalogue.BENCH_IK_METHODS)


def register_method(key: str, run: Callable, *, group: str = "extra", needs=(), description: str = "",
                    replace: bool = False) -> Method:
    """Add rows to every ``posekit bench ik`` run.

    Parameters
    ----------
    key : str
        Its name for ``--methods`` (e.g. ``"numpy-fabrik"``).
    run : callable
        ``run(ctx: MethodContext) -> list[dict]``, called once per start condition; each row needs
        ``method`` (its label) and ``effectors``; ``start`` and ``data`` are filled in. Use
        ``ctx.score(...)`` for accuracy columns so they mean what the solvers' mean.
    group : str
        ``"baseline"``, ``"batched"`` or ``"peer"`` (switched off by ``run(baseline=False)``, ...,
        ``--no-peers``), or anything else.
    needs : sequence of str
        Solvers that must be in the run (the FABRIK baseline runs only next to ``fabrik``).
    description : str
        One line for ``--help``.
    """
    m = Method(key, run, group, tuple(needs), description)
    return _METHODS.add(key, m, owner=getattr(run, "__module__", ""), replace=replace)


def unregister_method(key: str) -> None:
    """Remove a method (tests, notebooks)."""
    _METHODS.remove(key)


def method_names() -> list[str]:
    """Every registered method key: the built-in ones (:data:`posekit.catalogue.BENCH_IK_METHODS`) first."""
    return _METHODS.names()


def get_method(key: str) -> Method:
    return _METHODS.get(key)


# ---------------------------------------------------------------------------------------- solvers
def resolve_solvers(solvers) -> tuple:
    """Solver names of a run: a comma-separated string or a sequence; ``"all"`` is every registered
    solver that honours position effectors. Unknown names raise with the valid ones listed."""
    names = [n.strip() for n in (solvers.split(",") if isinstance(solvers, str) else solvers) if n.strip()]
    if names == ["all"]:
        names = [n for n in solver_names() if "position" in solver_info(n).kinds]
        if not names:
            raise ValueError("no registered solver honours position effectors (posekit.ik.registry is empty?)")
    for n in names:
        if "position" not in solver_info(n).kinds:  # raises for unknown names
            raise ValueError(f"solver {n!r} honours {', '.join(solver_info(n).kinds)} effectors only; "
                             "the ik benchmark's effector sets are positions")
    return tuple(dict.fromkeys(names))


RANDOM = "random"
"""The mixed-kind effector set of ``--effectors``: lesson 05's random benchmark rule drawn on each case
(:func:`posekit.evaluation.effector_cases.random_case_effectors`): 6-12 effectors, a position on every main
zone and the rest positions, rotations and look-ats on random body joints."""

EFFECTOR_CHOICES = (*EFFECTOR_SETS, RANDOM)
"""Every ``--effectors`` name: the named joint sets (:data:`posekit.ik.api.EFFECTOR_SETS`) and ``random``."""


class SolverRefused(ValueError):
    """A solver refused a benchmark's effectors (e.g. a neural solver with no network for those joints)."""


ONE_POINT = 1e-6
"""Two joints closer than this (metres) in a target pose sit on one point: a zero-length bone joins them (CMU's
Hips and LHipJoint), and no solver can place them apart."""


def _apart(skeleton, case: list, target_pos) -> list:
    """``case`` without the position effectors on a joint that sits on one point (:data:`ONE_POINT`) with the joint
    of an earlier position effector: the second of two such effectors asks nothing the first does not."""
    kept, taken = [], []
    for e in case:
        if e.kind == "position":
            p = np.asarray(target_pos[skeleton.index(e.joint)], float)
            if any(np.linalg.norm(p - q) < ONE_POINT for q in taken):
                continue
            taken.append(p)
        kept.append(e)
    return kept


def case_effectors(cases: Cases, effectors: str, tolerance: float = 1e-3, seed: int = 0) -> list[list]:
    """Every case's effectors: a named set at the true pose's joints, or the ``random`` mixed-kind draw.

    The ``random`` draw keeps one position effector per point: on a skeleton with zero-length bones (CMU's Hips
    and LHipJoint, its shoulders and spine joints) two drawn joints can sit on one point, and the second effector
    is dropped (:func:`_apart`); on a skeleton without such bones the draw is lesson 05's unchanged."""
    if effectors == RANDOM:
        from ..evaluation.effector_cases import random_case_effectors

        draw = random_case_effectors(cases, seed, tolerance)
        return [_apart(cases.skeleton, case, cases.target_pos[i]) for i, case in enumerate(draw)]
    return [effector_set(cases.skeleton, effectors, cases.target_pos[i], tolerance) for i in range(len(cases))]


def _take(cases: Cases, idx) -> Cases:
    """The cases at ``idx`` (an index array), every per-case array cut alike."""
    idx = np.asarray(idx, dtype=np.int64)
    if len(idx) == len(cases) and np.array_equal(idx, np.arange(len(cases))):
        return cases
    cut = lambda a: None if a is None or np.ndim(a) == 0 else np.asarray(a)[idx]
    return Cases(cases.skeleton, cases.start_rot[idx], cases.start_root[idx], cut(cases.start_local_pos),
                 cases.start_pos[idx], cases.target_pos[idx], cases.start, cases.source, cut(cases.target_rot),
                 cut(cases.target_root), cut(cases.target_local_pos), cut(cases.start_frame),
                 cut(cases.target_frame), cases.train_frames, cases.split)


def evaluate_solver(solver, cases: Cases, effectors: str, tolerance: float = 1e-3,
                    natural: NaturalnessIndex | None = None, natural_floor=None, seed: int = 0) -> dict:
    """One row's numbers: every case solved once from its start pose, timed one solve at a time on
    the calling thread (its CPU time, :data:`~posekit.bench.roofline.CLOCK`), then scored by
    :func:`posekit.evaluation.pose_scores.score_poses`.

    A solver is given the effectors of the kinds it honours (``solver.kinds``) and scored on all of them:
    with ``random`` a positions-only solver's rotation and look-at misses count against it.

    A case the solver refuses (a ``ValueError``: e.g. FABRIK given two effectors on one point) is counted, not
    fatal: ``refused_cases`` is how many, ``refused_reason`` the first refusal's sentence; the medians are over
    the cases it solved, and ``converged_fraction`` is over every case (a refused case did not converge).
    ``learned_kept_fraction``, for a learned solver with an exact finish (:mod:`posekit.ik.finish`), is the share
    of its solved cases whose result was finished from the learned pose (not DLS from the start pose).
    ``finish_rule``, for such a solver, is how it chose between its two answers: ``"natural"`` (the nearer a
    training pose: a naturalness comparison ran) or ``"learned"`` (no training poses of this skeleton: the
    learned pose's answer unless DLS got stuck there); None for every other solver.

    Raises
    ------
    SolverRefused
        The solver refused every case's effectors (its first message says why); nothing was measured.
    """
    effs = case_effectors(cases, effectors, tolerance, seed)
    given = [[e for e in case if e.kind in solver.kinds] for case in effs]
    reasons = {}
    warm = None
    for i in range(len(cases)):  # warm-up (JIT) on the first case the solver takes
        try:
            solver.solve(cases.pose(i), given[i])
            warm = i
            break
        except ValueError as err:
            reasons[i] = str(err)
    if warm is None:
        raise SolverRefused(next(iter(reasons.values())))
    lat, iters, pos, rots, solved, kept = [], [], [], [], [], []
    for i in range(len(cases)):
        if i in reasons:
            continue
        start = cases.pose(i)
        t = CLOCK()
        try:
            res = solver.solve(start, given[i])
        except ValueError as err:
            reasons[i] = str(err)
            continue
        lat.append(CLOCK() - t)
        pos.append(res.pose.global_pos)
        rots.append(res.pose.local_rot)
        iters.append(res.iterations)
        solved.append(i)
        info = getattr(res, "info", None) or {}
        if "learned_ms" in info:  # an exact finish (posekit.ik.finish): did it keep the learned pose?
            kept.append(info.get("kept") != "start")
    tracemalloc.start()
    solver.solve(cases.pose(warm), given[warm])
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    rot = np.stack(rots) if all(r is not None for r in rots) else None
    floor = None if natural_floor is None else np.asarray(natural_floor)[solved]
    scores = score_poses(_take(cases, solved), np.stack(pos), [effs[i] for i in solved], rot, natural,
                         floor).summary()
    if reasons:
        scores["converged_fraction"] = float(scores["converged_fraction"]) * len(solved) / len(cases)
    row = {"cases": len(cases), "latency_ms_median": float(np.median(lat) * 1e3), **scores,
           "iterations_median": float(np.median(iters)), "memory_kb": round(peak / 1024, 1),
           "refused_cases": len(reasons), "refused_reason": reasons[min(reasons)] if reasons else None,
           "learned_kept_fraction": float(np.mean(kept)) if kept else None,
           "finish_rule": getattr(solver, "choose", None) if kept else None}
    if hasattr(solver, "sizes_kb") and effectors in EFFECTOR_SETS:  # a learned solver: the networks one solve runs
        row.update(solver.sizes_kb(EFFECTOR_SETS[effectors]))
    return row


def effector_set_names(effector_sets) -> tuple:
    """``"2,5,random"`` or a sequence -> a tuple of :data:`EFFECTOR_CHOICES` names; unknown names raise."""
    names = tuple(dict.fromkeys(str(e).strip() for e in (effector_sets.split(",") if isinstance(effector_sets, str)
                                                          else effector_sets) if str(e).strip()))
    for e in names:
        if e not in EFFECTOR_CHOICES:
            raise ValueError(f"unknown effector set {e!r}; valid: {', '.join(EFFECTOR_CHOICES)}")
    if not names:
        raise ValueError(f"no effector set given; valid: {', '.join(EFFECTOR_CHOICES)}")
    return names


def _starts(start) -> tuple:
    names = [n.strip() for n in (start.split(",") if isinstance(start, str) else list(start)) if n.strip()]
    return tuple(dict.fromkeys(start_condition(n.strip()) for n in names if n.strip()))


def _methods(methods, baseline: bool, batched: bool, peers: bool, solvers) -> list[Method]:
    if methods is None or methods == "all":
        keys = method_names()
    elif methods == "none":
        keys = []
    else:
        keys = [k.strip() for k in (methods.split(",") if isinstance(methods, str) else methods) if k.strip()]
    chosen = [get_method(k) for k in keys]
    off = {g for g, on in (("baseline", baseline), ("batched", batched), ("peer", peers)) if not on}
    return [m for m in chosen if m.group not in off and set(m.needs) <= set(solvers)]


def run(motions, solvers=("fabrik", "ccd", "dls"), effector_sets=("2", "5"), n_cases: int = 1000,
        start="same-clip", seed: int = 0, tolerance: float = 1e-3, baseline: bool = True,
        batched: bool = True, peers: bool = True, methods=None, natural: bool = True,
        progress: bool = False, refused: dict | None = None) -> list[dict]:
    """Run the benchmark; one row (dict) per method, effector set and start condition.

    Parameters
    ----------
    motions : MotionSet
    solvers : str or sequence of str
        Registered solver names (or ``"all"``).
    effector_sets : sequence of str
    n_cases : int
        Cases per start condition.
    start : str or sequence of str
        Start conditions (comma-separated or a sequence): ``same-clip`` (alias ``frame``),
        ``other-clip``, ``rest``.
    seed : int
    tolerance : float, metres
    baseline, batched, peers : bool
        Run the method plug-ins of these groups.
    methods : str or sequence, optional
        Method keys to run (default every registered method; ``"none"`` for solvers only).
    natural : bool
        Measure the naturalness distance (to the nearest training pose).
    refused : dict, optional
        Filled with ``{(solver, effector set): reason}`` for the solvers that refused a set's effectors
        (no row; a warning says so too).
    """
    from ..learn.threads import single_thread

    every = solvers == "all" or list(solvers) == ["all"]
    solvers = resolve_solvers(solvers)
    effector_sets = effector_set_names(effector_sets)
    if int(n_cases) < 1:
        raise ValueError(f"--cases must be at least 1, got {n_cases}")
    starts = _starts(start)
    extras = _methods(methods, baseline, batched, peers, solvers)
    all_cases = {st: build_cases(motions, n_cases, seed, st) for st in starts}  # every refusal before any work
    first = all_cases[starts[0]]
    s = first.skeleton
    nat = floor = None
    if natural:
        nat = NaturalnessIndex(s, motions.global_pos[first.train_frames], seed=seed)
        floor = nat.distance(first.target_pos)  # the targets are the same under every start condition
    from ..ik.finish import judged_on
    from ..paths import held_checkpoints, use_skeleton

    built, skipped = {}, {}
    held = held_checkpoints()
    # among several checkpoints of one model in --weights DIR: the one for this data; an exact finish judges its
    # answers against this data's training poses (the natural column's), whatever skeleton it is
    with use_skeleton(s.names), judged_on(motions, first.train_frames):
        for name in solvers:
            try:
                built[name] = make_solver(name, s)
            except ValueError as err:
                if not every:  # named in --solvers: refused, with what the weights folder holds (SKIP_RULE)
                    raise ValueError(f"{name!r}, named in --solvers, cannot pose this data: {err}"
                                     + (f"; {held}" if held else "")
                                     + "; leave it out, or give --solvers all to skip it") from None
                skipped[name] = str(err)
    if skipped:
        first_reason = next(iter(skipped.values()))
        warnings.warn(f"bench ik: skipping solver(s) {', '.join(map(repr, skipped))} on {first.source!r} "
                      f"({first_reason[:200]}{'...' if len(first_reason) > 200 else ''})"
                      + (f"; a learned solver takes a checkpoint from your weights folder when the checkpoint says it "
                         f"is that model, and {held}" if held else ""), UserWarning, stacklevel=2)
    solvers = tuple(built)
    jobs = [(st, name, e) for st in starts for name in solvers for e in effector_sets]
    bar = None
    if progress:
        from ..progress import tqdm

        bar = tqdm(total=len(jobs) + len(starts) * len(extras), desc="bench ik", unit="row")
    rows = []
    refused = {} if refused is None else refused
    with single_thread():
        for st in starts:
            cases = all_cases[st]
            for name in solvers:
                for e in effector_sets:
                    try:
                        row = {"method": name, "effectors": e, "start": st,
                               **evaluate_solver(built[name], cases, e, tolerance, nat, floor, seed)}
                    except SolverRefused as err:
                        refused.setdefault((name, e), str(err))
                        row = None
                    if row is not None:
                        if (name, e) in PAPER:
                            row["paper_latency_ms"] = PAPER[(name, e)]
                        if (name, e) in PAPER_KB:
                            row["paper_kb"] = PAPER_KB[(name, e)]
                        rows.append(row)
                    if bar is not None:
                        bar.update()
            named = tuple(e for e in effector_sets if e in EFFECTOR_SETS)  # the methods place named sets only
            ctx = MethodContext(cases, named, solvers, tolerance, nat, floor)
            for m in extras:
                for r in m.run(ctx):
                    r.setdefault("start", st)
                    rows.append(r)
                if bar is not None:
                    bar.update()
    if bar is not None:
        bar.close()
    partly = [r for r in rows if r.get("refused_cases")]
    if partly:
        warnings.warn("bench ik: cases refused (counted, not measured): "
                      + "; ".join(f"{r['method']!r} {r['refused_cases']} of {r['cases']} on set {r['effectors']!r} "
                                  f"from {r['start']}" for r in partly[:4]) + ("; ..." if len(partly) > 4 else "")
                      + f" (the first said: {partly[0]['refused_reason'][:160]})", UserWarning, stacklevel=2)
    if refused:
        warnings.warn("bench ik: not measured (the solver refused the effectors): "
                      + "; ".join(f"{n!r} on set {e!r} ({why[:160]})" for (n, e), why in refused.items()),
                      UserWarning, stacklevel=2)
    for r in rows:
        r.setdefault("data", first.source)
    return rows


# ---------------------------------------------------------------------------------------- the CLI
TABLES = [
    ("Speed (one solve, one thread; batched: solves/s over all cases at once)",
     ["method", "effectors", "cases", "latency_ms_median", "paper_latency_ms", "memory_kb", "solves_per_s",
      "us_per_pose"]),
    ("Size of the learned solvers (float32 networks one solve runs; solver: without the autoencoder)",
     ["method", "effectors", "model_kb", "solver_kb", "paper_kb"]),
    ("Accuracy (medians over cases; bone error: the worst case)",
     ["method", "effectors", "effector_error_mm_median", "effector_error_deg_median", "converged_fraction",
      "iterations_median", "bone_length_error_mm_max"]),
    ("Pose (medians over cases; body joints, pelvis-relative; floor: the true pose's own naturalness)",
     ["method", "effectors", "mpjpe_mm_median", "rotation_error_deg_median", "natural_mm_median",
      "natural_floor_mm_median"]),
    ("Refused cases (not scored) and the exact finish (learned kept: finished from the learned pose)",
     ["method", "effectors", "refused_cases", "learned_kept_fraction"],
     lambda r: bool(r.get("refused_cases")) or r.get("learned_kept_fraction") is not None),
]
"""The tables ``posekit bench ik`` prints per start condition: (title, JSON keys). Each fits 100 columns."""

TABLE_LABELS = {
    "effectors": "effectors", "latency_ms_median": "ms", "paper_latency_ms": "paper ms", "memory_kb": "kB",
    "solves_per_s": "solves/s", "model_kb": "model kB", "solver_kb": "solver kB", "paper_kb": "paper kB",
    "us_per_pose": "us/pose", "effector_error_mm_median": "effector mm", "effector_error_deg_median": "effector deg",
    "converged_fraction": "converged", "refused_cases": "refused", "learned_kept_fraction": "learned kept",
    "iterations_median": "iters", "bone_length_error_mm_max": "bone mm",
    "mpjpe_mm_median": "MPJPE mm", "rotation_error_deg_median": "rotation deg", "natural_mm_median": "natural mm",
    "natural_floor_mm_median": "floor mm",
}
"""Short table headers for the JSON keys (units in the header)."""

TABLE_COLUMNS = ["method"] + list(dict.fromkeys(c for t in TABLES for c in t[1] if c != "method"))
"""Every column in one table (``posekit bench ik --wide``)."""


WEIGHTS_HELP = ("a folder of checkpoints you trained (posekit train NAME --data DATA --out DIR/ANY_NAME.pt): each learned "
                "solver loads the checkpoint in DIR that says it is its model, whatever the file is called: neural* "
                "(kind ae_solvers: train ae-solvers), latent-opt* (kind aegan, structured: train aegan without "
                "--dense), protores, protores-masked-fcr, protores-transformer (kind protores, arch protores, "
                "masked-fcr or transformer: train protores --arch ...); of several checkpoints of one model, the one "
                "trained for --data's skeleton, else the one with the shipped file's name (ae_solvers.pt, aegan.pt, "
                "protores.pt, protores_masked_fcr.pt, protores_transformer.pt); a model DIR lacks is the shipped one "
                "(made for the Bandai skeleton); a .pt in DIR that is not a posekit checkpoint is refused, by name; "
                "give --data too. ")
"""``--weights DIR`` of ``posekit bench ik`` and ``bench all``: how a checkpoint is found (:func:`posekit.paths.find_checkpoint`)."""

SKIP_RULE = ("A learned solver that cannot pose --data's skeleton (a model made for another one) is refused, exit "
             "status 2, with the reason and what DIR holds, when --solvers names it; it is skipped, with a warning "
             "that names it, under --solvers all and in posekit bench all.")
"""The one rule of ``posekit bench ik`` and ``bench all`` for a solver that cannot pose the data (both commands'
``--help`` and docs/own-mocap.md say it)."""

WEIGHTS_HELP += SKIP_RULE


def weights_and_data(args, solvers) -> tuple:
    """``--weights DIR`` and ``--data`` of a benchmark's command line: the weights context
    (:func:`posekit.paths.use_weights`, or a null context) and the data to open. With ``--weights`` the data must
    be named too (the data those weights were trained on); refused before any work with a sentence saying so."""
    import contextlib

    from ..paths import use_weights

    if getattr(args, "weights", None) is None:
        return contextlib.nullcontext(), (default_data(solvers) if args.data is None else args.data)
    if args.data is None:
        raise ValueError(f"--weights {args.weights}: name the data those weights were trained on with --data "
                         "(the BVH folder or file given to `posekit train ... --data`, or a shipped set's name)")
    return use_weights(args.weights), args.data


def _cli_run(args) -> list[dict]:

    from ..data.sources import open_dataset

    solvers = resolve_solvers(args.solvers)  # refuse bad names before loading data
    _starts(args.start)
    weights, data = weights_and_data(args, solvers)
    show = True  # on stderr: a bar in a terminal, a line every few seconds in a log (posekit.progress)
    with weights:
        motions = open_dataset(data, scale=args.scale, progress=show)
        return run(motions, solvers=solvers, effector_sets=args.effectors.split(","), n_cases=args.cases,
                   start=args.start, seed=args.seed, peers=not args.no_peers, methods=args.methods, progress=show)


def default_data(solvers) -> str:
    """The data a run uses when ``--data`` is not given: the one data set the run's learned solvers were
    trained on (:attr:`posekit.ik.registry.SolverInfo.data`), else the DeepMimic ``sample``."""
    sets = {solver_info(n).data for n in solvers} - {""}
    if len(sets) > 1:
        raise ValueError(f"the solvers of this run were trained on different data sets ({', '.join(sorted(sets))}); "
                         "choose one with --data")
    return sets.pop() if sets else "sample"


def _header(rows, args) -> str:
    data = rows[0]["data"] if rows else args.data
    return (f"IK benchmark: {data}, {args.cases} held-out cases per start condition (the same targets), one thread\n"
            "errors in mm, angles in degrees; effector: the worst of a case; MPJPE, rotation and natural: body "
            "joints, pelvis-relative; natural: distance to the nearest training pose; converged: every "
            "effector within 1 mm")


def _group_title(start: str) -> str:
    return f"Start: {start} ({START_CONDITIONS.get(start, start)})"


_START_HELP = ", ".join(f"{k} ({v})" for k, v in START_CONDITIONS.items())
_ALIAS_HELP = ", ".join(f"{a} = {b}" for a, b in START_ALIASES.items())

register_benchmark(
    "ik", _cli_run,
    help="IK solvers on held-out real poses, side by side (Table 1 of Victor et al. 2021, in its style)",
    args=[
        arg("--solvers", default="fabrik,ccd,dls",
            help="comma-separated registered solvers (posekit.ik.registry), e.g. fabrik, fabrik-constrained, "
                 "ccd, dls, or all"),
        arg("--effectors", default="2,5", help="comma-separated effector sets: 2 (hands), 5 (hands, feet, head), "
                                               "5point (hands, feet, chest), random (lesson 05's mixed kinds)"),
        arg("--start", default="same-clip",
            help=f"comma-separated start conditions: {_START_HELP}; alias {_ALIAS_HELP}"),
        arg("--cases", type=int, default=1000, help="held-out (start, target) cases per start condition"),
        arg("--data", default=None,
            help="sample, bandai-mini, bandai1, bandai2, or a BVH file/folder or .npz (default: the data the learned "
                 "solvers of the run were trained on, e.g. bandai-mini for neural; else sample)"),
        arg("--weights", default=None, help=WEIGHTS_HELP),
        arg("--scale", type=float, default=None,
            help="file units to metres for a BVH path (default: detected from the skeleton's height)"),
        arg("--seed", type=int, default=0, help="seed of the held-out split and of the case draw"),
        arg("--methods", default="all",
            help="comma-separated extra methods (numpy-fabrik: the plain numpy baseline, fabrik-batched, ikpy), "
                 "all or none"),
        arg("--no-peers", action="store_true", help="skip peer libraries (ikpy)"),
    ],
    tables=TABLES, labels=TABLE_LABELS, header=_header, group_by="start", group_title=_group_title, wide=True,
    footer=verdict_footer, lesson="notebooks/01_fabrik.ipynb")
