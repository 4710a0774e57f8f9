"""IK by latent optimisation in the AE-GAN's space (Victor & Meyer, JFIG 2020, Sec. 3.3) behind the
Solver API.

Introduced in ``notebooks/04_aegan_latent_space.ipynb``; registered as ``"latent-opt"`` and variants
(below). One solve, for position effectors on *any* body joints:

1. the start pose in its root frame -> z-scored ``x`` -> ``z_0 = E(x)``;
2. the targets in the same frame, z-scored like the features (a target beyond the training poses'
   range by more than :data:`RANGE_MARGIN` is still used, and ``info["out_of_range"]`` names it);
3. Eq. (6) from ``z_0`` (:mod:`posekit.models.aegan.latent_opt`, Adam or L-BFGS, the stopping rule there);
4. ``x' = G(z*)`` back to the world;
5. ``post="bones"`` (default): the effectors set on their targets and every bone given its length
   back by FABRIK's forward- and backward-reaching stages (:func:`posekit.ik.fix_bone_lengths`, as in lesson 03);
   ``post="none"``: the generator's pose as it is.

Registered names: ``latent-opt`` (L-BFGS, bones), ``latent-opt-raw`` (L-BFGS, no post-processing),
``latent-opt-adam`` (Adam, bones), ``latent-opt-adam-raw``. L-BFGS is the default: on the lesson's
cases it meets the targets in fewer iterations and less time than Adam (the lesson measures both).
"""

from __future__ import annotations

import numpy as np

from ...ik.api import Pose, SolverBase
from ...ik.fix_bones import fix_bone_lengths
from ...ik.registry import register
from ...learn import load_cached, require_skeleton
from . import fast as LK
from ...data.pose_vectors import feature_columns, pose_vectors, poses_from_vectors, targets_in_root_frame
from .numpy_nets import NumpyAEGAN, weights_path
from .latent_opt import OPTIMIZERS, Problem, optimize

__all__ = ["LatentOptSolver", "load_aegan", "RANGE_MARGIN", "SETTINGS"]

RANGE_MARGIN = 0.5
"""How far (z-scored units) beyond the training range a target is flagged ``out_of_range``."""

SETTINGS = {"adam": dict(max_iter=50, lr=0.05, patience=10, stall=1e-3),
            "lbfgs": dict(max_iter=50, memory=8, patience=10, stall=1e-3)}
"""Each optimiser's defaults (iteration budget, Adam's step, the stall rule)."""


def load_aegan(weights=None, skeleton=None):
    """The shipped (or given) :class:`~posekit.models.aegan.networks.AEGAN`, checked against ``skeleton``; cached
    per file. Imports torch."""
    from .networks import AEGAN

    return load_cached(AEGAN.load, weights_path() if weights is None else weights, skeleton)


