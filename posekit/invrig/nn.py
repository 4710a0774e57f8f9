"""The neural inverse rig mapping of Holden, Saito & Komura 2017 (Sec. 6): one hidden layer of 2048
ReLU units, trained on supersampled (joint positions, controls) pairs with an L1 sparsity term.

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb``. Loss per batch::

    L = mean ||y_hat - y||^2 + l1 * mean |h|

on z-scored inputs and outputs (``h``: the hidden activations). Training is :func:`posekit.learn.fit`;
weights are a :mod:`posekit.learn.checkpoint` (kind ``"invrig_nn"``) carrying the config, the rig's
control names, the skeleton (joint names, parents, offsets), the normalisation and the provenance,
and loading checks them.
"""

from __future__ import annotations

import numpy as np
import torch

from .. import paths
from ..records import NormStats
from ..learn import fit, load_checkpoint, save_checkpoint

__all__ = ["KIND", "WEIGHTS", "weights_path", "InverseRigNet", "train_inverse_net", "save_inverse_net", "load_inverse_net"]

KIND = "invrig_nn"

WEIGHTS = "invrig_nn_{method}.pt"
"""File name of the shipped weights of one supersampling method, in ``data_samples/weights/``."""


def weights_path(method: str, folder=None):
    """``folder/invrig_nn_{method}.pt`` (default the shipped weights' folder, :func:`posekit.paths.weights_path`)."""
    return paths.weights_path(WEIGHTS.format(method=method), folder)


class InverseRigNet:
    """x (N, D) -> y (N, C) with a 2048-unit ReLU layer; wraps the torch module and the normalisation.

    Parameters
    ----------
    n_in : int
        3 x joints (D: joint positions in metres, flattened).
    n_out : int
        Rig controls (C).
    hidden : int
    x_norm, y_norm : NormStats
        z-scores of the inputs and the outputs.
    control_names, joint_names : sequence of str
    skeleton : Skeleton, optional
        The skeleton the inputs come from; saved with the weights and checked when loading.
    """

    def __init__(self, n_in: int, n_out: int, hidden: int = 2048, x_norm=None, y_norm=None,
                 control_names=(), joint_names=(), skeleton=None):
        self.net = torch.nn.Sequential(torch.nn.Linear(n_in, hidden), torch.nn.ReLU(), torch.nn.Linear(hidden, n_out))
        self.x_norm, self.y_norm = x_norm, y_norm
        self.control_names, self.joint_names = tuple(control_names), tuple(joint_names)
        self.hidden = hidden
        self.skeleton = skeleton
        self.curves = None  # posekit.learn.Curves after training
        self.meta = {}  # provenance after loading: command, seed, data, licence, extra

    @property
    def config(self) -> dict:
        """The arguments that rebuild this network (stored in its checkpoint)."""
        return {"n_in": self.net[0].in_features, "n_out": self.net[2].out_features, "hidden": self.hidden,
                "controls": list(self.control_names)}

    def predict(self, X) -> np.ndarray:
        """Controls (N, C) for joint positions X (N, D) (or (N, J, 3)), metres."""
        X = np.asarray(X, dtype=float).reshape(len(X), -1)
        if X.shape[1] != self.net[0].in_features:
            raise ValueError(f"expected {self.net[0].in_features} inputs per pose "
                             f"({len(self.joint_names)} joints x 3), got {X.shape[1]}")
        if not np.all(np.isfinite(X)):
            raise ValueError("joint positions contain NaN or inf")
        with torch.no_grad():
            z = self.net(torch.as_tensor(self.x_norm.normalize(X), dtype=torch.float32)).numpy()
        return self.y_norm.denormalize(z)


class _WithHidden(torch.nn.Module):
    """The network's output and hidden activations in one call (one forward per backward, as
    ``DistributedDataParallel`` asks); the same parameters as the wrapped ``Sequential``."""

    def __init__(self, net):
        super().__init__()
        self.net = net

    def forward(self, x):
        h = self.net[1](self.net[0](x))
        return self.net[2](h), h


def _loss(l1: float):
    """Holden et al. 2017 Sec. 6: squared error plus an L1 penalty on the hidden activations."""

    def loss(net, x, y):
        out, h = net(x)
        return torch.mean((out - y) ** 2) + l1 * h.abs().mean()

    return loss


