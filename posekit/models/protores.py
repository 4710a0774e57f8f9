"""ProtoRes (Oreshkin et al. 2021, Sec. 2): a full pose from a variable set of effectors, top to bottom.

Introduced in ``notebooks/05_protores.ipynb``. Units and axes: :mod:`posekit.conventions` (metres,
radians, Y up, facing +Z); 6D rotations are the first two columns of a matrix
(:func:`posekit.rotations.matrix_to_sixd`).

The network reads N effectors, each of one of three kinds on one body joint, and writes a whole pose:

* **Inputs** (Sec. 2.1, :func:`effector_inputs`) — per effector 6 numbers (a position and three zeros,
  a 6D world rotation, or a look-at target and the joint's local look-at direction), its tolerance
  ``Lambda`` in [0, 1], and two learned embeddings (of the joint and of the kind, 32 numbers each),
  concatenated. Positions are taken relative to the tolerance-weighted centroid of the positional
  effectors (:func:`centroid`), so the network never sees where the character stands.
* **Proto-residual encoder** (Eq. 2, :class:`ProtoResEncoder`) — R blocks of L fully connected ReLU
  layers applied to every effector; each block emits a backcast and a prototype contribution, the
  prototype is the mean over effectors accumulated over blocks, and the next block reads
  ``relu(b_r - p_r / r)``: every effector's features minus what the set as a whole already explains.
  The pose code is the final prototype, one vector whatever N is.
* **Global position decoder** (Eq. 3, GPD) — an FC residual network: code -> every body joint's
  position (relative to the centroid).
* **Inverse kinematics decoder** (Eq. 4-5, IKD) — code and the GPD's positions -> every body joint's
  local rotation in 6D, made orthonormal by Gram-Schmidt.
* **Forward kinematics** (Eq. 6) — :func:`posekit.kinematics.fk` in torch, rooted at the GPD's pelvis,
  so the final pose keeps every bone length.

The two baselines of the paper's Table 1 (:mod:`posekit.models.protores_baselines`: Masked-FCR and a
Transformer) swap the encoder and keep the decoders and FK; :class:`PosingNet` holds any of the three.
A :class:`PosingNet` saves to one :mod:`posekit.learn.checkpoint` (kind ``"protores"``).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np
import torch
from torch import nn

from ..data.metrics import body_joints
from ..kinematics import fk
from ..learn import load_checkpoint, save_checkpoint
from ..rotations import sixd_to_matrix

__all__ = ["KIND", "ARCHS", "KIND_IDS", "SIGMA_M", "ETA", "ProtoResConfig", "centroid", "effector_inputs",
           "FCBlock", "FCR", "ProtoResEncoder", "PosingNet", "tolerance_to_sigma", "sigma_to_tolerance"]

KIND = "protores"
"""Checkpoint kind of every :class:`PosingNet` (ProtoRes and its baselines)."""

ARCHS = ("protores", "masked-fcr", "transformer")
"""Encoders: the paper's model and its two baselines (Table 1)."""

KIND_IDS = {"position": 0, "rotation": 1, "look_at": 2}
"""Effector kind -> type id (the type embedding's row)."""

SIGMA_M = 0.1
"""sigma_M: the noise scale of tolerance 1 (Appendix B): 0.1 m for positions, 0.1 rad for angles."""

ETA = 13.0
"""eta: the tolerance-to-noise exponent, ``sigma = sigma_M Lambda^eta`` (Appendix B)."""


def tolerance_to_sigma(lam):
    """``sigma = sigma_M Lambda^eta``: a tolerance in [0, 1] as a noise scale (metres or radians)."""
    return SIGMA_M * lam ** ETA


def sigma_to_tolerance(sigma):
    """The inverse of :func:`tolerance_to_sigma`: a noise scale in [0, sigma_M] as ``Lambda`` in [0, 1]."""
    return (np.asarray(sigma, dtype=float) / SIGMA_M) ** (1.0 / ETA)


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


