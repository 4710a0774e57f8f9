"""ProtoRes and its baselines behind the Solver API: effectors of three kinds in, a whole pose out, no start pose.

Introduced in ``notebooks/05_protores.ipynb``; registered as ``"protores"``, ``"protores-masked-fcr"`` and
``"protores-transformer"``. This wrapper is the only place that knows both worlds: posekit's
:class:`~posekit.ik.effectors.Effector` (any joint, tolerance in metres or radians) on one side, the
network's arrays (body-joint ids, kind ids, 6 values, ``Lambda`` in [0, 1]) on the other.

Tolerance
---------
An effector's tolerance ``t`` (metres or radians) becomes ``Lambda = (t / sigma_M)^(1/eta)``, the
tolerance whose training noise has scale ``t`` (:func:`~posekit.models.protores.networks.sigma_to_tolerance`):
1 mm -> 0.70, 1 degree -> 0.87, 1 cm -> 0.84. Tolerances above ``sigma_M`` (0.1 m, 0.1 rad) have no
meaning to the network and are refused. :meth:`ProtoResSolver.predict` takes ``Lambda`` itself.

Flags
-----
A position target further from the effectors' centroid than the skeleton can span (the longest path
between two joints, :func:`skeleton_span`) is outside anything the network has seen: the pose is still
valid (FK of predicted rotations) and ``info["out_of_range"]`` names the effectors.
"""

from __future__ import annotations

import numpy as np

from ...data.metrics import body_joints
from ...ik.api import Pose, SolverBase
from ...ik.effectors import KINDS
from ...ik.registry import register
from ...kinematics import fk
from ...learn import load_cached, require_skeleton
from ...rotations import matrix_to_quat, matrix_to_sixd
from ...ik.effectors import KIND_CODES as KIND_IDS
from .fast import ARCHS, NumpyPosingNet, weights_path
from .tolerance import SIGMA_M, sigma_to_tolerance

__all__ = ["ProtoResSolver", "load_protores", "load_numpy", "skeleton_span", "run_learned", "MAX_EFFECTORS", "ARCHS"]

NUMPY_BATCH = 8
"""Up to this many requests go through :class:`~posekit.models.protores.fast.NumpyPosingNet` (no torch
overhead); larger batches through torch."""

MAX_EFFECTORS = 64
"""Most effectors one prediction takes (a valid set has at most two per body joint; training drew 3-16)."""


def load_protores(arch: str = "protores", weights=None, skeleton=None):
    """The shipped (or given) :class:`~posekit.models.protores.networks.PosingNet` of ``arch``, checked against
    ``skeleton``; cached per file. Imports torch."""
    from .networks import PosingNet

    return load_cached(PosingNet.load, weights_path(arch) if weights is None else weights, skeleton)


def load_numpy(arch: str = "protores", weights=None, skeleton=None) -> NumpyPosingNet:
    """The same network as :func:`load_protores` for the numpy pass, read without torch; cached per file."""
    return load_cached(NumpyPosingNet.load, weights_path(arch) if weights is None else weights, skeleton)


def skeleton_span(skeleton) -> float:
    """The longest bone path between two joints, metres: no two joints of any pose are further apart."""
    J = skeleton.n_joints
    depth = np.zeros(J)
    for j in range(1, J):
        depth[j] = depth[skeleton.parents[j]] + np.linalg.norm(skeleton.offsets[j])
    best = 0.0
    for a in range(J):
        for b in range(a + 1, J):
            ca, cb = skeleton.chain(a, 0), skeleton.chain(b, 0)
            common = max(set(ca) & set(cb), key=lambda j: depth[j])
            best = max(best, depth[a] + depth[b] - 2 * depth[common])
    return float(best)