def train_inverse_net(X, Y, epochs: int = 20, batch: int = 256, lr: float = 1e-3, l1: float = 1e-4,
                      hidden: int = 2048, seed: int = 0, progress: bool = True, control_names=(), joint_names=(),
                      skeleton=None):
    """Train an :class:`InverseRigNet` (Adam through :func:`posekit.learn.fit`, seeded).

    Parameters
    ----------
    X : ndarray, shape (N, D) or (N, J, 3), metres
        Joint positions.
    Y : ndarray, shape (N, C)
        Rig controls.
    skeleton : Skeleton, optional
        Kept on the model so that :func:`save_inverse_net` records it; ``joint_names`` default to
        its names.

    Returns
    -------
    model : InverseRigNet
        ``model.curves`` holds the :class:`~posekit.learn.Curves`.
    losses : list of float
        Mean training loss per epoch.
    """
    torch.manual_seed(seed)  # the initial weights
    X = np.asarray(X, dtype=float).reshape(len(X), -1)
    Y = np.asarray(Y, dtype=float)
    if skeleton is not None and not joint_names:
        joint_names = skeleton.names
    xn, yn = NormStats.fit(X), NormStats.fit(Y)
    model = InverseRigNet(X.shape[1], Y.shape[1], hidden, xn, yn, control_names, joint_names, skeleton)
    Xt = torch.as_tensor(xn.normalize(X), dtype=torch.float32)
    Yt = torch.as_tensor(yn.normalize(Y), dtype=torch.float32)
    model.curves = fit(_WithHidden(model.net), _loss(l1), (Xt, Yt), epochs=epochs, batch=batch, lr=lr, seed=seed,
                       progress=progress)
    model.net.cpu()  # trained on the run's device (posekit train --device); predicted on the CPU
    model.train_config = {"l1": l1, "epochs": epochs, "batch": batch, "lr": lr, "optimizer": "adam"}
    return model, list(model.curves.train)


def save_inverse_net(model: InverseRigNet, path, *, skeleton=None, command: str = "", seed: int | None = None,
                     data: str = "", licence: str = "", **extra):
    """Save the weights (float16 to keep the file small) as a posekit checkpoint.

    The checkpoint carries the config (``n_in``, ``n_out``, ``hidden``, ``controls`` and the training
    settings ``l1``, ``epochs``, ``batch``, ``lr``), the skeleton, the normalisations ``x`` and
    ``y``, ``command``, ``seed``, ``data`` (provenance), ``licence`` and ``extra``.

    Parameters
    ----------
    skeleton : Skeleton, optional
        Default ``model.skeleton``; one of the two is needed, and its names must be the model's.
    """
    skeleton = skeleton if skeleton is not None else model.skeleton
    if skeleton is None:
        raise ValueError("save_inverse_net needs the skeleton the network was trained for: pass skeleton=... "
                         "(or train with train_inverse_net(..., skeleton=...))")
    if model.joint_names and tuple(skeleton.names) != model.joint_names:
        raise ValueError(f"save_inverse_net: the network was trained for skeleton joints {list(model.joint_names)}, "
                         f"not the given skeleton's {list(skeleton.names)}")
    config = {**model.config, **getattr(model, "train_config", {})}
    return save_checkpoint(path, model.net, kind=KIND, config=config, skeleton=skeleton,
                           norms={"x": model.x_norm, "y": model.y_norm}, command=command, seed=seed, data=data,
                           licence=licence, extra=extra, half=True)


def load_inverse_net(path, control_names, joints) -> InverseRigNet:
    """Load weights saved by :func:`save_inverse_net`, checking they were made for this rig and skeleton.

    Parameters
    ----------
    control_names : sequence of str
        The rig's controls, in order.
    joints : Skeleton or sequence of str
        A skeleton is checked in full (joint names, parents, offsets); names only by name.

    Raises
    ------
    ValueError
        When the controls or joints differ from the ones the weights were trained with (or the
        file is not an inverse-rig checkpoint).
    """
    from ..skeleton import Skeleton

    d = load_checkpoint(path, kind=KIND, skeleton=joints if isinstance(joints, Skeleton) else None)
    cfg, skel = d["config"], d["skeleton"]
    if list(control_names) != cfg["controls"]:
        raise ValueError(f"{path}: weights were trained for rig controls {cfg['controls'][:4]}... "
                         f"({len(cfg['controls'])}), not these ({len(control_names)})")
    names = list(joints.names) if isinstance(joints, Skeleton) else list(joints)
    if names != list(skel.names):
        raise ValueError(f"{path}: weights were trained for skeleton joints {list(skel.names)[:4]}... "
                         f"({skel.n_joints}), not these ({len(names)})")
    m = InverseRigNet(cfg["n_in"], cfg["n_out"], cfg["hidden"], d["norms"]["x"], d["norms"]["y"],
                      cfg["controls"], skel.names, skel)
    m.net.load_state_dict(d["state"])
    m.net.eval()
    m.meta = {k: d[k] for k in ("command", "seed", "data", "licence", "extra", "config")}
    return m
