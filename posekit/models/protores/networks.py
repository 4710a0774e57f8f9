"""ProtoRes (Oreshkin et al. 2022, Sec. 2): a full pose from a variable set of effectors, top to bottom.

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

The two baselines of the paper's Table 1 (:mod:`posekit.models.protores.baselines`: Masked-FCR and a
Transformer) swap the encoder and keep the decoders and FK; :class:`PosingNet` holds any of the three.
The inputs, the fully connected blocks and the config they share are in :mod:`posekit.models.protores.blocks`
(and importable from here).
A :class:`PosingNet` saves to one :mod:`posekit.learn.checkpoint` (kind ``"protores"``).
"""

from __future__ import annotations


import numpy as np
import torch
from torch import nn

from ...data.metrics import body_joints
from ...kinematics import fk
from ...learn import load_checkpoint, save_checkpoint
from ...rotations import sixd_to_matrix
from .baselines import MaskedFCREncoder, TransformerEncoder
from .blocks import (ARCHS, ETA, KIND_IDS, SIGMA_M, FCBlock, FCR, ProtoResConfig, Tokens, centroid, effector_inputs,
                     sigma_to_tolerance, tolerance_to_sigma)

__all__ = ["KIND", "WEIGHTS", "weights_path", "ARCHS", "KIND_IDS", "SIGMA_M", "ETA", "ProtoResConfig", "centroid", "effector_inputs",
           "Tokens", "FCBlock", "FCR", "ProtoResEncoder", "PosingNet", "tolerance_to_sigma", "sigma_to_tolerance"]

# the checkpoint kind and the shipped files: defined with the torch-free numpy pass, which reads them too
from .fast import KIND, WEIGHTS, weights_path  # noqa: E402


# ------------------------------------------------------------------------------------------ Eq. 2
class ProtoResEncoder(nn.Module):
    """Eq. 2 of Oreshkin et al. 2022: the proto-residual encoder, tokens (B, N, n_in) -> code (B, width).

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
        # skeleton data, not a weight: rebuilt from the skeleton, never stored (float16 would round it)
        self.register_buffer("pelvis_offset", torch.tensor(np.asarray(skeleton.offsets[pel], dtype=np.float32)),
                             persistent=False)

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
            skeleton's joint count (helper root included), world frame; ``centroid`` (B, 3) the effectors'
            centroid the inputs were re-referenced to.
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
        local = torch.eye(3, dtype=code.dtype, device=code.device).expand(Bn, J, 3, 3).clone()
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
        return {"gpd_pos": gpd_full, "local_rot": local, "root_pos": root, "global_pos": gpos, "global_rot": grot,
                "centroid": c}

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
            net.load_state_dict({k: v.float() for k, v in ck["state"].items() if k != "pelvis_offset"})
        except RuntimeError as err:
            raise ValueError(f"checkpoint {path}: weights do not match its config ({err})") from None
        net.eval()
        net.checkpoint = {k: ck[k] for k in ("command", "seed", "data", "licence", "extra")}
        return net