class ProtoResSolver(SolverBase):
    """Effectors -> a full pose in one network pass (Oreshkin et al. 2022).

    Parameters
    ----------
    skeleton : Skeleton
        The skeleton the weights were trained for (else a ``ValueError`` names the difference).
    arch : str
        ``"protores"`` (default), ``"masked-fcr"`` or ``"transformer"``.
    weights : str or Path, optional
        A ``protores`` checkpoint (default the shipped one of ``arch``).
    net : PosingNet, optional
        A network already in memory (the notebook's live demo).

    The ProtoRes and Masked-FCR encoders are read without torch and pose up to :data:`NUMPY_BATCH` requests in
    numpy; the torch network (:attr:`net`) is loaded the first time a larger batch, or the Transformer, needs it.
    """

    kinds = KINDS
    needs_start = False
    keeps_bone_lengths = True
    batch_atol = 1e-4

    def __init__(self, skeleton, arch: str = "protores", weights=None, net=None):
        if arch not in ARCHS:
            raise ValueError(f"arch must be one of {', '.join(ARCHS)}, got {arch!r}")
        self._weights, self._net, self.arch, self.skeleton = weights, net, arch, skeleton
        if net is not None:
            net.eval()
            self._numpy = NumpyPosingNet(net) if net.config.arch != "transformer" else None
            trained, self.arch = net.skeleton, net.config.arch
        elif arch == "transformer":
            self._numpy = None
            trained = self.net.skeleton
        else:
            self._numpy = load_numpy(arch, weights, skeleton)
            trained, self.arch = self._numpy.skeleton, self._numpy.arch
        require_skeleton(f"{arch} solver: the network", trained, skeleton)
        self.name = "protores" if self.arch == "protores" else f"protores-{self.arch}"
        self.body = np.asarray(body_joints(skeleton), dtype=np.int64)
        self._body_lookup = np.full(skeleton.n_joints, -1, dtype=np.int64)
        self._body_lookup[self.body] = np.arange(len(self.body))
        self.span = skeleton_span(skeleton)

    @property
    def net(self):
        """The torch :class:`~posekit.models.protores.networks.PosingNet` (loaded, with torch, when first asked)."""
        if self._net is None:
            self._net = load_protores(self.arch, self._weights, self.skeleton)
            self._net.eval()
        return self._net

    # ------------------------------------------------------------------------------ arrays
    def predict(self, joint, kind, value, tol):
        """The array-level prediction of B poses with N effectors each.

        Parameters
        ----------
        joint : array of int, shape (B, N) or (N,)
            Skeleton joint indices (body joints only).
        kind : array of int, shape (B, N) or (N,)
            :data:`~posekit.models.protores.networks.KIND_IDS`.
        value : array, shape (B, N, 6) or (N, 6)
            Position + zeros; 6D world rotation; look-at target + local direction (metres, world frame).
        tol : array, shape (B, N) or (N,)
            ``Lambda`` in [0, 1].

        Returns
        -------
        dict of ndarray
            ``global_pos`` (B, J, 3), ``local_rot`` (B, J, 4) quaternions, ``root_pos`` (B, 3), ``gpd_pos``
            (B, J, 3) or None, ``global_rot`` (B, J, 3, 3), ``out_of_range`` (B, N) bool.

        Raises
        ------
        ValueError
            Mismatched shapes; zero or more than :data:`MAX_EFFECTORS` effectors; a joint that is not a body
            joint; an unknown kind; NaN or inf; a tolerance outside [0, 1].
        """
        joint, kind = np.asarray(joint), np.asarray(kind)
        value, tol = np.asarray(value, dtype=np.float64), np.asarray(tol, dtype=np.float64)
        one = joint.ndim == 1
        if one:
            joint, kind, value, tol = (a[None] for a in (joint, kind, value, tol))
        if (joint.ndim != 2 or kind.shape != joint.shape or tol.shape != joint.shape
                or value.shape != joint.shape + (6,)):
            raise ValueError(f"expected joint and kind (B, N), value (B, N, 6), tol (B, N); got {joint.shape}, "
                             f"{kind.shape}, {value.shape}, {tol.shape}")
        N = joint.shape[1]
        if N == 0:
            raise ValueError(f"{self.name}: expected at least one effector, got none")
        if N > MAX_EFFECTORS:
            raise ValueError(f"{self.name}: at most {MAX_EFFECTORS} effectors per pose, got {N}")
        bad = (joint < 0) | (joint >= self.skeleton.n_joints)
        bad[~bad] = self._body_lookup[joint[~bad]] < 0
        if bad.any():
            j = int(joint[bad][0])
            what = self.skeleton.names[j] if 0 <= j < self.skeleton.n_joints else str(j)
            raise ValueError(f"{self.name}: joint {what} is not a body joint of {self.skeleton.name!r}; valid: "
                             + ", ".join(self.skeleton.names[b] for b in self.body))
        if ((kind < 0) | (kind > 2)).any():
            raise ValueError(f"{self.name}: unknown kind id {int(kind[(kind < 0) | (kind > 2)][0])}; valid: "
                             + ", ".join(f"{v} {k}" for k, v in KIND_IDS.items()))
        if not (np.isfinite(value).all() and np.isfinite(tol).all()):
            raise ValueError(f"{self.name}: effector values or tolerances contain NaN or inf")
        if (tol < 0).any() or (tol > 1).any():
            raise ValueError(f"{self.name}: tolerance Lambda must lie in [0, 1] (0 exact, 1 loosest: "
                             f"{SIGMA_M} m or rad of noise), got {float(tol[(tol < 0) | (tol > 1)][0])!r}")
        bj = self._body_lookup[joint]
        exact = self._numpy is not None and len(bj) <= NUMPY_BATCH  # few requests: the numpy pass is faster
        if exact:  # its pose is float64 FK of its rotations already
            out = self._numpy.forward(bj, kind, value, tol)
        else:
            import torch

            with torch.no_grad():
                t = [torch.as_tensor(bj), torch.as_tensor(kind, dtype=torch.int64),
                     torch.as_tensor(value, dtype=torch.float32), torch.as_tensor(tol, dtype=torch.float32)]
                out = {k: None if v is None else v.numpy() for k, v in self.net(*t).items()}
        far = (kind == KIND_IDS["position"]) & (
            np.linalg.norm(value[..., :3] - out["centroid"][:, None], axis=-1) > self.span)
        f64 = lambda a: None if a is None else a.astype(np.float64)  # noqa: E731
        # the pose as float64 quaternions and root, and its FK in float64: a Pose that is exactly what
        # FK of its rotations gives (the network's own float32 FK agrees to about 1e-6 m)
        quats = matrix_to_quat(f64(out["local_rot"]))
        quats /= np.linalg.norm(quats, axis=-1, keepdims=True)
        root = f64(out["root_pos"])
        gpos, grot = (out["global_pos"], out["global_rot"]) if exact else fk(self.skeleton, quats, root)
        res = {"global_pos": gpos, "global_rot": grot, "local_rot": quats, "root_pos": root,
               "gpd_pos": f64(out["gpd_pos"]), "out_of_range": far}
        if one:
            res = {k: None if v is None else v[0] for k, v in res.items()}
        return res

    def arrays(self, resolved):
        """A :class:`~posekit.ik.effectors.ResolvedEffectors` as :meth:`predict`'s inputs
        ``(joint (N,), kind (N,), value (N, 6), Lambda (N,))``."""
        N = len(resolved)
        kind = np.array([KIND_IDS[k] for k in resolved.kinds], dtype=np.int64)
        value = np.zeros((N, 6))
        for k in range(N):
            if kind[k] == 1:
                value[k] = matrix_to_sixd(resolved.rotation[k])
            else:
                value[k, :3] = resolved.position[k]
                if kind[k] == 2:
                    value[k, 3:] = resolved.axis[k]
        tol = np.asarray(resolved.tolerance, dtype=float)
        if (tol > SIGMA_M).any():
            k = int(np.argmax(tol > SIGMA_M))
            raise ValueError(f"{self.name}: the {resolved.kinds[k]} effector on {resolved.names[k]} has tolerance "
                             f"{tol[k]:.3g}; ProtoRes models tolerances up to sigma_M = {SIGMA_M} (metres or "
                             "radians, Lambda = 1)")
        return resolved.joints.copy(), kind, value, sigma_to_tolerance(tol)

    # ------------------------------------------------------------------------------ Solver API
    def _result(self, res, resolved, b=None):
        pick = (lambda v: v) if b is None else (lambda v: v[b])
        pose = Pose(pick(res["global_pos"]), pick(res["local_rot"]), pick(res["root_pos"]))
        info = {"arch": self.arch}
        far = pick(res["out_of_range"])
        if far.any():
            info["out_of_range"] = [resolved.names[k] for k in np.nonzero(far)[0]]
        return self.result(pose, resolved, 1, info, global_rot=pick(res["global_rot"]))

    def _solve(self, start, resolved):
        return self._result(self.predict(*self.arrays(resolved)), resolved)

    def _solve_many(self, starts, resolved):
        # one network pass per group of problems with the same number of effectors
        arrays = [self.arrays(r) for r in resolved]
        out = [None] * len(resolved)
        sizes = np.array([len(r) for r in resolved])
        for n in np.unique(sizes):
            idx = np.nonzero(sizes == n)[0]
            res = self.predict(*(np.stack([arrays[i][f] for i in idx]) for f in range(4)))
            for b, i in enumerate(idx):
                out[i] = self._result(res, resolved[i], b)
        return out


