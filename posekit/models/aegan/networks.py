"""Victor & Meyer, JFIG 2020, Sec. 3.2: an AE-GAN latent space of poses, top to bottom.

Introduced in ``notebooks/04_aegan_latent_space.ipynb``. Poses are lesson 03's z-scored root-frame
vectors ``x`` (:mod:`posekit.data.pose_vectors`, ``3 B`` numbers for ``B`` body joints); the code ``z``
has ``d = 32`` numbers in ``[-1, 1]`` (the encoder ends in tanh; the prior is uniform on that cube).

* **Encoder** ``E: x -> z`` — an SPL (:class:`~posekit.models.aegan.spl.StructuredPrediction`, 12 numbers
  per joint: 252 units on 21 joints, the paper's size) and a dense layer to ``d`` with tanh.
* **Generator** ``G: z -> x`` — a dense layer of ``12 B`` ReLU units (252) and an SPL to 3 numbers per joint.
* **Pose discriminator** ``D_x: x -> [0, 1]`` — the encoder's shape, its last layer one sigmoid unit.
* **Latent discriminator** ``D_z: z -> [0, 1]`` — 4 x 256 LeakyReLU and a sigmoid unit.

The SPLs follow the skeleton's body-joint tree (each joint reads its parent's prediction).
:class:`AEGAN` holds the four networks with the normalisation and the skeleton, saves them as one
:mod:`posekit.learn.checkpoint` (kind ``"aegan"``), and gives the generator in numpy with its
gradient (:class:`NumpyAEGAN`) for latent optimisation.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import torch
from torch import nn

from ...records import NormStats
from ...learn import load_checkpoint, save_checkpoint
from .spl import StructuredPrediction, dense_twin

__all__ = ["KIND", "WEIGHTS", "weights_path", "AEGANConfig", "body_parents", "Encoder", "Generator", "PoseDiscriminator", "LatentDiscriminator",
           "AEGAN", "NumpyAEGAN", "sample_prior"]

# the checkpoint kind, the shipped file and the body tree: defined with the torch-free numpy networks
from .numpy_nets import KIND, WEIGHTS, NumpyAEGAN, body_parents, weights_path  # noqa: E402,F401


@dataclass
class AEGANConfig:
    """Sizes of the networks (the paper's by default, scaled per joint).

    Attributes
    ----------
    n_joints : int
        Body joints B (the features are 3 B).
    latent : int
        d (32).
    per_joint : int
        SPL outputs per joint in the encoder and the pose discriminator, and the generator's dense width
        per joint (12: 252 units on 21 joints).
    spl_hidden : int
        Hidden units of each joint's MLP in an SPL.
    ancestors : {"parent", "all"}
        What each SPL joint reads (the sparse variant by default).
    dz_hidden, dz_layers : int
        The latent discriminator (4 x 256).
    structured : bool
        SPL layers (True) or their dense twins of equal width (:func:`~posekit.models.aegan.spl.dense_twin`).
    """

    n_joints: int
    latent: int = 32
    per_joint: int = 12
    spl_hidden: int = 16
    ancestors: str = "parent"
    dz_hidden: int = 256
    dz_layers: int = 4
    structured: bool = True

    @property
    def n_features(self) -> int:
        return 3 * self.n_joints

    def to_dict(self) -> dict:
        return dict(self.__dict__)


def _spl(cfg: AEGANConfig, parents, n_in: int, out: int):
    if cfg.structured:
        return StructuredPrediction(n_in, parents, out, cfg.spl_hidden, cfg.ancestors)
    return dense_twin(n_in, cfg.n_joints, out, cfg.spl_hidden)


class Encoder(nn.Module):
    """``E(x) = tanh(W spl(x) + b)``: (N, 3 B) -> (N, d) in [-1, 1]."""

    def __init__(self, cfg: AEGANConfig, parents, out: int | None = None, squash=torch.tanh):
        super().__init__()
        self.spl = _spl(cfg, parents, cfg.n_features, cfg.per_joint)
        self.fc = nn.Linear(cfg.n_joints * cfg.per_joint, cfg.latent if out is None else out)
        self.squash = squash

    def forward(self, x):
        return self.squash(self.fc(torch.relu(self.spl(x))))


class Generator(nn.Module):
    """``G(z) = spl(relu(W z + b))``: (N, d) -> (N, 3 B), z-scored pose features."""

    def __init__(self, cfg: AEGANConfig, parents):
        super().__init__()
        self.fc = nn.Linear(cfg.latent, cfg.n_joints * cfg.per_joint)
        self.spl = _spl(cfg, parents, cfg.n_joints * cfg.per_joint, 3)

    def forward(self, z):
        return self.spl(torch.relu(self.fc(z)))


class PoseDiscriminator(Encoder):
    """``D_x(x)``: the encoder's shape with one sigmoid output, (N, 3 B) -> (N, 1). Returns the logit
    from :meth:`logit`; ``forward`` is the probability."""

    def __init__(self, cfg: AEGANConfig, parents):
        super().__init__(cfg, parents, out=1, squash=torch.sigmoid)

    def logit(self, x):
        return self.fc(torch.relu(self.spl(x)))


class LatentDiscriminator(nn.Module):
    """``D_z(z)``: ``dz_layers`` x ``dz_hidden`` LeakyReLU(0.2) and a sigmoid unit, (N, d) -> (N, 1)."""

    def __init__(self, cfg: AEGANConfig):
        super().__init__()
        sizes = [cfg.latent] + [cfg.dz_hidden] * cfg.dz_layers
        mods = []
        for a, b in zip(sizes[:-1], sizes[1:]):
            mods += [nn.Linear(a, b), nn.LeakyReLU(0.2)]
        mods.append(nn.Linear(sizes[-1], 1))
        self.net = nn.Sequential(*mods)

    def logit(self, z):
        return self.net(z)

    def forward(self, z):
        return torch.sigmoid(self.net(z))


def sample_prior(n: int, latent: int, generator: torch.Generator | None = None):
    """``n`` codes from the prior: uniform on ``[-1, 1]^d`` (the tanh range of the encoder), (n, d)."""
    return torch.rand(n, latent, generator=generator) * 2 - 1


@dataclass
class AEGAN:
    """The four networks of Sec. 3.2 and what they were trained for.

    Attributes
    ----------
    skeleton : Skeleton
    config : AEGANConfig
    norm : NormStats
        z-score of the pose vectors.
    encoder, generator : Encoder, Generator
    pose_disc, latent_disc : PoseDiscriminator, LatentDiscriminator
    x_range : ndarray, shape (2, 3 B)
        Lowest and highest z-scored feature of the training poses (targets beyond are flagged).
    info : dict
        Provenance of the checkpoint it was loaded from.
    """

    skeleton: object
    config: AEGANConfig
    norm: NormStats
    encoder: Encoder
    generator: Generator
    pose_disc: PoseDiscriminator
    latent_disc: LatentDiscriminator
    x_range: np.ndarray | None = None
    info: dict = field(default_factory=dict)

    NETS = ("encoder", "generator", "pose_disc", "latent_disc")

    @classmethod
    def new(cls, skeleton, norm: NormStats, config: AEGANConfig | None = None, seed: int = 0) -> "AEGAN":
        """Untrained networks (seeded initial weights) for ``skeleton``'s body joints."""
        parents = body_parents(skeleton)
        cfg = config or AEGANConfig(len(parents))
        if cfg.n_joints != len(parents):
            raise ValueError(f"AEGANConfig.n_joints = {cfg.n_joints}, but {skeleton.name or 'the skeleton'} has "
                             f"{len(parents)} body joints")
        torch.manual_seed(seed)
        return cls(skeleton, cfg, norm, Encoder(cfg, parents), Generator(cfg, parents),
                   PoseDiscriminator(cfg, parents), LatentDiscriminator(cfg))

    def nets(self) -> dict:
        return {k: getattr(self, k) for k in self.NETS}

    def n_parameters(self, name: str) -> int:
        return sum(p.numel() for p in getattr(self, name).parameters())

    def encode(self, x):
        """z-scored poses (N, 3 B) -> codes (N, d), numpy in and out, no gradients."""
        with torch.no_grad():
            return self.encoder(torch.as_tensor(np.asarray(x, np.float32))).numpy()

    def decode(self, z):
        """Codes (N, d) -> z-scored poses (N, 3 B), numpy in and out."""
        with torch.no_grad():
            return self.generator(torch.as_tensor(np.asarray(z, np.float32))).numpy()

    def compile(self) -> "NumpyAEGAN":
        """The encoder and generator in numpy, with the generator's gradient."""
        return NumpyAEGAN(self)

    def pose_score(self, x):
        """The pose discriminator's probability that z-scored poses (N, 3 B) are real, (N,)."""
        with torch.no_grad():
            return self.pose_disc(torch.as_tensor(np.asarray(x, np.float32)))[:, 0].numpy()

    # ------------------------------------------------------------------------------- checkpoints
    def save(self, path, *, command: str = "", seed: int | None = None, data: str = "", licence: str = "",
             extra: dict | None = None, half: bool = True):
        """One checkpoint (kind ``"aegan"``): the four networks (float16 by default), config, skeleton,
        normalisation ``"pose"``, training range, provenance."""
        state = {f"{k}.{n}": v for k, net in self.nets().items() for n, v in net.state_dict().items()}
        return save_checkpoint(path, state, kind=KIND, config=self.config.to_dict(), skeleton=self.skeleton,
                               norms={"pose": self.norm}, command=command, seed=seed, data=data, licence=licence,
                               extra={"x_range": self.x_range, **(extra or {})}, half=half)

    @classmethod
    def load(cls, path, skeleton=None) -> "AEGAN":
        """Read :meth:`save`'s file; with ``skeleton`` it must be the one the weights were made for,
        else a ``ValueError`` names the difference."""
        ck = load_checkpoint(path, kind=KIND, skeleton=skeleton)
        cfg = AEGANConfig(**ck["config"])
        if "pose" not in ck["norms"]:
            raise ValueError(f"checkpoint {path} has no pose normalisation")
        m = cls.new(ck["skeleton"], ck["norms"]["pose"], cfg)
        for k, net in m.nets().items():
            part = {n[len(k) + 1:]: v.float() for n, v in ck["state"].items() if n.startswith(k + ".")}
            try:
                net.load_state_dict(part)
            except RuntimeError as err:
                raise ValueError(f"checkpoint {path}: network {k!r} does not match its config ({err})") from None
            net.eval()
        m.x_range = ck["extra"].get("x_range")
        m.info = {k: ck[k] for k in ("command", "seed", "data", "licence", "path")} | {"extra": ck["extra"]}
        return m
