"""``posekit bench invrig``: the shape of Tables 1 and 2 of Holden, Saito & Komura 2017 on our rig.

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb``. Training animation and held-out test clips
come from :func:`posekit.rig.standard_sets` (seeded). Per method, on the 1,000 test frames:

* ``joint_error`` — mean distance between the rig's joints at the predicted controls and the true
  joints, cm (the paper's "Joint Error");
* ``ground_truth_error`` — mean absolute control error, in standard deviations of the training
  animation (the paper's rig-space "Ground-Truth Error");
* ``total_s`` and ``frames_per_s`` — the whole test set on one thread, rig evaluations included.

Table 1: heuristic script, GPR, GPR + learned Jacobian, GPR + computed Jacobian, NN, NN + computed
Jacobian. Table 2: the network trained on each supersampling method (weights shipped in
``data_samples/weights``, made by ``posekit train invrig``). Table 3 (the paper's Fig. 11): three long
1,000-frame test clips solved frame by frame, by pure optimisation from the previous frame and with
a learned first guess every frame; errors of the first and the last 200 frames.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from .plugin import arg, register_benchmark

# the rig, the regressors and torch are imported where they are used, so that building the
# command line (which lists this benchmark) stays fast

__all__ = ["Setup", "run", "drift", "PAPER_FPS"]

PAPER_FPS = (195, 656)
"""Frames per second the paper reports for its methods with Maya in the loop (range over methods)."""


class Setup:
    """Rig, data and fitted GPR shared by the benchmark and the lesson."""

    def __init__(self, seed: int = 0, budget: int = 500, kernel: str = "multiquadric"):
        from ..data import load_sample
        from ..regression import GPR, LearnedJacobian, greedy_subsample, line_search_theta0
        from ..rig import HumanoidRig, animate, standard_sets

        self.rig = HumanoidRig(load_sample().skeleton)
        self.train, self.test, self.test_clip = standard_sets(self.rig, seed)
        self.X = self.rig.evaluate(self.train).reshape(len(self.train), -1)
        self.Xt3 = self.rig.evaluate(self.test)
        # control scale for the ground-truth error: the training standard deviation, floored at 1 % of
        # the control's range (the never-animated controls have none)
        self.sd = np.maximum(self.train.std(0), 0.01 * (self.rig.high - self.rig.low))
        # three long continuous test clips (1,000 frames each) for the drift experiment, shape (3, 1000, C)
        self.long = animate(self.rig, 3, 1000, key_every=10, extreme=1.6, seed=seed + 2)[0].reshape(3, 1000, -1)
        self.long_x = self.rig.evaluate(self.long)
        rng = np.random.default_rng(seed)
        cv = rng.choice(len(self.X), 600, replace=False)
        t = time.perf_counter()
        self.theta0, self.cv_table = line_search_theta0(self.X[cv], self.train[cv], kernel, seed=seed)
        self.subset = greedy_subsample(self.X, self.train, budget, kernel, self.theta0, seed=seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            self.gpr = GPR(kernel, self.theta0).fit(self.X[self.subset], self.train[self.subset])
            self.learned_jacobian = LearnedJacobian(self.rig, self.train[self.subset], theta0=self.theta0)
        self.fit_s = time.perf_counter() - t

    def joint_error(self, y, frames=slice(None)):
        """Mean joint distance (cm) of the rig at ``y`` — clamped to the rig's ranges first, as the rig
        would (:meth:`clamped_values` counts how many were outside) — to the test joints."""
        y = self.rig.clamp(y)[0]
        return float(np.linalg.norm(self.rig.evaluate(y) - self.Xt3[frames], axis=-1).mean() * 100)

    def clamped_values(self, y) -> int:
        """How many predicted control values lie outside the rig's ranges."""
        return self.rig.clamp(y)[1].count

    def ground_truth_error(self, y, frames=slice(None)):
        return float(np.mean(np.abs(y - self.test[frames]) / self.sd))

    def net(self, method: str, folder=None):
        from ..regression.nn import load_inverse_net
        from ..regression.train import weights_path

        return load_inverse_net(weights_path(method, folder), self.rig.names, self.rig.skeleton.names)


def drift(s: Setup, guess: str = "previous", iterations: int = 3, progress: bool = False):
    """Per-frame errors on the three long test clips when every frame is solved by the
    computed-Jacobian refinement starting from the previous frame's answer (``guess="previous"``:
    pure optimisation, the paper's Fig. 11; frame 0 starts from the rest controls) or from the GPR
    prediction (``guess="gpr"``, all frames at once since they are independent).

    Returns
    -------
    joint_error_cm, ground_truth_error : ndarray, shape (3, 1000)
    """
    from ..regression import refine

    x = s.long_x  # (3, 1000, J, 3)
    n_clips, F = x.shape[:2]
    if guess == "gpr":
        flat = x.reshape(n_clips * F, -1)
        y = refine(s.rig, x.reshape(n_clips * F, -1, 3), s.gpr.predict(flat), "computed", iterations)
        y = y.reshape(s.long.shape)
    elif guess == "previous":
        y = np.empty_like(s.long)
        prev = np.tile(s.rig.default(), (n_clips, 1))
        frames = range(F)
        if progress:
            from tqdm.auto import tqdm

            frames = tqdm(frames, desc="optimising frame by frame", unit="frame")
        for f in frames:  # the clips advance together, frame by frame
            prev = refine(s.rig, x[:, f], prev, "computed", iterations)
            y[:, f] = prev
    else:
        raise ValueError(f"guess must be 'previous' or 'gpr', got {guess!r}")
    je = np.linalg.norm(s.rig.evaluate(s.rig.clamp(y)[0]) - x, axis=-1).mean(-1) * 100
    ge = np.mean(np.abs(y - s.long) / s.sd, axis=-1)
    return je, ge


