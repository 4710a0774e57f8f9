"""Lesson 02's setup: the rig, the animator's training and test data, the fitted GPR, and the drift
experiment (the paper's Fig. 11) — shared by ``notebooks/02_inverse_rig_mapping.ipynb`` and
``posekit bench invrig``.

Units: :mod:`posekit.conventions` (joint positions in metres; joint errors reported in cm).
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from ..data import load_sample
from .animator import animate, standard_sets
from .gpr import GPR, greedy_subsample, line_search_theta0
from .humanoid import HumanoidRig
from .jacobian import LearnedJacobian, refine

__all__ = ["Setup", "drift"]


class Setup:
    """Rig, data and fitted GPR shared by the benchmark and the lesson."""

    def __init__(self, seed: int = 0, budget: int = 500, kernel: str = "multiquadric"):

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
        from .nn import load_inverse_net, weights_path  # torch is imported only when a network is loaded

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
            from ..progress import tqdm

            frames = tqdm(frames, desc="optimising frame by frame", unit="frame")
        for f in frames:  # the clips advance together, frame by frame
            prev = refine(s.rig, x[:, f], prev, "computed", iterations)
            y[:, f] = prev
    else:
        raise ValueError(f"guess must be 'previous' or 'gpr', got {guess!r}")
    je = np.linalg.norm(s.rig.evaluate(s.rig.clamp(y)[0]) - x, axis=-1).mean(-1) * 100
    ge = np.mean(np.abs(y - s.long) / s.sd, axis=-1)
    return je, ge
