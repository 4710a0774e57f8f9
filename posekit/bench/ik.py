"""``posekit bench ik``: every IK solver on the same held-out real poses, side by side in one run.

Introduced in ``notebooks/01_fabrik.ipynb``. Cases come from the *test* clips of a clip-level split
(no clip a learned solver trains on): the target is a real pose, the effectors are the true positions
of its chosen joints, and the start is another frame of the same clip (``start="frame"``) or the rest
pose (``start="rest"``). Both poses are expressed in the root frame (Victor & Meyer 2020, Sec. 3.2)
and the start is shifted so its pelvis sits on the target's: every solver keeps the pelvis fixed, so
every case is reachable and the target pose is one exact solution.

Metrics per method and effector set (JSON keys): ``latency_ms_median`` (one solve, one thread),
``effector_error_mm_median`` (worst effector of a case), ``mpjpe_mm_median`` (mean distance of all
joints to the true pose — the "naturalness" the learned solvers are about), ``bone_length_error_mm_max``,
``converged_fraction`` (every effector within 1 mm), ``iterations_median``, ``memory_kb`` (peak Python
allocation of one solve, tracemalloc), plus batched-FABRIK throughput, a plain numpy FABRIK as the
baseline, peers (ikpy) and the paper's figures.
"""

from __future__ import annotations

import time
import tracemalloc
from dataclasses import dataclass

import numpy as np

from ..data import MotionSet, sample_pairs, split_by_clip
from ..ik import CCDSolver, DLSSolver, FabrikSolver
from ..ik.api import EFFECTOR_SETS, Effector, Pose, base_index, effector_set
from ..kinematics import bone_lengths_of, fk
from ..transforms import rotate_y_rotations, to_root_space

__all__ = ["Cases", "build_cases", "SOLVERS", "register_solver", "make_solver", "run", "PAPER"]

PAPER = {
    ("fabrik", "2"): 6.56,  # Victor & Meyer 2020, Table 1: full-body FABRIK runtime, ms
    ("fabrik", "5"): 6.74,
}
"""Paper figures shown beside ours (runtime in ms)."""


SOLVERS = {
    "fabrik": FabrikSolver,
    "fabrik-constrained": lambda s: FabrikSolver(s, constraints=True),
    "ccd": CCDSolver,
    "dls": DLSSolver,
}
"""Solver name -> factory(skeleton). Later lessons register their solvers here."""


def register_solver(name: str, factory):
    """Make ``posekit bench ik --solvers NAME`` build a solver with ``factory(skeleton)``."""
    SOLVERS[name] = factory


def make_solver(name: str, skeleton):
    if name not in SOLVERS:
        raise ValueError(f"unknown solver {name!r}; valid: {', '.join(SOLVERS)}")
    return SOLVERS[name](skeleton)


@dataclass
class Cases:
    """Benchmark cases.

    Attributes
    ----------
    skeleton : Skeleton
    start_rot : ndarray, shape (N, J, 4)
    start_root : ndarray, shape (N, 3)
    start_local_pos : ndarray, shape (N, J, 3) or None
    start_pos : ndarray, shape (N, J, 3)
    target_pos : ndarray, shape (N, J, 3)
        True poses; effector targets are taken from them.
    start : str
    source : str
    """

    skeleton: object
    start_rot: np.ndarray
    start_root: np.ndarray
    start_local_pos: np.ndarray | None
    start_pos: np.ndarray
    target_pos: np.ndarray
    start: str
    source: str

    def __len__(self):
        return len(self.target_pos)

    def pose(self, i) -> Pose:
        lp = None if self.start_local_pos is None else self.start_local_pos[i]
        return Pose(self.start_pos[i], self.start_rot[i], self.start_root[i], lp)


def build_cases(motions: MotionSet, n_cases: int = 1000, seed: int = 0, start: str = "frame",
                split=(0.8, 0.1, 0.1)) -> Cases:
    """Held-out cases (see the module docstring). With fewer clips than split sets (one or two BVH
    files) the held-out frames are the end of every clip instead, with a warning
    (:func:`posekit.data.split_by_clip` with ``fallback=True``)."""
    s = motions.skeleton
    test = split_by_clip(motions, split, seed=seed, fallback=True)[2]
    a, b = sample_pairs(motions, n_cases, rng=seed, frames=test)
    frames = np.unique(np.concatenate([a, b]))
    local, origin, angle = to_root_space(s, motions.global_pos[frames])
    q, root = rotate_y_rotations(motions.local_rot[frames], motions.root_pos[frames] - origin, -angle)
    where = {f: i for i, f in enumerate(frames)}
    ia, ib = np.array([where[f] for f in a]), np.array([where[f] for f in b])
    target = local[ib]
    lp_all = None if motions.local_pos is None else motions.local_pos[frames]
    pel = base_index(s)
    if start == "frame":
        rot, rpos = q[ia], root[ia].copy()
        lp = None if lp_all is None else lp_all[ia]
        pos = local[ia]
    elif start == "rest":
        if lp_all is not None:
            raise ValueError(f"start='rest' needs a skeleton whose rest pose is a standing pose; "
                             f"{s.name!r} animates joint translations, use start='frame'")
        rot = np.broadcast_to([0.0, 0.0, 0.0, 1.0], (len(a), s.n_joints, 4)).copy()
        rpos = np.broadcast_to(s.offsets[0], (len(a), 3)).copy()
        lp = None
        pos = fk(s, rot, rpos)[0]
    else:
        raise ValueError(f"start must be 'frame' or 'rest', got {start!r}")
    shift = target[:, pel] - pos[:, pel]
    return Cases(s, rot, rpos + shift, lp, pos + shift[:, None], target, start, motions.source)