class ProtoResEncoder(nn.Module):
    """Eq. 2 of Oreshkin et al. 2021: the proto-residual encoder, tokens (B, N, n_in) -> code (B, width).

    Block ``r = 1..R`` (an :class:`FCBlock`) on every effector's input ``x_r``::

        b_r, f_r = FCBlock_r(x_r)                    backcast and forecast, per effector
        e_r      = e_{r-1} + f_r                      each effector's encoding, accumulated over blocks
        p_r      = mean_i e_{r,i}                     the prototype: what the whole set says
        x_{r+1}  = relu(b_r - p_r / r)                each effector minus what the set already explains

    with ``e_0 = 0`` and ``x_1`` the tokens; the pose code is ``p_R``. (The paper writes the feedback
    with ``r - 1`` for its block numbering from 2; the authors' code divides by the 1-based index of the
    block just run, as here.) The mean makes the code independent of the effectors' order and defined
    for any N >= 1.
    """

    def __init__(self, n_in: int, width: int, blocks: int, layers: int):
        super().__init__()
        self.blocks = nn.ModuleList(FCBlock(n_in if r == 0 else width, width, layers, width) for r in range(blocks))
        self.out_features = width

    def forward(self, x):
        e = 0.0
        for r, block in enumerate(self.blocks, start=1):
            b, f = block(x)
            e = e + f
            p = e.mean(dim=1)
            x = torch.relu(b - p[:, None, :] / r)
        return p


