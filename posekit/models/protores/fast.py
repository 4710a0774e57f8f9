"""ProtoRes's forward pass in numpy: the same network, for one request at a time without torch's per-call cost.

Introduced in ``notebooks/05_protores.ipynb`` (the speed table). A pass through a
:class:`~posekit.models.protores.networks.PosingNet` is some 300 small tensor operations; for one pose torch's fixed
cost per operation, not arithmetic, sets the time. :class:`NumpyPosingNet` holds the trained weights as
float32 arrays and runs Eq. 2-6 with plain matrix products (and FK joint by joint), which is what
:meth:`ProtoResSolver.solve <posekit.models.protores.solver.ProtoResSolver>` uses for the ProtoRes and
Masked-FCR encoders; batches, and the Transformer, go through torch. Tested equal to the torch pass to
float32 rounding.
"""

from __future__ import annotations

import numpy as np

from ...rotations import sixd_to_matrix

__all__ = ["NumpyPosingNet"]


def _lin(layer):
    return (np.ascontiguousarray(layer.weight.detach().numpy().T, dtype=np.float32),
            layer.bias.detach().numpy().astype(np.float32))


def _block(block):
    return ([_lin(fc) for fc in block.fc], _lin(block.skip), _lin(block.forecast))


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
        from .networks import centroid  # noqa: F401  (the same centroid rule, written below in numpy)

        cfg = net.config
        if cfg.arch == "transformer":
            raise ValueError("NumpyPosingNet covers the ProtoRes and Masked-FCR encoders; the Transformer runs in "
                             "torch")
        self.arch = cfg.arch
        if cfg.arch == "protores":
            self.emb_joint = net.tokens.joint.weight.detach().numpy().astype(np.float32)
            self.emb_kind = net.tokens.kind.weight.detach().numpy().astype(np.float32)
            self.encoder = [_block(b) for b in net.encoder.blocks]
        else:
            self.placeholder = net.encoder.placeholder.detach().numpy().astype(np.float32)
            self.encoder = [_block(b) for b in net.encoder.fcr.blocks]
        self.gpd = None if net.gpd is None else [_block(b) for b in net.gpd.blocks]
        self.ikd = [_block(b) for b in net.ikd.blocks]
        s = net.skeleton
        self.parents = np.asarray(s.parents)
        self.offsets = np.asarray(s.offsets, dtype=np.float64)
        self.body = net.body
        self.pelvis_index = net.pelvis_index
        self.helper_root = net.helper_root
        self.pelvis_offset = np.asarray(s.offsets[s.pelvis()], dtype=np.float64)
        self.J = s.n_joints

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
