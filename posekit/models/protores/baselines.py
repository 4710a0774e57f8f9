"""The two baselines of ProtoRes's Table 1 (Oreshkin et al. 2022, Sec. 4): other encoders, the same decoders.

Introduced in ``notebooks/05_protores.ipynb``. Each maps the same effector inputs as
:class:`~posekit.models.protores.networks.ProtoResEncoder` to a pose code; :class:`~posekit.models.protores.networks.PosingNet`
puts the shared GPD, IKD and FK after it, so the comparison isolates the encoder.

* **Masked-FCR** (:class:`MaskedFCREncoder`) — a fixed-size input: three tables (position, rotation,
  look-at) of one 7-number slot per body joint (6 values + tolerance), a learned placeholder in every
  slot that has no effector, flattened (3 x B x 7) into a fully connected residual network
  (:class:`~posekit.models.protores.blocks.FCR`). It must learn every combination of present and missing
  slots separately; that is what the prototype avoids.
* **Transformer** (:class:`TransformerEncoder`) — torch's own ``nn.Transformer``: the effector tokens
  (values, tolerance, joint and type embeddings, projected to ``d_model``) are the source sequence, one
  query per body joint (its joint embedding, projected) the target sequence, no positional encoding
  (a set has no order). The B output tokens, flattened, are projected to the code width. The paper's
  sizes: ``d_model`` 128, 8 heads, 2 encoder + 2 decoder layers; feed-forward width 4 ``d_model`` here
  (the authors' code: 1024), dropout off.
"""

from __future__ import annotations

import torch
from torch import nn

from .blocks import FCR, KIND_IDS, ProtoResConfig

__all__ = ["MaskedFCREncoder", "TransformerEncoder"]


class MaskedFCREncoder(nn.Module):
    """Masked-FCR: effectors scattered into a (3, B, 7) table with learned placeholders -> FCR -> code.

    ``forward(joint, kind, value, tol)`` with the shapes of :meth:`PosingNet.forward
    <posekit.models.protores.networks.PosingNet.forward>` (values re-referenced); returns (B, width).
    """

    def __init__(self, cfg: ProtoResConfig):
        super().__init__()
        self.n_joints = cfg.n_joints
        self.placeholder = nn.Parameter(torch.rand(len(KIND_IDS), cfg.n_joints, 7))
        self.fcr = FCR(len(KIND_IDS) * cfg.n_joints * 7, cfg.width, cfg.width, cfg.blocks, cfg.layers)
        self.out_features = cfg.width

    def forward(self, joint, kind, value, tol):
        Bn = joint.shape[0]
        table = self.placeholder.expand(Bn, -1, -1, -1).clone()
        batch = torch.arange(Bn)[:, None].expand_as(joint)
        table[batch, kind, joint] = torch.cat([value, tol[..., None]], dim=-1)
        return self.fcr(table.reshape(Bn, -1))


class TransformerEncoder(nn.Module):
    """The Transformer baseline: effector tokens -> ``nn.Transformer`` with one query per body joint -> code.

    ``forward(tokens)`` with tokens (B, N, 7 + 2 embed) from :class:`~posekit.models.protores.blocks.Tokens`;
    returns (B, width).
    """

    def __init__(self, cfg: ProtoResConfig):
        super().__init__()
        d = cfg.d_model
        self.src = nn.Linear(cfg.n_in, d)
        self.query = nn.Embedding(cfg.n_joints, d)
        self.transformer = nn.Transformer(d_model=d, nhead=cfg.heads, num_encoder_layers=cfg.enc_layers,
                                          num_decoder_layers=cfg.dec_layers, dim_feedforward=4 * d, dropout=0.0,
                                          batch_first=True)
        self.proj = nn.Linear(cfg.n_joints * d, cfg.width)
        self.out_features = cfg.width

    def forward(self, tokens):
        Bn = tokens.shape[0]
        q = self.query.weight.expand(Bn, -1, -1)
        y = self.transformer(self.src(tokens), q)
        return self.proj(y.reshape(Bn, -1))