def _numpy_fabrik(skeleton, start, eff, targets, tol=1e-3, max_iter=20):
    """Baseline: the same full-body FABRIK as :class:`~posekit.ik.FabrikSolver` — backward pass with
    plain centroids at the sub-bases, near-extended chains straightened
    (:func:`~posekit.ik.fabrik.straighten_chain`), forward pass — written the straightforward way,
    numpy vector ops per joint and no compilation, as a newcomer would after the lesson."""
    from ..ik.fabrik import effector_chains, straighten_chain

    parents = skeleton.parents
    pos = start.copy()
    L = np.linalg.norm(pos - pos[np.maximum(parents, 0)], axis=1)
    fixed = np.zeros(len(parents), dtype=bool)
    fixed[skeleton.chain(base_index(skeleton), 0)] = True
    active = set()
    for e in eff:
        active.update(skeleton.chain(int(e), 0))
    chains = effector_chains(skeleton, eff, fixed)
    goal = {int(e): targets[k] for k, e in enumerate(eff)}
    it = 0
    while np.linalg.norm(pos[eff] - targets, axis=1).max() > tol and it < max_iter:
        back = pos.copy()
        for j in range(len(parents) - 1, -1, -1):
            if fixed[j] or j not in active:
                continue
            if j in goal:
                back[j] = goal[j]
                continue
            props = [back[c] + L[c] * (pos[j] - back[c]) / np.linalg.norm(pos[j] - back[c])
                     for c in np.nonzero(parents == j)[0] if c in active]
            back[j] = np.mean(props, axis=0)
        for ch in chains:  # each chain as the forward pass would place it, straightened if near-extended
            q = [back[ch[0]]]
            for j in ch[1:]:
                q.append(q[-1] + L[j] * (back[j] - q[-1]) / np.linalg.norm(back[j] - q[-1]))
            straightened = straighten_chain(np.array(q), goal[int(ch[-1])])
            if straightened is not None:
                m, new = straightened
                back[ch[m + 1:]] = new[m + 1:]
        for j in range(len(parents)):
            if fixed[j]:
                continue
            u = (back[j] if j in active else pos[j]) - pos[parents[j]]
            pos[j] = pos[parents[j]] + L[j] * u / np.linalg.norm(u)
        it += 1
    return pos


def _evaluate(solver, cases: Cases, effectors: str, tolerance: float):
    s = cases.skeleton
    lengths0 = bone_lengths_of(s, cases.start_pos)
    lat, eff_err, mpjpe, bl, conv, iters = [], [], [], [], [], []
    solver.solve(cases.pose(0), effector_set(s, effectors, cases.target_pos[0], tolerance))  # warm-up (JIT)
    for i in range(len(cases)):
        effs = effector_set(s, effectors, cases.target_pos[i], tolerance)
        start = cases.pose(i)
        t = time.perf_counter()
        res = solver.solve(start, effs)
        lat.append(time.perf_counter() - t)
        pos = res.pose.global_pos
        eff_err.append(res.effector_error.max())
        mpjpe.append(np.linalg.norm(pos - cases.target_pos[i], axis=1).mean())
        bl.append(np.abs(bone_lengths_of(s, pos) - lengths0[i]).max())
        conv.append(res.converged)
        iters.append(res.iterations)
    tracemalloc.start()
    solver.solve(cases.pose(0), effector_set(s, effectors, cases.target_pos[0], tolerance))
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return {
        "cases": len(cases),
        "latency_ms_median": float(np.median(lat) * 1e3),
        "effector_error_mm_median": float(np.median(eff_err) * 1e3),
        "mpjpe_mm_median": float(np.median(mpjpe) * 1e3),
        "bone_length_error_mm_max": float(np.max(bl) * 1e3),
        "converged_fraction": float(np.mean(conv)),
        "iterations_median": float(np.median(iters)),
        "memory_kb": round(peak / 1024, 1),
    }