def _timed(fn):
    t = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t


def run(seed: int = 0, budget: int = 500, weights=None, sampling: bool = True, drift_table: bool = True,
        setup_: Setup | None = None) -> list[dict]:
    """Measure Table 1 (and Table 2 with ``sampling``, Table 3 with ``drift_table``); one row per method."""
    from ..learn.threads import single_thread
    from ..regression import METHODS, refine
    from ..rig import heuristic_inverse

    s = setup_ or Setup(seed, budget)
    Xt = s.Xt3.reshape(len(s.test), -1)
    rows = []
    with single_thread():
        nn_pca = s.net("pca", weights)
        methods = [
            ("heuristic script", lambda: heuristic_inverse(s.rig, s.Xt3)),
            ("GPR", lambda: s.gpr.predict(Xt)),
            ("GPR + learned Jacobian", lambda: refine(s.rig, s.Xt3, s.gpr.predict(Xt), s.learned_jacobian)),
            ("GPR + computed Jacobian", lambda: refine(s.rig, s.Xt3, s.gpr.predict(Xt), "computed")),
            ("NN", lambda: nn_pca.predict(Xt)),
            ("NN + computed Jacobian", lambda: refine(s.rig, s.Xt3, nn_pca.predict(Xt), "computed")),
        ]
        for name, fn in methods:
            y, dt = _timed(fn)
            rows.append({"table": 1, "method": name, "joint_error": s.joint_error(y),
                         "ground_truth_error": s.ground_truth_error(y), "total_s": dt,
                         "frames_per_s": len(Xt) / dt, "clamped_values": s.clamped_values(y)})
        for guess, name in (("previous", "optimisation only (previous frame as guess)"),
                            ("gpr", "GPR + computed Jacobian, every frame")) if drift_table else ():
            (je, ge), dt = _timed(lambda: drift(s, guess))
            rows.append({"table": 3, "method": name, "frames": je.size,
                         "joint_error_first_200": float(je[:, :200].mean()),
                         "joint_error_last_200": float(je[:, -200:].mean()),
                         "ground_truth_error_first_200": float(ge[:, :200].mean()),
                         "ground_truth_error_last_200": float(ge[:, -200:].mean()), "frames_per_s": je.size / dt})
        if sampling:
            for m in METHODS:
                y = s.net(m, weights).predict(Xt)
                yr = refine(s.rig, s.Xt3, y, "computed")
                rows.append({"table": 2, "method": f"NN, {m} sampling", "joint_error": s.joint_error(y),
                             "ground_truth_error": s.ground_truth_error(y),
                             "joint_error_with_jacobian": s.joint_error(yr)})
    for r in rows:
        r.setdefault("frames", len(Xt))
    rows.append({"table": 0, "method": "setup", "theta0": s.theta0, "gpr_budget": budget, "fit_s": s.fit_s,
                 "paper_frames_per_s": list(PAPER_FPS)})
    return rows


def _header(rows, args) -> str:
    setup = next(r for r in rows if r.get("table") == 0)
    frames = next(r["frames"] for r in rows if r.get("table") == 1)
    return (f"Inverse rig mapping on the held-out test clips ({frames} frames), one thread; GPR: multiquadric, "
            f"theta0 = {setup['theta0']:.3g}, {setup['gpr_budget']} subsampled poses, "
            f"fitted in {setup['fit_s']:.1f} s\n"
            "joint error: cm; ground-truth error: control error in training standard deviations")


TABLES = [
    ("Table 1 (paper: {}-{} frames/s with Maya in the loop)".format(*PAPER_FPS),
     ["method", "joint_error", "ground_truth_error", "total_s", "frames_per_s", "clamped_values"], {"table": 1}),
    ("Table 2: the network by supersampling method",
     ["method", "joint_error", "ground_truth_error", "joint_error_with_jacobian"], {"table": 2}),
    ("Drift (Fig. 11): three 1,000-frame test clips solved frame by frame; joint error (cm) and control\n"
     "error (sd) of the first and the last 200 frames",
     ["method", "joint_error_first_200", "joint_error_last_200", "ground_truth_error_first_200",
      "ground_truth_error_last_200", "frames_per_s"], {"table": 3}),
]
"""The tables ``posekit bench invrig`` prints: (title, JSON keys, which rows)."""

TABLE_LABELS = {
    "joint_error": "joint cm", "ground_truth_error": "control sd", "total_s": "total s", "frames_per_s": "frames/s",
    "clamped_values": "clamped", "joint_error_with_jacobian": "joint cm + Jacobian",
    "joint_error_first_200": "cm first", "joint_error_last_200": "cm last",
    "ground_truth_error_first_200": "sd first", "ground_truth_error_last_200": "sd last",
}
"""Short table headers for the JSON keys (units in the header)."""

register_benchmark(
    "invrig", lambda args: run(seed=args.seed, budget=args.budget, weights=args.weights),
    help="inverse rig mapping: Tables 1 and 2 of Holden et al. 2017 on our rig",
    args=[arg("--seed", type=int, default=0, help="seed of the animation and the GPR fit"),
          arg("--budget", type=int, default=500, help="GPR training poses after greedy subsampling"),
          arg("--weights", default=None, help="folder of invrig_nn_*.pt (default data_samples/weights)")],
    tables=TABLES, labels=TABLE_LABELS, header=_header, lesson="notebooks/02_inverse_rig_mapping.ipynb",
    replace=True)
