"""The documented, seeded command that makes the inverse-rig network weights shipped in
``data_samples/weights/`` (``posekit train invrig``); lesson 02 loads them.

For each supersampling method: draw ``samples`` control vectors like the training animation, run the
rig to get their joint positions, and train :func:`~posekit.invrig.nn.train_inverse_net`.
"""

from __future__ import annotations

from ..learn.trainers import print_written, register_trainer
from ..plugins import arg
from .nn import save_inverse_net, train_inverse_net, weights_path
from .sampling import METHODS, sample_controls

__all__ = ["LICENCE", "command", "train_all"]

LICENCE = ("MIT: made from the DeepMimic humanoid sample's skeleton (the DeepMimic code and data repository, MIT "
           "licence; as redistributed in the pybullet wheel, zlib licence), posed by posekit's seeded rig animation. "
           "Cite Peng et al. 2018.")


def command(method: str, samples: int, epochs: int, seed: int) -> str:
    """The command line that makes the weights of ``method`` (recorded in the checkpoint)."""
    return f"posekit train invrig --methods {method} --samples {samples} --epochs {epochs} --seed {seed}"


def train_all(methods=METHODS, samples: int = 20_000, epochs: int = 20, seed: int = 0, out=None, progress=True):
    """Train and save one network per sampling method; returns {method: path}.

    Each file is a :mod:`posekit.learn.checkpoint` recording the skeleton, the normalisation, the
    config, the command, the seed, the data provenance and the licence (:data:`LICENCE`).
    """
    from ..data import load_sample
    from .animator import standard_sets
    from .humanoid import HumanoidRig

    rig = HumanoidRig(load_sample().skeleton)
    train, _, _ = standard_sets(rig, seed=0)
    paths = {}
    for m in methods:
        Ys = sample_controls(m, train, samples, rig.low, rig.high, seed=seed)
        Xs = rig.evaluate(Ys)
        net, losses = train_inverse_net(Xs, Ys, epochs=epochs, seed=seed, progress=progress,
                                        control_names=rig.names, skeleton=rig.skeleton)
        data = (f"DeepMimic humanoid sample (data_samples/deepmimic_humanoid.npz), rig HumanoidRig, sampling {m}: "
                f"{samples} control vectors drawn (seed {seed}) like the training animation of "
                f"posekit.invrig.standard_sets(rig, seed=0), joint positions from rig.evaluate")
        paths[m] = save_inverse_net(net, weights_path(m, out), command=command(m, samples, epochs, seed), seed=seed,
                                    data=data, licence=LICENCE, method=m, samples=samples, final_loss=losses[-1],
                                    train_loss=losses)
    return paths


def _cli(args) -> int:
    """``posekit train invrig``."""

    paths = train_all(methods=args.methods.split(","), samples=args.samples, epochs=args.epochs, seed=args.seed,
                      out=args.out, progress=True)
    for m, p in paths.items():
        print_written(p)
    return 0


register_trainer(
    "invrig", _cli, help="inverse-rig networks, one per supersampling method (lesson 02)",
    makes="data_samples/weights/invrig_nn_{uniform,gaussian,mvn,gmm,pca}.pt",
    what="inverse-rig networks, one per supersampling method (Holden et al. 2017)",
    used_by="lesson 02 (02_inverse_rig_mapping.ipynb) and posekit bench invrig",
    takes="about 40 s on 2 idle cores (8 s per method)", out="/",
    args=[arg("--methods", default="uniform,gaussian,mvn,gmm,pca",
              help="comma-separated supersampling methods (default: uniform,gaussian,mvn,gmm,pca)"),
          arg("--samples", type=int, default=20_000, help="training samples per method (default: 20000)"),
          arg("--epochs", type=int, default=20, help="(default: 20)"),
          arg("--seed", type=int, default=0, help="(default: 0)"),
          arg("--out", default=None, help="folder (default data_samples/weights)")])
