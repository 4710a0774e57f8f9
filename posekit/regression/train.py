"""The documented, seeded command that makes the inverse-rig network weights shipped in
``data_samples/weights/`` (``posekit train invrig``); lesson 02 loads them.

For each supersampling method: draw ``samples`` control vectors like the training animation, run the
rig to get their joint positions, and train :func:`~posekit.regression.nn.train_inverse_net`.
"""

from __future__ import annotations

from pathlib import Path

from ..paths import samples_dir
from .nn import save_inverse_net, train_inverse_net
from .sampling import METHODS, sample_controls

__all__ = ["WEIGHTS", "weights_path", "train_all"]

WEIGHTS = "invrig_nn_{method}.pt"


def weights_path(method: str, folder=None) -> Path:
    return Path(folder or samples_dir() / "weights") / WEIGHTS.format(method=method)


def train_all(methods=METHODS, samples: int = 20_000, epochs: int = 20, seed: int = 0, out=None, progress=True):
    """Train and save one network per sampling method; returns {method: path}."""
    import torch

    from ..data import load_sample
    from ..rig import HumanoidRig, standard_sets

    torch.set_num_threads(max(1, torch.get_num_threads()))
    rig = HumanoidRig(load_sample().skeleton)
    train, _, _ = standard_sets(rig, seed=0)
    paths = {}
    for m in methods:
        Ys = sample_controls(m, train, samples, rig.low, rig.high, seed=seed)
        Xs = rig.evaluate(Ys)
        net, losses = train_inverse_net(Xs, Ys, epochs=epochs, seed=seed, progress=progress,
                                        control_names=rig.names, joint_names=rig.skeleton.names)
        path = weights_path(m, out)
        path.parent.mkdir(parents=True, exist_ok=True)
        save_inverse_net(net, path, method=m, samples=samples, epochs=epochs, seed=seed, final_loss=losses[-1])
        paths[m] = path
    return paths
