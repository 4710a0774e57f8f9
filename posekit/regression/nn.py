"""The neural inverse rig mapping of Holden, Saito & Komura 2017 (Sec. 6): one hidden layer of 2048
ReLU units, trained on supersampled (joint positions, controls) pairs with an L1 sparsity term.

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb``. Loss per batch::

    L = mean ||y_hat - y||^2 + l1 * mean |h|

on z-scored inputs and outputs (``h``: the hidden activations). Weights are saved with the rig's
control names, the skeleton's joint names and the normalisation, and loading checks all three.
"""

from __future__ import annotations

import numpy as np

from ..data.dataset import NormStats

__all__ = ["InverseRigNet", "train_inverse_net", "save_inverse_net", "load_inverse_net"]


def _torch():
    import torch

    return torch


class InverseRigNet:
    """x (N, D) -> y (N, C) with a 2048-unit ReLU layer; wraps the torch module and the normalisation."""

    def __init__(self, n_in: int, n_out: int, hidden: int = 2048, x_norm=None, y_norm=None,
                 control_names=(), joint_names=()):
        torch = _torch()
        self.net = torch.nn.Sequential(torch.nn.Linear(n_in, hidden), torch.nn.ReLU(), torch.nn.Linear(hidden, n_out))
        self.x_norm, self.y_norm = x_norm, y_norm
        self.control_names, self.joint_names = tuple(control_names), tuple(joint_names)
        self.hidden = hidden

    def predict(self, X) -> np.ndarray:
        """Controls for joint positions X (N, D) (or (N, J, 3))."""
        torch = _torch()
        X = np.asarray(X, dtype=float).reshape(len(X), -1)
        if X.shape[1] != self.net[0].in_features:
            raise ValueError(f"expected {self.net[0].in_features} inputs per pose "
                             f"({len(self.joint_names)} joints x 3), got {X.shape[1]}")
        if not np.all(np.isfinite(X)):
            raise ValueError("joint positions contain NaN or inf")
        with torch.no_grad():
            z = self.net(torch.as_tensor(self.x_norm.normalize(X), dtype=torch.float32)).numpy()
        return self.y_norm.denormalize(z)


def train_inverse_net(X, Y, epochs: int = 20, batch: int = 256, lr: float = 1e-3, l1: float = 1e-4,
                      hidden: int = 2048, seed: int = 0, progress: bool = True, control_names=(), joint_names=()):
    """Train an :class:`InverseRigNet` (Adam, seeded). X (N, D) joint positions, Y (N, C) controls.

    Returns
    -------
    model : InverseRigNet
    losses : list of float
        Mean training loss per epoch.
    """
    torch = _torch()
    torch.manual_seed(seed)
    X = np.asarray(X, dtype=float).reshape(len(X), -1)
    Y = np.asarray(Y, dtype=float)
    xn, yn = NormStats.fit(X), NormStats.fit(Y)
    model = InverseRigNet(X.shape[1], Y.shape[1], hidden, xn, yn, control_names, joint_names)
    opt = torch.optim.Adam(model.net.parameters(), lr=lr)
    Xt = torch.as_tensor(xn.normalize(X), dtype=torch.float32)
    Yt = torch.as_tensor(yn.normalize(Y), dtype=torch.float32)
    g = torch.Generator().manual_seed(seed)
    it = range(epochs)
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(it, desc="training", unit="epoch")
    losses = []
    for _ in it:
        perm = torch.randperm(len(Xt), generator=g)
        total = 0.0
        for k in range(0, len(Xt), batch):
            idx = perm[k:k + batch]
            h = model.net[1](model.net[0](Xt[idx]))
            loss = torch.mean((model.net[2](h) - Yt[idx]) ** 2) + l1 * h.abs().mean()
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += float(loss.detach()) * len(idx)
        losses.append(total / len(Xt))
    return model, losses


def save_inverse_net(model: InverseRigNet, path, **meta):
    """Save weights (float16 to keep the file small), normalisation and names; ``meta`` is kept too."""
    torch = _torch()
    state = {k: v.to(torch.float16) for k, v in model.net.state_dict().items()}
    torch.save({"state": state, "hidden": model.hidden, "x_mean": model.x_norm.mean, "x_std": model.x_norm.std,
                "y_mean": model.y_norm.mean, "y_std": model.y_norm.std, "controls": list(model.control_names),
                "joints": list(model.joint_names), "meta": meta}, path)


def load_inverse_net(path, control_names, joint_names) -> InverseRigNet:
    """Load weights saved by :func:`save_inverse_net`, checking they were made for this rig and skeleton.

    Raises
    ------
    ValueError
        When the controls or joints differ from the ones the weights were trained with.
    """
    torch = _torch()
    d = torch.load(path, map_location="cpu", weights_only=False)
    if list(control_names) != d["controls"]:
        raise ValueError(f"{path}: weights were trained for rig controls {d['controls'][:4]}... "
                         f"({len(d['controls'])}), not these ({len(control_names)})")
    if list(joint_names) != d["joints"]:
        raise ValueError(f"{path}: weights were trained for skeleton joints {d['joints'][:4]}... "
                         f"({len(d['joints'])}), not these ({len(joint_names)})")
    n_in, n_out = len(d["joints"]) * 3, len(d["controls"])
    m = InverseRigNet(n_in, n_out, d["hidden"], NormStats(d["x_mean"], d["x_std"]), NormStats(d["y_mean"], d["y_std"]),
                      d["controls"], d["joints"])
    m.net.load_state_dict({k: v.to(torch.float32) for k, v in d["state"].items()})
    m.meta = d.get("meta", {})
    return m
