"""The neural IK solver of Victor et al. 2021 behind the Solver API: encode, solve in latent space,
decode, restore bone lengths.

Introduced in ``notebooks/03_autoencoder_solvers.ipynb``; registered as ``"neural"`` and variants
(below), so the benchmark, the viewer and the studio use it by name. This wrapper is the only place
that knows both worlds: effectors and :class:`~posekit.records.Pose` on one side, z-scored root-frame
vectors and latent codes (:mod:`posekit.models.pose_autoencoder.networks`) on the other.

One solve
---------
1. the start pose in its root frame (pelvis on the floor's origin, facing +Z) -> ``x`` -> ``z = E(x)``;
2. the position targets in the same frame, z-scored like the pose features; a target outside the
   training poses' range is clamped to it (the pose stays valid) and ``info["out_of_range"]`` names it;
3. ``z' = S_t(z, p_t)`` for the solver trained on exactly these joints (``"all"`` for hands, feet and
   head), or the chain of Sec. 3.5 (``chain=True``: hands -> feet -> head, the chaining-aware copies);
4. ``x' = D(z')`` back to the world;
5. post-processing (Sec. 3.4) ``post="bones"``: FABRIK's forward reaching — effectors set on their
   targets, every parent re-placed at bone length from its children, then one backward-reaching stage
   (:func:`posekit.ik.fix_bone_lengths`), so every bone has its length again. ``post="none"`` returns
   the network's pose; ``post="fabrik"`` continues with full FABRIK iterations from that pose (the
   learned pose as FABRIK's start: effectors met to FABRIK's tolerance).

Registered names: ``neural`` (all-five / hands solver, ``post="bones"``), ``neural-raw`` (no
post-processing), ``neural-chained`` (chain, bones), ``neural-chained-raw``, ``neural-fabrik``.
"""

from __future__ import annotations

import numpy as np

from ...data.metrics import body_joints
from ...ik.api import Pose, SolverBase
from ...ik.fix_bones import fix_bone_lengths
from ...ik.registry import make_solver, register
from ...learn import load_cached, require_skeleton
from . import fast as K
from ...data.pose_vectors import feature_columns, pose_vectors, poses_from_vectors, targets_in_root_frame
from .numpy_nets import GROUPS, NumpyAESolvers, chain_groups, stages, weights_path

__all__ = ["NeuralIKSolver", "POSTS", "load_model"]

POSTS = ("bones", "none", "fabrik")
"""Post-processing choices (see the module docstring)."""

RANGE_MARGIN = 0.5
"""How far (z-scored units) a target may lie beyond the training range before it is clamped."""

try:
    from numba.typed import List as _List
except ImportError:  # pragma: no cover - numba is a dependency
    _List = list


def load_model(weights=None, skeleton=None):
    """The shipped (or given) :class:`~posekit.models.pose_autoencoder.networks.AESolvers`, checked against
    ``skeleton``; cached per file. Imports torch."""
    from .networks import AESolvers

    return load_cached(AESolvers.load, weights_path() if weights is None else weights, skeleton)