class LatentOptSolver(SolverBase):
    """Position effectors on any body joints -> a pose, by gradient descent on the AE-GAN's code.

    Parameters
    ----------
    skeleton : Skeleton
        The skeleton the weights were trained for (else a ``ValueError`` names the difference).
    weights : str or Path, optional
        An ``aegan`` checkpoint (default the shipped ``data_samples/weights/aegan.pt``).
    optimizer : {"lbfgs", "adam"}
    post : {"bones", "none"}
    model : AEGAN, optional
        A model already in memory (e.g. the notebook's live demo).
    **options
        Override :data:`SETTINGS` (``max_iter``, ``lr``, ``patience``, ``stall``).

    Every solve runs numpy and compiled code only: without ``model`` the encoder and generator are read from
    the checkpoint without torch (:meth:`NumpyAEGAN.load <posekit.models.aegan.numpy_nets.NumpyAEGAN.load>`).
    """

    name = "latent-opt"
    kinds = ("position",)
    needs_start = True

    def __init__(self, skeleton, weights=None, optimizer: str = "lbfgs", post: str = "bones",
                 model=None, **options):
        if optimizer not in OPTIMIZERS:
            raise ValueError(f"optimizer must be one of {', '.join(OPTIMIZERS)}, got {optimizer!r}")
        if post not in ("bones", "none"):
            raise ValueError(f"post must be 'bones' or 'none', got {post!r}")
        bad = set(options) - set(SETTINGS[optimizer])
        if bad:
            raise ValueError(f"unknown option(s) {sorted(bad)} for {optimizer}; valid: {sorted(SETTINGS[optimizer])}")
        self.net = model.compile() if model is not None else load_cached(
            NumpyAEGAN.load, weights_path() if weights is None else weights, skeleton)
        require_skeleton("latent-opt solver: the AE-GAN", self.net.skeleton, skeleton)
        self._model, self._weights = model, weights
        self.skeleton = skeleton
        self.optimizer, self.post = optimizer, post
        self.options = {**SETTINGS[optimizer], **options}
        self.keeps_bone_lengths = post != "none"
        self.mean = self.net.norm.mean.astype(np.float32)
        self.std = self.net.norm.std.astype(np.float32)
        self._gen = LK.flatten_generator(self.net) if self.net.config["ancestors"] == "parent" else None
        self._work = LK.workspace(self._gen) if self._gen is not None else None
        xr = self.net.x_range
        self.lo, self.hi = (None, None) if xr is None else (np.asarray(xr[0], np.float32) - RANGE_MARGIN,
                                                            np.asarray(xr[1], np.float32) + RANGE_MARGIN)

    @property
    def model(self):
        """The torch :class:`~posekit.models.aegan.networks.AEGAN` (loaded, with torch, when first asked)."""
        if self._model is None:
            self._model = load_aegan(self._weights, self.skeleton)
        return self._model

    def sizes_kb(self, joints=None) -> dict:
        """Float32 size of the networks one solve runs (encoder + generator), kB; no per-set solver."""
        n = self.net.n_parameters("encoder") + self.net.n_parameters("generator")
        return {"model_kb": round(4 * n / 1024, 1), "solver_kb": 0.0}

    def predict(self, start_pos, joints, targets, tol=1e-3):
        """The array-level solve of B problems with one effector joint set.

        Parameters
        ----------
        start_pos : ndarray, shape (B, J, 3), metres
        joints : sequence of int, length K
            Body joints (a helper root such as ``joint_Root`` carries no pose: ``ValueError``).
        targets : ndarray, shape (B, K, 3), metres, world frame
        tol : float or ndarray (B, K), metres
            The stopping tolerance of each effector (on the generator's pose).

        Returns
        -------
        pos : ndarray, shape (B, J, 3)
            The decoded (and post-processed) poses.
        raw : ndarray, shape (B, J, 3)
            The generator's poses.
        iterations : ndarray of int, shape (B,)
        out_of_range : ndarray of bool, shape (B, K)
        """
        prob, origin, angle, out = self.problem(start_pos, joints, targets, tol)
        z, iters, _ = optimize(self.net, prob, self.optimizer, **self.options)
        return (*self._poses(z, origin, angle, joints, targets), iters, out)

    def predict_one(self, start_pos, joints, targets, tol=1e-3):
        """:meth:`predict` of one problem — start (J, 3), joints (K,), targets (K, 3), tolerances (K,) —
        with the optimiser compiled (:mod:`posekit.models.aegan.fast`): what ``solve`` runs. Returns
        ``(pos (J, 3), raw (J, 3), iterations, out_of_range (K,))``."""
        tol = np.asarray(tol, float)[None] if np.ndim(tol) else tol
        if self._gen is None:  # an all-ancestors SPL: the numpy path
            pos, raw, it, oor = self.predict(np.asarray(start_pos)[None], joints, np.asarray(targets)[None], tol)
            return pos[0], raw[0], int(it[0]), oor[0]
        prob, origin, angle, oor = self.problem(np.asarray(start_pos)[None], joints, np.asarray(targets)[None], tol)
        o = self.options
        args = (prob.z0[0], prob.columns, prob.target[0], np.ascontiguousarray(prob.scale), prob.tol[0], *self._gen,
                self._work)
        if self.optimizer == "lbfgs":
            z, it, _ = LK.lbfgs_one(*args, o["max_iter"], o["memory"], o["patience"], o["stall"], 1e-4, 8)
        else:
            z, it, _ = LK.adam_one(*args, o["max_iter"], o["lr"], o["patience"], o["stall"], 0.9, 0.999)
        pos, raw = self._poses(z[None], origin, angle, joints, np.asarray(targets)[None])
        return pos[0], raw[0], int(it), oor[0]

    def problem(self, start_pos, joints, targets, tol=1e-3):
        """Eq. (6)'s problems for B starts (B, J, 3) and targets (B, K, 3) on body ``joints`` (steps 1-2 of the
        module docstring): ``(Problem, origin (B, 3), angle (B,), out_of_range (B, K))``."""
        s = self.skeleton
        joints = [int(j) for j in joints]
        targets = np.asarray(targets, dtype=float)
        B, K = targets.shape[:2]
        cols = feature_columns(s, joints)
        x, origin, angle = pose_vectors(s, np.asarray(start_pos, dtype=float))
        z0 = self.net.encode((x.astype(np.float32) - self.mean) / self.std)
        t = (targets_in_root_frame(targets, origin, angle).reshape(B, -1).astype(np.float32) - self.mean[cols]) \
            / self.std[cols]
        out = np.zeros((B, K), dtype=bool)
        if self.lo is not None:
            out = ((t < self.lo[cols]) | (t > self.hi[cols])).reshape(B, K, 3).any(-1)
        tol = np.broadcast_to(np.asarray(tol, float), (B, K)).copy()
        return Problem(z0, cols, t, self.std[cols], tol), origin, angle, out

    def _poses(self, z, origin, angle, joints, targets):
        """Steps 4-5: codes (B, d) -> (post-processed poses, the generator's poses), each (B, J, 3)."""
        s = self.skeleton
        raw = poses_from_vectors(s, self.net.forward(z)[0] * self.std + self.mean, origin, angle)
        if self.post == "none":
            return raw, raw
        snapped = raw.copy()
        snapped[:, [int(j) for j in joints]] = targets
        return fix_bone_lengths(s, snapped), raw

    def _solve(self, start, resolved):
        pos, _, iters, oor = self.predict_one(start.global_pos, resolved.joints, resolved.position, resolved.tolerance)
        info = {"optimizer": self.optimizer, "post": self.post}
        if oor.any():
            info["out_of_range"] = [self.skeleton.names[j] for j, o in zip(resolved.joints, oor) if o]
        return self.result(Pose(pos), resolved, iters, info)

    # solve_batch solves one problem at a time (the compiled path), so that its results are solve's
    # exactly: in float32 an optimisation run on a batch sums in another order and ends a little away
    # (tested within 2 mm). predict() is the batched path (what the benchmark's throughput rows time).


def _variant(**fixed):
    def factory(skeleton, weights=None, **options):
        return LatentOptSolver(skeleton, weights=weights, **fixed, **options)

    factory.kinds, factory.needs_start = ("position",), True
    return factory


_LESSON = "notebooks/04_aegan_latent_space.ipynb"
register("latent-opt", LatentOptSolver, lesson=_LESSON, data="bandai-mini",
         description="L-BFGS on the AE-GAN's code (Victor & Meyer, JFIG 2020), bone lengths restored")
register("latent-opt-raw", _variant(post="none"), lesson=_LESSON, data="bandai-mini",
         description="latent optimisation (L-BFGS), the generator's pose, no post-processing")
register("latent-opt-adam", _variant(optimizer="adam"), lesson=_LESSON, data="bandai-mini",
         description="latent optimisation with Adam, bone lengths restored")
register("latent-opt-adam-raw", _variant(optimizer="adam", post="none"), lesson=_LESSON, data="bandai-mini",
         description="latent optimisation with Adam, no post-processing")
