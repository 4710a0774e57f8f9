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

:class:`NumpySPL` is the same layer in numpy float32 with a hand-written backward pass (the gradient of
the output with respect to the input), for latent optimisation without torch's per-call cost.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

__all__ = ["tree_levels", "StructuredPrediction", "NumpySPL", "dense_twin"]


def tree_levels(parents, ancestors: str = "parent"):
    """Joints grouped by depth, with the ancestors each one reads.

    Parameters
    ----------
    parents : sequence of int, length J
        Parent of each joint, -1 for a root (several roots are fine); any order.
    ancestors : {"parent", "all"}

    Returns
    -------
    levels : list of (joints (n,), ancestors (n, a)) int arrays
        Depth 0 first; ``a`` is 0 at the roots, then 1 (parent) or the depth (all, nearest first).
    """
    if ancestors not in ("parent", "all"):
        raise ValueError(f"ancestors must be 'parent' or 'all', got {ancestors!r}")
    parents = [int(p) for p in parents]
    n = len(parents)
    chains = []
    for j in range(n):
        chain, k = [], parents[j]
        while k >= 0:
            if k >= n or k == j or k in chain:
                raise ValueError(f"parents: joint {j} has no root above it (a cycle or an index out of range)")
            chain.append(k)
            k = parents[k]
        chains.append(chain)
    depth = [len(c) for c in chains]
    levels = []
    for d in range(max(depth) + 1):
        js = [j for j in range(n) if depth[j] == d]
        anc = [chains[j][: (1 if ancestors == "parent" else d)] for j in js]
        levels.append((np.array(js, dtype=np.int64), np.array(anc, dtype=np.int64).reshape(len(js), -1)))
    return levels


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


class NumpySPL:
    """:class:`StructuredPrediction` in numpy float32, forward and backward, on (N, in) batches.

    The layout inside is joint-major, ``(J, N, .)``, so each depth is one batched ``matmul``.
    """

    def __init__(self, layer: StructuredPrediction):
        f32 = lambda t: t.detach().cpu().numpy().astype(np.float32).copy()  # noqa: E731
        self.J, self.out, self.hidden = layer.n_joints, layer.out, layer.hidden
        self.U = f32(layer.shared.weight).T.copy()  # (in, J hidden): every joint's U_j side by side
        self.c = f32(layer.shared.bias)
        self.levels = []
        for (js, anc), A, V, b in zip(layer.levels, layer.anc, layer.w_out, layer.b_out):
            flat = anc.reshape(-1)
            uniq = np.unique(flat)
            # sums the gradients of (joint, ancestor) pairs into each distinct ancestor: (n_uniq, n * a)
            S = (uniq[:, None] == flat[None, :]).astype(np.float32)
            self.levels.append((js, anc, f32(A), f32(V), f32(b)[:, None, :], uniq, S))

    def forward(self, h):
        """``h`` (N, in) -> (N, J * out) and the cache :meth:`backward` needs."""
        h = np.asarray(h, dtype=np.float32)
        n = h.shape[0]
        a = (h @ self.U + self.c).reshape(n, self.J, self.hidden).transpose(1, 0, 2)  # (J, N, hidden)
        outs = np.zeros((self.J, n, self.out), np.float32)
        acts = []
        for js, anc, A, V, b, _, _ in self.levels:
            pre = a[js]
            p = None
            if anc.shape[1]:
                p = outs[anc].transpose(0, 2, 1, 3).reshape(len(js), n, -1)  # (n_l, N, a * out)
                pre = pre + np.matmul(p, A)
            r = np.maximum(pre, 0.0)
            outs[js] = np.matmul(r, V) + b
            acts.append((r, p))
        return outs.transpose(1, 0, 2).reshape(n, -1), (h, acts)

    def backward(self, cache, grad_out):
        """The gradient with respect to the input, (N, in), of a loss whose gradient with respect to
        the output is ``grad_out`` (N, J * out)."""
        h, acts = cache
        n = h.shape[0]
        g_out = np.asarray(grad_out, np.float32).reshape(n, self.J, self.out).transpose(1, 0, 2).copy()
        g_a = np.zeros((self.J, n, self.hidden), np.float32)
        for (js, anc, A, V, _, uniq, S), (r, p) in zip(reversed(self.levels), reversed(acts)):
            g_pre = np.matmul(g_out[js], V.transpose(0, 2, 1)) * (r > 0)  # (n_l, N, hidden)
            g_a[js] = g_pre
            if anc.shape[1]:  # into the ancestors' outputs (deeper levels are done: their sums are complete)
                g_p = np.matmul(g_pre, A.transpose(0, 2, 1)).reshape(len(js), n, anc.shape[1], self.out)
                g_p = g_p.transpose(0, 2, 1, 3).reshape(len(js) * anc.shape[1], n * self.out)
                g_out[uniq] += (S @ g_p).reshape(len(uniq), n, self.out)
        return g_a.transpose(1, 0, 2).reshape(n, -1) @ self.U.T