def _variant(arch):
    def factory(skeleton, weights=None, **options):
        return ProtoResSolver(skeleton, arch=arch, weights=weights, **options)

    return factory


_LESSON = "notebooks/05_protores.ipynb"
_COMMON = dict(kinds=KINDS, needs_start=False, lesson=_LESSON, data="bandai-mini")
register("protores", _variant("protores"), **_COMMON,
         description="ProtoRes (Oreshkin et al. 2022): any effectors -> a full pose in one pass")
register("protores-masked-fcr", _variant("masked-fcr"), **_COMMON,
         description="ProtoRes's Masked-FCR baseline (fixed-size input with learned placeholders)")
register("protores-transformer", _variant("transformer"), **_COMMON,
         description="ProtoRes's Transformer baseline (torch nn.Transformer encoder)")


def run_learned(solver, bench, tolerance=None) -> dict:
    """Predict every case of an effector benchmark (:class:`posekit.evaluation.effector_cases.EffectorBenchmark`)
    with a :class:`ProtoResSolver`'s array path (one pass per effector count), for
    :func:`posekit.evaluation.effector_scores.scores`. ``tolerance``: a Lambda for every effector instead of the cases' own
    (their metres/radians turned into Lambda). Returns the arrays ``global_pos``, ``local_rot``,
    ``global_rot``, ``gpd_pos`` (C, ...) and ``out_of_range`` (count)."""
    C, J = len(bench), bench.skeleton.n_joints
    res = {"global_pos": np.empty((C, J, 3)), "local_rot": np.empty((C, J, 4)), "global_rot": np.empty((C, J, 3, 3)),
           "gpd_pos": np.empty((C, J, 3)) if solver.net.gpd is not None else None, "out_of_range": 0}
    lam = sigma_to_tolerance(np.minimum(bench.tolerance, 0.1)) if tolerance is None else np.full(bench.tolerance.shape,
                                                                                                  float(tolerance))
    for n in np.unique(bench.n):
        idx = np.nonzero(bench.n == n)[0]
        r = solver.predict(bench.joint[idx, :n], bench.kind[idx, :n], bench.value[idx, :n], lam[idx, :n])
        for k in ("global_pos", "local_rot", "global_rot"):
            res[k][idx] = r[k]
        if res["gpd_pos"] is not None:
            res["gpd_pos"][idx] = r["gpd_pos"]
        res["out_of_range"] += int(r["out_of_range"].any(1).sum())
    return res
