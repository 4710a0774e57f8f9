"""The parts ProtoRes (Oreshkin et al. 2022) and its baselines share: sizes, the effector inputs, the blocks.

Introduced in ``notebooks/05_protores.ipynb``. Units and axes: :mod:`posekit.conventions` (metres,
radians, Y up, facing +Z); 6D rotations are the first two columns of a matrix.

* :class:`ProtoResConfig` — the sizes of a network, whichever encoder it has;
* the inputs of Sec. 2.1 — :func:`centroid` (the tolerance-weighted centroid of the positional
  effectors), :func:`effector_inputs` (values re-referenced to it), :class:`Tokens` (values, tolerance,
  joint and kind embeddings);
* the fully connected blocks — :class:`FCBlock` (layers, backcast and forecast, after N-BEATS) and
  :class:`FCR` (blocks in a row, forecasts summed): the decoders of Eq. 3-4 and the Masked-FCR encoder;
* the tolerance <-> noise scale of Appendix B (:func:`tolerance_to_sigma`).

The model itself — the proto-residual encoder, the decoders' use and FK — is :mod:`posekit.models.protores.networks`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import torch
from torch import nn

from ...ik.effectors import KIND_CODES
from .fast import ARCHS  # the encoders, named where the torch-free numpy pass reads them too
from .tolerance import ETA, SIGMA_M, sigma_to_tolerance, tolerance_to_sigma  # noqa: F401 - re-exported

__all__ = ["ARCHS", "KIND_IDS", "SIGMA_M", "ETA", "ProtoResConfig", "centroid", "effector_inputs", "Tokens",
           "FCBlock", "FCR", "tolerance_to_sigma", "sigma_to_tolerance"]

KIND_IDS = KIND_CODES
"""Effector kind -> type id (the type embedding's row): the solvers' own codes
(:data:`posekit.ik.effectors.KIND_CODES`, position 0, rotation 1, look-at 2)."""



@dataclass
class ProtoResConfig:
    """Sizes of a :class:`PosingNet` (the paper's are R = 3, L = 3, width 1024; ours default smaller for a CPU).

    Attributes
    ----------
    n_joints : int
        Body joints B of the skeleton (outputs: B positions, B rotations).
    arch : str
        One of :data:`ARCHS`.
    width : int
        Units of every fully connected layer (encoder and decoders).
    blocks, layers : int
        R blocks of L layers in the encoder (and in each decoder).
    embed : int
        Size of the joint and type embeddings (32 in the paper).
    gpd : bool
        Whether the IKD reads the GPD's positions and FK is rooted at the GPD's pelvis (Table 2's
        ablation: without it the IKD predicts the pelvis position itself).
    d_model, heads, enc_layers, dec_layers : int
        The Transformer baseline's sizes (128, 8, 2, 2 in the paper).
    """

    n_joints: int
    arch: str = "protores"
    width: int = 128
    blocks: int = 3
    layers: int = 3
    embed: int = 32
    gpd: bool = True
    d_model: int = 128
    heads: int = 8
    enc_layers: int = 2
    dec_layers: int = 2
    extra: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.arch not in ARCHS:
            raise ValueError(f"arch must be one of {', '.join(ARCHS)}, got {self.arch!r}")

    @property
    def n_in(self) -> int:
        """Numbers per effector token: 6 values + tolerance + two embeddings."""
        return 7 + 2 * self.embed

    def to_dict(self) -> dict:
        return asdict(self)


# ------------------------------------------------------------------------------------------ inputs
def centroid(kind, value, tol):
    """Tolerance-weighted centroid of the positional effectors (Sec. 2.1), shape (B, 3), metres.

    Weights ``1 - Lambda + 1e-3`` (a tight effector counts most); look-at targets and rotations do not
    count; a set with no position effector is centred on the origin.

    Parameters
    ----------
    kind : tensor of int, shape (B, N)
        :data:`KIND_IDS`.
    value : tensor, shape (B, N, 6)
    tol : tensor, shape (B, N), in [0, 1]
    """
    w = (kind == KIND_IDS["position"]).to(value.dtype) * (1.0 - tol + 1e-3)
    s = w.sum(1, keepdim=True)
    return (w[..., None] * value[..., :3]).sum(1) / s.clamp_min(1e-9) * (s > 0).to(value.dtype)


def effector_inputs(kind, value, c):
    """The effector values re-referenced to the centroid ``c`` (B, 3): positions and look-at targets
    minus ``c``; 6D rotations and look-at directions unchanged. Shape (B, N, 6)."""
    shift = (kind != KIND_IDS["rotation"]).to(value.dtype)[..., None] * c[:, None, :]
    return torch.cat([value[..., :3] - shift, value[..., 3:]], dim=-1)


class Tokens(nn.Module):
    """Sec. 2.1: one token per effector, ``[values (6), Lambda, e_joint (embed), e_type (embed)]``."""

    def __init__(self, cfg: ProtoResConfig):
        super().__init__()
        self.joint = nn.Embedding(cfg.n_joints, cfg.embed)
        self.kind = nn.Embedding(len(KIND_IDS), cfg.embed)

    def forward(self, joint, kind, values, tol):
        return torch.cat([values, tol[..., None], self.joint(joint), self.kind(kind)], dim=-1)


# ------------------------------------------------------------------------------------------ blocks
class FCBlock(nn.Module):
    """One fully connected block (the unit of Eq. 2-4): ``h = FC_L(... FC_1(x))`` with LeakyReLU after
    each layer; returns the backcast ``b = relu(h + W_b x)`` and the forecast ``f = W_f h``.
    Shapes (..., n_in) -> ((..., width), (..., n_out))."""

    def __init__(self, n_in: int, width: int, layers: int, n_out: int):
        super().__init__()
        self.fc = nn.ModuleList(nn.Linear(n_in if i == 0 else width, width) for i in range(layers))
        self.skip = nn.Linear(n_in, width)
        self.forecast = nn.Linear(width, n_out)

    def forward(self, x):
        h = x
        for fc in self.fc:
            h = nn.functional.leaky_relu(fc(h))
        return torch.relu(h + self.skip(x)), self.forecast(h)


class FCR(nn.Module):
    """A fully connected residual network (the decoders of Eq. 3-4, the Masked-FCR encoder).

    R :class:`FCBlock` s in a row: block ``r`` reads the previous block's backcast, and the output is
    the sum of the blocks' forecasts, ``y = sum_r f_r``. Shapes (..., n_in) -> (..., n_out).
    """

    def __init__(self, n_in: int, n_out: int, width: int, blocks: int, layers: int):
        super().__init__()
        self.blocks = nn.ModuleList(FCBlock(n_in if r == 0 else width, width, layers, n_out) for r in range(blocks))

    def forward(self, x):
        y = 0.0
        for block in self.blocks:
            x, f = block(x)
            y = y + f
        return y
