"""ProtoRes's forward pass in numpy: the same network, for one request at a time without torch's per-call cost.

Introduced in ``notebooks/05_protores.ipynb`` (the speed table). A pass through a
:class:`~posekit.models.protores.networks.PosingNet` is some 300 small tensor operations; for one pose torch's fixed
cost per operation, not arithmetic, sets the time. :class:`NumpyPosingNet` holds the trained weights as
float32 arrays and runs Eq. 2-6 with plain matrix products (and FK joint by joint), which is what
:meth:`ProtoResSolver.solve <posekit.models.protores.solver.ProtoResSolver>` uses for the ProtoRes and
Masked-FCR encoders; batches, and the Transformer, go through torch. Tested equal to the torch pass to
float32 rounding. :meth:`NumpyPosingNet.load` reads the weights without torch (the studio's small kernels).
"""

from __future__ import annotations

import numpy as np

from ...data.metrics import body_joints
from ...rotations import sixd_to_matrix

__all__ = ["NumpyPosingNet", "ARCHS", "KIND", "WEIGHTS", "weights_path"]

ARCHS = ("protores", "masked-fcr", "transformer")
"""Encoders: the paper's model and its two baselines (Table 1)."""

KIND = "protores"
"""Checkpoint kind of every :class:`~posekit.models.protores.networks.PosingNet` (ProtoRes and its baselines)."""

WEIGHTS = {"protores": "protores.pt", "masked-fcr": "protores_masked_fcr.pt", "transformer": "protores_transformer.pt"}
"""File names of the shipped weights in ``data_samples/weights/``."""


def weights_path(arch: str = "protores", folder=None):
    """The weights' file of the encoder ``arch`` (:data:`WEIGHTS`) in ``folder`` or the shipped weights'
    folder (:func:`posekit.paths.weights_path`)."""
    from ... import paths

    if arch not in WEIGHTS:
        raise ValueError(f"arch must be one of {', '.join(WEIGHTS)}, got {arch!r}")
    return paths.weights_path(WEIGHTS[arch], folder)


def _lin(state, name):
    return (np.ascontiguousarray(np.asarray(state[f"{name}.weight"]).T, dtype=np.float32),
            np.asarray(state[f"{name}.bias"]).astype(np.float32))


def _block(state, name, layers):
    return ([_lin(state, f"{name}.fc.{k}") for k in range(layers)], _lin(state, f"{name}.skip"),
            _lin(state, f"{name}.forecast"))


def _fcr(state, name, blocks, layers):
    """An FCR stack's blocks ``{name}.blocks.{i}``; exactly ``blocks`` of ``layers`` layers each."""
    if f"{name}.blocks.{blocks}.skip.weight" in state or f"{name}.blocks.0.fc.{layers}.weight" in state:
        raise KeyError(f"{name}: more blocks or layers than the config's {blocks} x {layers}")
    return [_block(state, f"{name}.blocks.{i}", layers) for i in range(blocks)]


def _run_block(blk, x):
    fcs, (Ws, bs), (Wf, bf) = blk
    h = x
    for W, b in fcs:
        h = h @ W + b
        h = np.maximum(h, np.float32(0.01) * h)  # LeakyReLU, torch's default slope
    return np.maximum(h + x @ Ws + bs, 0), h @ Wf + bf


def _run_fcr(blocks, x):
    y = 0.0
    for blk in blocks:
        x, f = _run_block(blk, x)
        y = y + f
    return y


