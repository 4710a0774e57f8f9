"""The structured prediction layer (SPL) of Aksan, Kaufmann & Hilliges 2019, in torch and in numpy.

Introduced in ``notebooks/04_aegan_latent_space.ipynb``. A dense layer predicts every joint from the
same input at once. An SPL predicts joint by joint, in kinematic-tree order, so each joint sees what was
predicted for the joints above it::

    o_j = V_j relu(U_j h + A_j [o_a for a in anc(j)] + c_j) + d_j          (Aksan et al. 2019, Eq. 4)

``h`` is the layer's input (shared by every joint), ``anc(j)`` the joint's parent (the sparse variant,
``ancestors="parent"``, the paper's choice) or all of its ancestors (``ancestors="all"``), ``o_j`` the
joint's ``out`` numbers. Every joint has its own small MLP of ``hidden`` units.

Implementation: the ``U_j h`` of every joint is one matrix product (they do not depend on each other);
then the joints are visited by *depth* in the tree (``levels``): all joints of one depth depend only on
shallower ones, so one batched product per depth does them together. A joint of depth ``d`` has
exactly ``d`` ancestors (1 parent), so every joint of a level has the same input width.

:class:`~posekit.models.aegan.numpy_nets.NumpySPL` is the same layer in numpy float32 with a hand-written backward pass (the gradient of
the output with respect to the input), for latent optimisation without torch's per-call cost.
"""

from __future__ import annotations

import torch
from torch import nn

from .numpy_nets import NumpySPL, tree_levels  # noqa: F401 - the numpy twin and the tree order, re-exported

__all__ = ["tree_levels", "StructuredPrediction", "NumpySPL", "dense_twin"]


class StructuredPrediction(nn.Module):
    """``(N, in_features) -> (N, J * out)``: one MLP per joint in tree order (module docstring).

    Parameters
    ----------
    in_features : int
    parents : sequence of int, length J
        The tree (-1 for a root).
    out : int
        Numbers predicted per joint (3 for a position, 12 in the AE-GAN's encoder).
    hidden : int
        Units of each joint's hidden layer.
    ancestors : {"parent", "all"}
    """

    def __init__(self, in_features: int, parents, out: int, hidden: int = 16, ancestors: str = "parent"):
        super().__init__()
        self.in_features, self.out, self.hidden, self.ancestors = int(in_features), int(out), int(hidden), ancestors
        self.parents = [int(p) for p in parents]
        self.n_joints = len(self.parents)
        self.levels = tree_levels(self.parents, ancestors)
        self.shared = nn.Linear(in_features, self.n_joints * hidden)  # U_j h + c_j of every joint at once
        self.anc = nn.ParameterList()
        self.w_out = nn.ParameterList()
        self.b_out = nn.ParameterList()
        for js, anc in self.levels:
            n, a = len(js), anc.shape[1]
            self.anc.append(nn.Parameter(torch.randn(n, a * out, hidden) * (1.0 / max(1, a * out)) ** 0.5))
            self.w_out.append(nn.Parameter(torch.randn(n, hidden, out) * (1.0 / hidden) ** 0.5))
            self.b_out.append(nn.Parameter(torch.zeros(n, out)))
        for i, (js, anc) in enumerate(self.levels):
            self.register_buffer(f"_js{i}", torch.as_tensor(js), persistent=False)  # index tensors, not weights
            self.register_buffer(f"_anc{i}", torch.as_tensor(anc.reshape(-1)), persistent=False)

    def forward(self, h):
        n = h.shape[0]
        a = self.shared(h).view(n, self.n_joints, self.hidden).transpose(0, 1)  # (J, N, hidden)
        outs = [None] * self.n_joints
        for i, (js, anc) in enumerate(self.levels):
            pre = a[getattr(self, f"_js{i}")]  # (n, N, hidden)
            if anc.shape[1]:  # the ancestors' outputs side by side, (n, N, a * out)
                p = torch.stack([torch.cat([outs[k] for k in row], dim=-1) for row in anc])
                pre = pre + torch.bmm(p, self.anc[i])
            o = torch.baddbmm(self.b_out[i].unsqueeze(1), torch.relu(pre), self.w_out[i])  # (n, N, out)
            for r, j in enumerate(js):
                outs[j] = o[r]
        return torch.cat(outs, dim=-1)


def dense_twin(in_features: int, n_joints: int, out: int, hidden: int = 16) -> nn.Sequential:
    """The dense layer an SPL replaces, of equal width: ``Linear(in, J hidden) -> ReLU -> Linear(J hidden, J out)``
    (every output sees every hidden unit; the lesson compares parameters and reconstruction error)."""
    width = n_joints * hidden
    return nn.Sequential(nn.Linear(in_features, width), nn.ReLU(), nn.Linear(width, n_joints * out))
