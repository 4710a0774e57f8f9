"""``posekit bench fk``: forward-kinematics throughput and shipped-data load time.

Rows, side by side in one run on one thread: posekit's numpy FK, a straightforward numpy FK
(``np.matmul`` per joint, the baseline a newcomer would write), torch FK, and the goal from the
roadmap (500,000 poses/s for a 22-joint skeleton; the shipped sample loads in under 1 s). Each row
also says how far its positions are from the baseline's (``max_diff_vs_baseline_m``).
"""

from __future__ import annotations

import time

import numpy as np

from ..kinematics import fk
from ..rotations import quat_to_matrix, random_rotations
from ..skeleton import Skeleton
from .plugin import arg, register_benchmark

GOAL_POSES_PER_S = 500_000
GOAL_LOAD_S = 1.0

# a 22-joint humanoid tree with the Bandai Namco topology (lengths are random: only speed matters)
_PARENTS_22 = [-1, 0, 1, 2, 3, 4, 3, 6, 7, 8, 3, 10, 11, 12, 1, 14, 15, 16, 1, 18, 19, 20]


def _naive_fk(skeleton, R):
    """Baseline: per-joint ``np.matmul`` on (N, 3, 3) stacks, no layout tricks."""
    N, J = R.shape[:2]
    Rg = np.empty_like(R)
    Pg = np.empty((N, J, 3))
    Rg[:, 0] = R[:, 0]
    Pg[:, 0] = skeleton.offsets[0]
    for j in range(1, J):
        p = skeleton.parents[j]
        Rg[:, j] = Rg[:, p] @ R[:, j]
        Pg[:, j] = Pg[:, p] + Rg[:, p] @ skeleton.offsets[j]
    return Pg, Rg


def _best_rate(fn, n_poses, repeats):
    fn()
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return n_poses / best


def run(n_poses: int = 20_000, repeats: int = 5, seed: int = 0) -> list[dict]:
    """Measure; returns one row per method with ``poses_per_s`` and ``goal``."""
    from ..learn.threads import single_thread

    rng = np.random.default_rng(seed)
    J = len(_PARENTS_22)
    skel = Skeleton([f"j{i}" for i in range(J)], _PARENTS_22, rng.normal(size=(J, 3)) * 0.1, name="bench22")
    q = random_rotations((n_poses, J), rng)
    R = quat_to_matrix(q)
    rows = []
    with single_thread():
        import torch

        Rt = torch.from_numpy(R)
        cases = [
            ("posekit fk (numpy, matrices in)", lambda: fk(skel, R)),
            ("posekit fk (numpy, quaternions in)", lambda: fk(skel, q)),
            ("baseline: np.matmul per joint", lambda: _naive_fk(skel, R)),
            ("posekit fk (torch, matrices in)", lambda: fk(skel, Rt)),
        ]
        reference = _naive_fk(skel, R)[0]
        for name, fn in cases:
            rate = _best_rate(fn, n_poses, repeats)
            # every method must compute the same positions as the baseline, or its rate means nothing
            pos = np.asarray(fn()[0])
            rows.append({"method": name, "joints": J, "poses": n_poses, "poses_per_s": round(rate),
                         "goal_poses_per_s": GOAL_POSES_PER_S,
                         "max_diff_vs_baseline_m": float(np.abs(pos - reference).max())})
    from ..data import load_sample

    t = time.perf_counter()
    ms = load_sample()
    load_s = time.perf_counter() - t
    rows.append({"method": "load shipped sample", "joints": ms.skeleton.n_joints, "poses": ms.n_frames,
                 "seconds": round(load_s, 4), "goal_seconds": GOAL_LOAD_S})
    return rows


TABLES = [
    ("Forward kinematics, one thread (best of repeats)",
     ["method", "joints", "poses", "poses_per_s", "goal_poses_per_s", "max_diff_vs_baseline_m"],
     lambda r: "poses_per_s" in r),
    ("Load time", ["method", "poses", "seconds", "goal_seconds"], lambda r: "seconds" in r),
]
"""The tables ``posekit bench fk`` prints: (title, JSON keys, which rows)."""

TABLE_LABELS = {"poses_per_s": "poses/s", "goal_poses_per_s": "goal", "max_diff_vs_baseline_m": "max diff (m)",
                "goal_seconds": "goal s"}
"""Short table headers for the JSON keys."""

register_benchmark(
    "fk", lambda args: run(n_poses=args.poses, repeats=args.repeats, seed=args.seed),
    help="forward-kinematics throughput against the baseline and the goal",
    args=[arg("--poses", type=int, default=20_000, help="poses per FK call"),
          arg("--repeats", type=int, default=5, help="timed repeats (the best counts)"),
          arg("--seed", type=int, default=0, help="seed of the random skeleton and rotations")],
    tables=TABLES, labels=TABLE_LABELS, lesson="notebooks/00_skeletons_and_poses.ipynb")