class NumpyPosingNet:
    """A :class:`~posekit.models.protores.networks.PosingNet` (ProtoRes or Masked-FCR encoder) in numpy.

    ``forward(joint, kind, value, tol)`` takes the arrays of ``PosingNet.forward`` (body-joint ids, kind ids,
    values (B, N, 6), Lambda) and returns ``global_pos`` (B, J, 3), ``global_rot`` (B, J, 3, 3),
    ``local_rot`` (B, J, 3, 3), ``root_pos`` (B, 3) — float64, the pose exactly FK of its rotations — and
    ``gpd_pos`` (B, J, 3) or None and ``centroid`` (B, 3) (float32).
    """

    def __init__(self, net):
        state = {k: v.detach().cpu().numpy() for k, v in net.state_dict().items()}
        self._build(state, net.config.to_dict(), net.skeleton)
        self.checkpoint = getattr(net, "checkpoint", None)

    @classmethod
    def load(cls, path, skeleton=None) -> "NumpyPosingNet":
        """Read a :meth:`PosingNet.save <posekit.models.protores.networks.PosingNet.save>` file without torch;
        with ``skeleton`` it must be the one the weights were made for, else a ``ValueError`` names the
        difference (as :meth:`PosingNet.load <posekit.models.protores.networks.PosingNet.load>`)."""
        from ...learn.checkpoint import load_checkpoint

        ck = load_checkpoint(path, kind=KIND, skeleton=skeleton, arrays=True)
        self = cls.__new__(cls)
        try:
            self._build(ck["state"], ck["config"], ck["skeleton"])
        except KeyError as err:
            raise ValueError(f"checkpoint {path}: weights do not match its config (missing or extra {err})") from None
        self.checkpoint = {k: ck[k] for k in ("command", "seed", "data", "licence", "extra")}
        return self

    def _build(self, state, config: dict, skeleton):
        """The arrays of the forward pass from a state dict (name -> array) and the config's fields (the
        :class:`~posekit.models.protores.networks.PosingNet` layout)."""
        arch, gpd = config.get("arch", "protores"), bool(config.get("gpd", True))
        if arch == "transformer":
            raise ValueError("NumpyPosingNet covers the ProtoRes and Masked-FCR encoders; the Transformer runs in "
                             "torch")
        blocks, layers = int(config["blocks"]), int(config["layers"])
        self.arch, self.config, self.skeleton = arch, dict(config), skeleton
        f32 = lambda name: np.asarray(state[name]).astype(np.float32)  # noqa: E731
        if arch == "protores":
            self.emb_joint, self.emb_kind = f32("tokens.joint.weight"), f32("tokens.kind.weight")
            self.encoder = _fcr(state, "encoder", blocks, layers)
        else:
            self.placeholder = f32("encoder.placeholder")
            self.encoder = _fcr(state, "encoder.fcr", blocks, layers)
        self.gpd = _fcr(state, "gpd", blocks, layers) if gpd else None
        self.ikd = _fcr(state, "ikd", blocks * (1 if gpd else 2), layers)
        s = skeleton
        self.parents = np.asarray(s.parents)
        self.offsets = np.asarray(s.offsets, dtype=np.float64)
        self.body = np.asarray(body_joints(s), dtype=np.int64)
        if int(config["n_joints"]) != len(self.body):
            raise ValueError(f"config.n_joints is {config['n_joints']} but skeleton {s.name!r} has {len(self.body)} "
                             "body joints")
        pel = s.pelvis()
        self.pelvis_index = int(np.nonzero(self.body == pel)[0][0])
        self.helper_root = int(s.parents[pel]) if s.parents[pel] >= 0 else -1
        self.pelvis_offset = np.asarray(s.offsets[pel], dtype=np.float64)
        self.J = s.n_joints
        self.n_params = sum(int(np.asarray(v).size) for k, v in state.items() if k != "pelvis_offset")

    def n_parameters(self) -> int:
        """Weights in the network (the torch :class:`~posekit.models.protores.networks.PosingNet`'s count)."""
        return self.n_params

    def _centroid(self, kind, value, tol):
        w = (kind == 0).astype(np.float32) * (np.float32(1) - tol + np.float32(1e-3))
        s = w.sum(1, keepdims=True)
        return (w[..., None] * value[..., :3]).sum(1) / np.maximum(s, 1e-9) * (s > 0)

    def forward(self, joint, kind, value, tol):
        value = np.asarray(value, dtype=np.float32)
        tol = np.asarray(tol, dtype=np.float32)
        Bn, N = joint.shape
        c = self._centroid(kind, value, tol)
        shift = (kind != 1).astype(np.float32)[..., None] * c[:, None, :]
        v = np.concatenate([value[..., :3] - shift, value[..., 3:]], axis=-1)
        if self.arch == "protores":
            x = np.concatenate([v, tol[..., None], self.emb_joint[joint], self.emb_kind[kind]], axis=-1)
            e = 0.0
            for r, blk in enumerate(self.encoder, start=1):
                b, f = _run_block(blk, x)
                e = e + f
                p = e.mean(axis=1)
                x = np.maximum(b - p[:, None, :] / np.float32(r), 0)
            code = p
        else:
            table = np.repeat(self.placeholder[None], Bn, axis=0)
            table[np.arange(Bn)[:, None], kind, joint] = np.concatenate([v, tol[..., None]], axis=-1)
            code = _run_fcr(self.encoder, table.reshape(Bn, -1))
        nb = len(self.body)
        gpd = None
        if self.gpd is not None:
            gpd = _run_fcr(self.gpd, code).reshape(Bn, nb, 3)
            pelvis = gpd[:, self.pelvis_index]
            out = _run_fcr(self.ikd, np.concatenate([code, (gpd - pelvis[:, None]).reshape(Bn, -1)], axis=-1))
        else:
            out = _run_fcr(self.ikd, code)
            pelvis = out[:, 6 * nb:]
        # from here on float64: Gram-Schmidt and FK, so that the pose is exactly FK of its rotations
        local = np.broadcast_to(np.eye(3), (Bn, self.J, 3, 3)).copy()
        local[:, self.body] = sixd_to_matrix(out[:, :6 * nb].reshape(Bn, nb, 6))
        pelvis = (pelvis + c).astype(np.float64)
        root = pelvis - self.pelvis_offset if self.helper_root >= 0 else pelvis
        G = np.empty_like(local)
        P = np.empty((Bn, self.J, 3))
        G[:, 0], P[:, 0] = local[:, 0], root
        for j in range(1, self.J):
            p = self.parents[j]
            G[:, j] = G[:, p] @ local[:, j]
            P[:, j] = P[:, p] + G[:, p] @ self.offsets[j]
        gpd_full = None
        if gpd is not None:
            gpd_full = np.zeros((Bn, self.J, 3), dtype=np.float32)
            gpd_full[:, self.body] = gpd + c[:, None]
            if self.helper_root >= 0:
                gpd_full[:, self.helper_root] = root
        return {"gpd_pos": gpd_full, "local_rot": local, "root_pos": root, "global_pos": P, "global_rot": G,
                "centroid": c}