# ------------------------------------------------------------------------------------------ the net
class PosingNet(nn.Module):
    """Effectors -> pose: an encoder of :data:`ARCHS`, the GPD, the IKD and FK (Sec. 2, Fig. 2).

    Parameters
    ----------
    skeleton : Skeleton
        Outputs cover its body joints (:func:`~posekit.data.metrics.body_joints`); a helper root
        (Bandai's ``joint_Root``) gets the identity rotation and sits its rest offset below the pelvis.
    config : ProtoResConfig
    """

    def __init__(self, skeleton, config: ProtoResConfig):
        super().__init__()
        from .protores_baselines import MaskedFCREncoder, TransformerEncoder

        self.skeleton, self.config = skeleton, config
        self.body = np.asarray(body_joints(skeleton), dtype=np.int64)
        B = len(self.body)
        if config.n_joints != B:
            raise ValueError(f"config.n_joints is {config.n_joints} but skeleton {skeleton.name!r} has {B} body joints")
        w = config.width
        if config.arch == "protores":
            self.tokens = Tokens(config)
            self.encoder = ProtoResEncoder(config.n_in, w, config.blocks, config.layers)
        elif config.arch == "transformer":
            self.tokens = Tokens(config)
            self.encoder = TransformerEncoder(config)
        else:
            self.tokens = None
            self.encoder = MaskedFCREncoder(config)
        code = self.encoder.out_features
        self.gpd = FCR(code, 3 * B, w, config.blocks, config.layers) if config.gpd else None
        # without the GPD one decoder of twice the blocks predicts the rotations and the pelvis (the
        # authors' single-stage ablation)
        self.ikd = FCR(code + 3 * B * config.gpd, 6 * B + 3 * (not config.gpd), w,
                       config.blocks * (1 if config.gpd else 2), config.layers)
        pel = skeleton.pelvis()
        self.pelvis_index = int(np.nonzero(self.body == pel)[0][0])
        self.helper_root = int(skeleton.parents[pel]) if skeleton.parents[pel] >= 0 else -1
        self.register_buffer("pelvis_offset", torch.tensor(np.asarray(skeleton.offsets[pel], dtype=np.float32)))

    def n_parameters(self) -> int:
        return sum(p.numel() for p in self.parameters())

    def encode(self, joint, kind, value, tol):
        """The pose code (B, code) of effectors already re-referenced (see :meth:`forward`)."""
        if self.tokens is None:
            return self.encoder(joint, kind, value, tol)
        return self.encoder(self.tokens(joint, kind, value, tol))

    def forward(self, joint, kind, value, tol):
        """Predict poses.

        Parameters
        ----------
        joint : tensor of int, shape (B, N)
            Body-joint index of each effector (0..n_joints-1, the order of ``body_joints``).
        kind : tensor of int, shape (B, N)
            :data:`KIND_IDS`.
        value : tensor, shape (B, N, 6), world frame, metres
            Position (3) + zeros; 6D world rotation; look-at target (3) + local direction (3).
        tol : tensor, shape (B, N)
            Tolerance ``Lambda`` in [0, 1].

        Returns
        -------
        dict of tensors
            ``gpd_pos`` (B, J, 3) the GPD's positions (None without the GPD); ``local_rot`` (B, J, 3, 3);
            ``root_pos`` (B, 3); ``global_pos`` (B, J, 3) and ``global_rot`` (B, J, 3, 3) by FK. ``J`` is the
            skeleton's joint count (helper root included), world frame.
        """
        c = centroid(kind, value, tol)
        code = self.encode(joint, kind, effector_inputs(kind, value, c), tol)
        Bn, nb = code.shape[0], len(self.body)
        gpd = None
        if self.gpd is not None:
            gpd = self.gpd(code).reshape(Bn, nb, 3)
            pelvis = gpd[:, self.pelvis_index]
            # Eq. 4: the IKD reads the code and the GPD's pose relative to its pelvis
            out = self.ikd(torch.cat([code, (gpd - pelvis[:, None]).reshape(Bn, -1)], dim=-1))
        else:
            out = self.ikd(code)
            pelvis = out[:, 6 * nb:]
        J = self.skeleton.n_joints
        rot6 = out[:, :6 * nb].reshape(Bn, nb, 6)
        local = torch.eye(3, dtype=code.dtype).expand(Bn, J, 3, 3).clone()
        local[:, self.body] = sixd_to_matrix(rot6)
        pelvis = pelvis + c
        root = pelvis - self.pelvis_offset if self.helper_root >= 0 else pelvis
        gpos, grot = fk(self.skeleton, local, root)
        gpd_full = None
        if gpd is not None:
            gpd_full = gpos.new_zeros(Bn, J, 3)
            gpd_full[:, self.body] = gpd + c[:, None]
            if self.helper_root >= 0:
                gpd_full[:, self.helper_root] = pelvis - self.pelvis_offset
        return {"gpd_pos": gpd_full, "local_rot": local, "root_pos": root, "global_pos": gpos, "global_rot": grot}

    # ---------------------------------------------------------------------------------- files
    def save(self, path, *, command: str = "", seed: int | None = None, data: str = "", licence: str = "",
             extra: dict | None = None, half: bool = True):
        """One checkpoint (kind ``"protores"``): weights (float16 by default), config, skeleton, provenance."""
        return save_checkpoint(path, self.state_dict(), kind=KIND, config=self.config.to_dict(),
                               skeleton=self.skeleton, command=command, seed=seed, data=data, licence=licence,
                               extra=extra or {}, half=half)

    @classmethod
    def load(cls, path, skeleton=None) -> "PosingNet":
        """Read :meth:`save`'s file; with ``skeleton`` it must be the one the weights were made for, else a
        ``ValueError`` names the difference."""
        ck = load_checkpoint(path, kind=KIND, skeleton=skeleton)
        net = cls(ck["skeleton"], ProtoResConfig(**ck["config"]))
        try:
            net.load_state_dict({k: v.float() for k, v in ck["state"].items()})
        except RuntimeError as err:
            raise ValueError(f"checkpoint {path}: weights do not match its config ({err})") from None
        net.eval()
        net.checkpoint = {k: ck[k] for k in ("command", "seed", "data", "licence", "extra")}
        return net