def _ikpy_rows(cases: Cases, n: int, tolerance: float):
    """ikpy (a peer library) on one chain, pelvis -> left hand, against posekit on the same chain."""
    s = cases.skeleton
    try:
        import ikpy
        from ikpy.chain import Chain
        from ikpy.link import OriginLink, URDFLink
    except ImportError:  # a peer that is not installed is simply absent
        return []
    from ..rotations import quat_to_euler

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
    lat, err, lat_pk, err_pk = [], [], [], []
    solver = FabrikSolver(s)
    hand = s.index("left_hand")
    for i in range(min(n, len(cases))):
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
        t = time.perf_counter()
        res = solver.solve(cases.pose(i), [Effector(hand, target, tolerance=tolerance)])
        lat_pk.append(time.perf_counter() - t)
        err_pk.append(res.effector_error.max())
    version = getattr(ikpy, "__version__", "?")
    row = lambda name, l, e: {"method": name, "effectors": "left_hand", "cases": len(l),
                              "latency_ms_median": float(np.median(l) * 1e3),
                              "effector_error_mm_median": float(np.median(e) * 1e3),
                              "converged_fraction": float(np.mean(np.array(e) <= tolerance))}
    return [row(f"ikpy {version} (one chain)", lat, err),
            row("fabrik (same chain)", lat_pk, err_pk)]


def run(motions: MotionSet, solvers=("fabrik", "ccd", "dls"), effector_sets=("2", "5"), n_cases: int = 1000,
        start: str = "frame", seed: int = 0, tolerance: float = 1e-3, baseline: bool = True,
        batched: bool = True, peers: bool = True, progress: bool = False) -> list[dict]:
    """Run the benchmark; one row (dict) per method and effector set."""
    from threadpoolctl import threadpool_limits

    for e in effector_sets:
        if e not in EFFECTOR_SETS:
            raise ValueError(f"unknown effector set {e!r}; valid: {', '.join(EFFECTOR_SETS)}")
    cases = build_cases(motions, n_cases, seed, start)
    s = cases.skeleton
    rows = []
    jobs = [(name, e) for name in solvers for e in effector_sets]
    if progress:
        from tqdm.auto import tqdm

        jobs = tqdm(jobs, desc="bench ik", unit="solver x set")
    with threadpool_limits(1):
        for name, e in jobs:
            solver = make_solver(name, s)
            row = {"method": name, "effectors": e, **_evaluate(solver, cases, e, tolerance)}
            if (name, e) in PAPER:
                row["paper_latency_ms"] = PAPER[(name, e)]
            rows.append(row)
        for e in effector_sets:
            eff = s.indices(EFFECTOR_SETS[e])
            if baseline and "fabrik" in solvers:
                m = min(200, len(cases))
                lat = []
                for i in range(m):
                    t = time.perf_counter()
                    _numpy_fabrik(s, cases.start_pos[i], eff, cases.target_pos[i, eff], tolerance)
                    lat.append(time.perf_counter() - t)
                rows.append({"method": "baseline: numpy per-joint FABRIK", "effectors": e, "cases": m,
                             "latency_ms_median": float(np.median(lat) * 1e3)})
            if batched and "fabrik" in solvers:
                from ..ik.fabrik_batched import fabrik_batched

                reps = max(1, 20_000 // len(cases))
                startb = np.tile(cases.start_pos, (reps, 1, 1))
                tg = np.tile(cases.target_pos[:, eff], (reps, 1, 1))
                t = time.perf_counter()
                _, conv, _ = fabrik_batched(s, startb, eff, tg, tolerance)
                dt = time.perf_counter() - t
                rows.append({"method": "fabrik batched", "effectors": e, "cases": len(startb),
                             "solves_per_s": round(len(startb) / dt), "converged_fraction": float(conv.mean())})
        if peers:
            rows += _ikpy_rows(cases, min(100, len(cases)), tolerance)
    for r in rows:
        r.setdefault("start", start)
        r.setdefault("data", cases.source)
    return rows


TABLES = [
    ("Speed (one solve, one thread; batched: solves/s over all cases at once)",
     ["method", "effectors", "cases", "latency_ms_median", "paper_latency_ms", "memory_kb", "solves_per_s"]),
    ("Accuracy (medians over cases; bone error: the worst case)",
     ["method", "effectors", "effector_error_mm_median", "mpjpe_mm_median", "bone_length_error_mm_max",
      "converged_fraction", "iterations_median"]),
]
"""The tables ``posekit bench ik`` prints: (title, JSON keys). Each fits 100 columns."""

TABLE_LABELS = {
    "effectors": "effectors", "latency_ms_median": "ms", "paper_latency_ms": "paper ms", "memory_kb": "kB",
    "solves_per_s": "solves/s", "effector_error_mm_median": "effector mm", "mpjpe_mm_median": "MPJPE mm",
    "bone_length_error_mm_max": "bone mm", "converged_fraction": "converged", "iterations_median": "iterations",
}
"""Short table headers for the JSON keys (units in the header)."""

TABLE_COLUMNS = [c for _, cols in TABLES for c in cols if c != "method"]
TABLE_COLUMNS = ["method"] + list(dict.fromkeys(TABLE_COLUMNS))
"""Every column in one table (``posekit bench ik --wide``)."""