class NeuralIKSolver(SolverBase):
    """Position effectors -> a whole pose by a pose autoencoder and latent-space solvers.

    Parameters
    ----------
    skeleton : Skeleton
        Must be the skeleton the weights were trained for (the Bandai mini set's); otherwise a
        ``ValueError`` names the joint, parent or offset that differs.
    weights : str or Path, optional
        An ``ae_solvers`` checkpoint (default the shipped ``data_samples/weights/ae_solvers.pt``) —
        or an :class:`AESolvers` already in memory (``model=``).
    post : {"bones", "none", "fabrik"}
    chain : bool
        Solve with the chain of Sec. 3.5 (hands -> feet -> head, each stage the solver of its group)
        instead of one solver for the whole effector set.
    chain_aware : bool
        With ``chain``: use the fine-tuned stages (False: naive chaining of the independent solvers).
    model : AESolvers, optional
    reencode : bool
        With ``chain``: between two stages decode the code and encode the pose again (``z = E(D(z))``), as the
        authors' code chains its solvers (``CombinedSequentialIKSolver``); False composes them in the latent space,
        as Sec. 3.5 writes it.

    Every solve runs numpy and compiled code only: without ``model`` the networks are read from the checkpoint
    without torch (:meth:`NumpyAESolvers.load <posekit.models.pose_autoencoder.numpy_nets.NumpyAESolvers.load>`);
    :attr:`model`, the torch networks, is loaded when first asked.
    """

    name = "neural"
    kinds = ("position",)
    needs_start = True
    batch_atol = 1e-5  # float32 networks: the batched numpy path and the compiled single path round differently

    def __init__(self, skeleton, weights=None, post: str = "bones", chain: bool = False, chain_aware: bool = True,
                 model=None, reencode: bool = False):
        if post not in POSTS:
            raise ValueError(f"post must be one of {', '.join(POSTS)}, got {post!r}")
        self.net = model.compile() if model is not None else load_cached(
            NumpyAESolvers.load, weights_path() if weights is None else weights, skeleton)
        require_skeleton("neural solver: the model", self.net.skeleton, skeleton)
        self._model, self._weights = model, weights
        self.skeleton = skeleton
        self.post, self.chain, self.chain_aware = post, bool(chain), bool(chain_aware)
        self.reencode = bool(reencode)
        self.keeps_bone_lengths = post != "none"
        self.mean = self.net.norm.mean.astype(np.float32)
        self.std = self.net.norm.std.astype(np.float32)
        self.lo, self.hi = (None, None) if self.net.x_range is None else np.asarray(self.net.x_range, np.float32)
        self._cols = {g: feature_columns(skeleton, GROUPS[g]) for g in self.net.solvers}
        self._groups = {frozenset(skeleton.indices(GROUPS[g])): g for g in self.net.solvers}
        self._fabrik = make_solver("fabrik", skeleton) if post == "fabrik" else None
        self._plans: dict = {}
        self._compile_single()

    @property
    def model(self):
        """The torch :class:`~posekit.models.pose_autoencoder.networks.AESolvers` (loaded, with torch, when first
        asked)."""
        if self._model is None:
            self._model = load_model(self._weights, self.skeleton)
        return self._model

    def _compile_single(self):
        """Arrays of the compiled single-pose path (:mod:`posekit.models.pose_autoencoder.fast`)."""
        s = self.skeleton
        roles = s.roles
        sh = ("left_shoulder" in roles and "right_shoulder" in roles)
        self._frame = (s.pelvis(), s.index("left_hip"), s.index("right_hip"),
                       s.index("left_shoulder") if sh else -1, s.index("right_shoulder") if sh else -1)
        self._body = body_joints(s).astype(np.int64)
        chain = [s.pelvis()]
        while chain[-1] != 0:
            chain.append(int(s.parents[chain[-1]]))
        self._chain = np.array(chain, dtype=np.int64)
        self._chain_off = np.array([s.offsets[j] for j in chain], dtype=float).reshape(-1, 3)
        big = np.float32(np.inf)
        lo = self.lo - RANGE_MARGIN if self.lo is not None else np.full_like(self.mean, -big)
        hi = self.hi + RANGE_MARGIN if self.hi is not None else np.full_like(self.mean, big)
        self._tnorm = {g: (self.mean[c].astype(float), self.std[c].astype(float), lo[c].astype(float),
                           hi[c].astype(float)) for g, c in self._cols.items()}
        self._mean64, self._std64 = self.mean.astype(float), self.std.astype(float)

        def typed(layers):
            ws = _List([np.ascontiguousarray(w, dtype=np.float32) for w, _ in layers])
            bs = _List([np.zeros(0, np.float32) if b is None else np.ascontiguousarray(b, np.float32)
                        for _, b in layers])
            return ws, bs

        n = self.net
        self._enc, self._dec = typed(n.enc), typed(n.dec)
        self._solv = {g: typed(v) for g, v in n.solvers.items()}
        self._chnd = {g: typed(v) for g, v in n.chained.items()}

    def predict_one(self, start_pos, joints, targets):
        """:meth:`predict` of one problem — start (J, 3), joints (K,), targets (K, 3), metres — by the compiled
        kernels of :mod:`posekit.models.pose_autoencoder.fast` (what ``solve`` runs for a single problem); returns
        ``(pos (J, 3), raw (J, 3), clamped (K,))``."""
        start_pos = np.ascontiguousarray(start_pos, dtype=float)
        targets = np.ascontiguousarray(targets, dtype=float)
        plan = self.plan(joints)
        ox, oz, c, sn = K.root_frame(start_pos, *self._frame)
        x = np.empty(len(self._mean64), np.float32)
        K.features(start_pos, self._body, ox, oz, c, sn, self._mean64, self._std64, x)
        z = K.mlp(x, *self._enc, False)
        clamped = np.zeros(len(joints), dtype=np.bool_)
        order = dict(plan)
        for k, (g, aware) in enumerate(self._stages(plan)):
            if self.reencode and k:                   # the authors' chaining: decode, then encode the pose again
                z = K.mlp(K.mlp(z, *self._dec, False), *self._enc, False)
            v = np.empty(3 * len(order[g]), np.float32)
            cl = np.zeros(len(order[g]), dtype=np.bool_)
            K.targets(targets[order[g]], ox, oz, c, sn, *self._tnorm[g], v, cl)
            clamped[order[g]] |= cl
            z = K.mlp(np.concatenate((z, v)), *(self._chnd if aware else self._solv)[g], False)
        xo = K.mlp(z, *self._dec, False)
        raw = K.pose_from_features(xo, self._body, self._chain, self._chain_off, self.skeleton.n_joints, ox, oz, c, sn,
                                   self._mean64, self._std64)
        return self._post(raw, joints, targets), raw, clamped

    def _stages(self, plan) -> list:
        """``[(group, use its chaining-aware copy)]`` of a plan (:func:`posekit.models.pose_autoencoder.networks.stages`)."""
        return stages([g for g, _ in plan], chain=[g for g, _ in plan] if self.chain else None,
                      chain_aware=self.chain_aware, chained=self.net.chained)

    def _post(self, raw, joints, targets):
        """Post-processing (module docstring) of decoded poses (..., J, 3) for targets (..., K, 3)."""
        if self.post == "none":
            return raw
        snapped = raw.copy()
        snapped[..., list(joints), :] = targets
        return fix_bone_lengths(self.skeleton, snapped)

    def sizes_kb(self, joints) -> dict:
        """Float32 size of what a solve for ``joints`` runs, kB: ``model_kb`` (autoencoder + solver(s),
        the paper's figure) and ``solver_kb`` (the solver network(s) alone)."""
        groups = [g for g, _ in self.plan(self.skeleton.indices(joints))]
        total, ae = self.net.n_parameters(groups), self.net.n_parameters()
        return {"model_kb": round(4 * total / 1024, 1), "solver_kb": round(4 * (total - ae) / 1024, 1)}

    # ------------------------------------------------------------------------------------ plans
    def plan(self, joints) -> list:
        """The solver stages for an effector joint set: ``[(group, order of the effectors)]``."""
        key = tuple(int(j) for j in joints)
        if key in self._plans:
            return self._plans[key]
        s, have = self.skeleton, set(key)
        if len(have) != len(key):
            raise ValueError("neural solver: two effectors on one joint")
        found = []
        if not self.chain and frozenset(key) in self._groups:
            found = [self._groups[frozenset(key)]]
        elif self.chain:
            roles = {r for r in s.roles if s.index(r) in have}
            groups = chain_groups(roles, self.net.solvers)
            covered = {int(j) for g in groups for j in s.indices(GROUPS[g])}
            found = groups if covered == have else []
        if not found:
            sets = "; ".join(f"{g}: {', '.join(GROUPS[g])}" for g in self.net.solvers)
            how = "a union of hands, feet and head (chain)" if self.chain else "exactly one of them"
            raise ValueError(f"neural solver {self.name!r} has solvers for these joint sets — {sets}; the effectors "
                             f"are on {', '.join(s.names[j] for j in key)}, which is not {how}")
        order = [(g, [key.index(int(j)) for j in s.indices(GROUPS[g])]) for g in found]
        self._plans[key] = order
        return order

    # ----------------------------------------------------------------------------------- solving
    def predict(self, start_pos, joints, targets):
        """The array-level solve of B problems with one effector joint set.

        Parameters
        ----------
        start_pos : ndarray, shape (B, J, 3), metres
        joints : sequence of int, length K
        targets : ndarray, shape (B, K, 3), metres, world frame

        Returns
        -------
        pos : ndarray, shape (B, J, 3)
            The decoded (and post-processed) poses.
        raw : ndarray, shape (B, J, 3)
            The decoded poses before post-processing.
        clamped : ndarray of bool, shape (B, K)
            Targets outside the training range (clamped to it).
        """
        s = self.skeleton
        start_pos = np.asarray(start_pos, dtype=float)
        targets = np.asarray(targets, dtype=float)
        plan = self.plan(joints)
        x, origin, angle = pose_vectors(s, start_pos)
        local_t = targets_in_root_frame(targets, origin, angle)
        z = self.net.encode((x.astype(np.float32) - self.mean) / self.std)
        B, K = targets.shape[:2]
        clamped = np.zeros((B, K), dtype=bool)
        p = {}
        for g, order in plan:
            cols = self._cols[g]
            v = (local_t[:, order].reshape(B, -1).astype(np.float32) - self.mean[cols]) / self.std[cols]
            if self.lo is not None:
                lo, hi = self.lo[cols] - RANGE_MARGIN, self.hi[cols] + RANGE_MARGIN
                out = (v < lo) | (v > hi)
                if out.any():
                    clamped[:, order] |= out.reshape(B, -1, 3).any(-1)
                    v = np.clip(v, lo, hi)
            p[g] = v
        z = self.net.latent(z, p, chain=[g for g, _ in plan] if self.chain else None, chain_aware=self.chain_aware,
                            reencode=self.reencode)
        xo = self.net.decode(z) * self.std + self.mean
        raw = poses_from_vectors(s, xo, origin, angle)
        return self._post(raw, joints, targets), raw, clamped

    def _solve(self, start, resolved):
        return self._solve_many([start], [resolved])[0]

    def _solve_many(self, starts, resolved):
        out = [None] * len(starts)
        groups: dict = {}
        for i, r in enumerate(resolved):
            groups.setdefault(tuple(int(j) for j in r.joints), []).append(i)
        for joints, idx in groups.items():
            if len(idx) == 1:
                pos, raw, clamped = (a[None] for a in self.predict_one(starts[idx[0]].global_pos, joints,
                                                                         resolved[idx[0]].position))
            else:
                start = np.stack([np.asarray(starts[i].global_pos, dtype=float) for i in idx])
                targets = np.stack([resolved[i].position for i in idx])
                pos, raw, clamped = self.predict(start, joints, targets)
            names = [g for g, _ in self.plan(joints)]
            for row, i in enumerate(idx):
                info = {"stages": list(names), "post": self.post}
                if clamped[row].any():
                    info["out_of_range"] = [self.skeleton.names[j] for j, c in zip(joints, clamped[row]) if c]
                iters = 1
                pose = Pose(pos[row])
                if self._fabrik is not None:
                    res = self._fabrik.solve(Pose(pos[row]), resolved[i])
                    pose, iters = res.pose, 1 + res.iterations
                out[i] = self.result(pose, resolved[i], iters, info)
        return out


def _variant(**fixed):
    def factory(skeleton, weights=None, chain_aware: bool = True):
        return NeuralIKSolver(skeleton, weights=weights, chain_aware=chain_aware, **fixed)

    factory.kinds, factory.needs_start = ("position",), True
    return factory


_LESSON = "notebooks/03_autoencoder_solvers.ipynb"
register("neural", NeuralIKSolver, lesson=_LESSON, data="bandai-mini",
         description="pose autoencoder + latent solver (Victor et al. 2021), bone lengths restored")
register("neural-raw", _variant(post="none"), lesson=_LESSON, data="bandai-mini",
         description="the neural solver's decoded pose, no post-processing")
register("neural-chained", _variant(chain=True), lesson=_LESSON, data="bandai-mini",
         description="chained neural solvers hands -> feet -> head (Sec. 3.5), bone lengths restored")
register("neural-chained-raw", _variant(chain=True, post="none"), lesson=_LESSON, data="bandai-mini",
         description="chained neural solvers, no post-processing")
register("neural-fabrik", _variant(post="fabrik"), lesson=_LESSON, data="bandai-mini",
         description="the neural pose as FABRIK's start: learned pose, effectors met by FABRIK")
