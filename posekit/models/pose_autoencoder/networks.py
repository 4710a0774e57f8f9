"""Victor et al. 2021, "Learning-based pose edition for efficient and interactive design": the networks, top to bottom.

Introduced in ``notebooks/03_autoencoder_solvers.ipynb``. Poses are z-scored root-frame vectors
``x`` (:mod:`posekit.data.pose_vectors`); every network works on those.

* **Autoencoder** (Sec. 3.3.1) — :class:`PoseAutoencoder`. Encoder ``E``: two 200-unit ReLU layers and
  a linear layer to the latent code ``z`` (d = 64). Decoder ``D``: the mirrored network. With
  ``tied=True`` it is what the authors' code does: the decoder reuses the *transposed* encoder weights
  and has no biases, ``D(z) = W1^T relu(W2^T relu(W3^T z))``; ``tied=False`` gives the decoder its
  own weights and biases. Trained on ``MSE(D(E(x)), x)``.
* **Solvers** (Sec. 3.3.2) — :class:`LatentSolver` ``S_t(z, p_t) -> z'``: the start pose's code and
  the targets ``p_t`` of the joint set ``t`` (z-scored like the pose features), three 126-unit ReLU
  layers and a d-unit linear output. (The authors' code defines a third hidden layer and never calls
  it; here all three are used.) Trained with the autoencoder frozen on Eq. (1)::

      L_s = MSE_t(D(z'), x_target) + k MSE_other(D(z'), x_target),   k = 0.01

  — the target set's joints must match, the other joints should look like the true target pose.
* **Chaining** (Sec. 3.5) — ``z' = S_t3(S_t2(S_t1(z, p_1), p_2), p_3)``: one solver per joint set,
  applied in turn (:meth:`AESolvers.latent`).

:class:`AESolvers` holds the autoencoder, the solvers, the normalisation and the skeleton, saves them
as one :mod:`posekit.learn.checkpoint` (kind ``"ae_solvers"``) and runs them in plain numpy for
single poses (:meth:`AESolvers.compile`), where torch's per-call overhead would dominate.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import torch
from torch import nn

from ...records import NormStats
from ...learn import load_checkpoint, save_checkpoint
from ...data.pose_vectors import feature_columns

__all__ = ["KIND", "WEIGHTS", "weights_path", "GROUPS", "CHAIN", "chain_groups", "stages", "AEConfig", "PoseAutoencoder",
           "LatentSolver", "AESolvers", "NumpyAESolvers"]

# the checkpoint kind, the shipped file and the solver groups: defined with the torch-free numpy networks
from .numpy_nets import CHAIN, GROUPS, KIND, WEIGHTS, NumpyAESolvers, chain_groups, stages, weights_path  # noqa: E402,F401


@dataclass
class AEConfig:
    """Sizes of the networks (the paper's by default).

    Attributes
    ----------
    n_features : int
        3 x body joints.
    hidden : int
        Width of the autoencoder's two hidden layers (200).
    latent : int
        d, the size of the latent code (64).
    tied : bool
        Decoder = transposed encoder weights, no biases (the authors' code).
    solver_hidden, solver_layers : int
        Each solver's ReLU layers: 3 x 126.
    """

    n_features: int
    hidden: int = 200
    latent: int = 64
    tied: bool = True
    solver_hidden: int = 126
    solver_layers: int = 3

    def to_dict(self) -> dict:
        return dict(self.__dict__)


class PoseAutoencoder(nn.Module):
    """``E: x (N, F) -> z (N, d)`` and ``D: z -> x`` (Sec. 3.3.1; tied or untied decoder)."""

    def __init__(self, n_features: int, hidden: int = 200, latent: int = 64, tied: bool = True):
        super().__init__()
        self.tied = bool(tied)
        self.enc1, self.enc2 = nn.Linear(n_features, hidden), nn.Linear(hidden, hidden)
        self.enc3 = nn.Linear(hidden, latent)
        if not self.tied:
            self.dec1, self.dec2 = nn.Linear(latent, hidden), nn.Linear(hidden, hidden)
            self.dec3 = nn.Linear(hidden, n_features)

    def encode(self, x):
        """z = W3 relu(W2 relu(W1 x + b1) + b2) + b3."""
        return self.enc3(torch.relu(self.enc2(torch.relu(self.enc1(x)))))

    def decode(self, z):
        """Tied: x = W1^T relu(W2^T relu(W3^T z)), no biases (the authors' code); untied: the mirrored MLP."""
        if self.tied:
            h = torch.relu(z @ self.enc3.weight)
            h = torch.relu(h @ self.enc2.weight)
            return h @ self.enc1.weight
        return self.dec3(torch.relu(self.dec2(torch.relu(self.dec1(z)))))

    def forward(self, x):
        return self.decode(self.encode(x))


class LatentSolver(nn.Module):
    """``S_t(z (N, d), p (N, 3K)) -> z' (N, d)``: ``layers`` ReLU layers of ``hidden`` units, then linear."""

    def __init__(self, latent: int, n_targets: int, hidden: int = 126, layers: int = 3):
        super().__init__()
        sizes = [latent + 3 * n_targets] + [hidden] * layers
        mods = []
        for a, b in zip(sizes[:-1], sizes[1:]):
            mods += [nn.Linear(a, b), nn.ReLU()]
        mods.append(nn.Linear(sizes[-1], latent))
        self.net = nn.Sequential(*mods)

    def forward(self, z, p):
        return self.net(torch.cat([z, p], dim=-1))


@dataclass
class AESolvers:
    """An autoencoder, its solvers and what they were trained for.

    Attributes
    ----------
    skeleton : Skeleton
    config : AEConfig
    norm : NormStats
        z-score of the pose vectors.
    ae : PoseAutoencoder
    solvers : dict of str -> LatentSolver
        One per :data:`GROUPS` name trained.
    chained : dict of str -> LatentSolver
        Chaining-aware copies (fine-tuned on the codes the earlier solvers of :data:`CHAIN` produce).
    x_range : ndarray, shape (2, F)
        Lowest and highest z-scored feature of the training poses: targets outside are clamped to it
        and flagged.
    info : dict
        Provenance of the checkpoint it was loaded from (command, seed, data, licence, ...).
    """

    skeleton: object
    config: AEConfig
    norm: NormStats
    ae: PoseAutoencoder
    solvers: dict = field(default_factory=dict)
    chained: dict = field(default_factory=dict)
    x_range: np.ndarray | None = None
    info: dict = field(default_factory=dict)

    @classmethod
    def new(cls, skeleton, norm: NormStats, config: AEConfig, seed: int = 0) -> "AESolvers":
        """An untrained autoencoder (seeded initial weights) and no solvers yet."""
        torch.manual_seed(seed)
        ae = PoseAutoencoder(config.n_features, config.hidden, config.latent, config.tied)
        return cls(skeleton, config, norm, ae)

    def new_solver(self, group: str, seed: int = 0) -> LatentSolver:
        """An untrained solver for a :data:`GROUPS` entry (seeded initial weights)."""
        torch.manual_seed(seed)
        c = self.config
        return LatentSolver(c.latent, len(GROUPS[group]), c.solver_hidden, c.solver_layers)

    def columns(self, group: str) -> np.ndarray:
        """Feature columns of a group's joints, shape (3K,)."""
        return feature_columns(self.skeleton, GROUPS[group])

    def latent(self, z, targets: dict, chain=None, chain_aware: bool = True):
        """Move codes ``z`` (N, d) to meet ``targets`` ({group: (N, 3K) z-scored}) in torch.

        One group: ``S_t(z, p_t)``. Several, or ``chain``: the chain of Sec. 3.5 in :data:`CHAIN` order,
        with the chaining-aware copies for every stage after the first when ``chain_aware``.
        """
        for g, aware in stages(targets, chain, chain_aware, self.chained):
            z = (self.chained if aware else self.solvers)[g](z, targets[g])
        return z

    def n_parameters(self, groups=()) -> int:
        """Parameters of the autoencoder plus the named solvers (the paper's model size)."""
        n = sum(p.numel() for p in self.ae.parameters())
        for g in groups:
            n += sum(p.numel() for p in self.solvers[g].parameters())
        return n

    # ------------------------------------------------------------------------------- checkpoints
    def state(self) -> dict:
        out = {f"ae.{k}": v for k, v in self.ae.state_dict().items()}
        for g, net in self.solvers.items():
            out.update({f"solver.{g}.{k}": v for k, v in net.state_dict().items()})
        for g, net in self.chained.items():
            out.update({f"chained.{g}.{k}": v for k, v in net.state_dict().items()})
        return out

    def save(self, path, *, command: str = "", seed: int | None = None, data: str = "", licence: str = "",
             extra: dict | None = None, half: bool = True):
        """One checkpoint (kind ``"ae_solvers"``): weights (float16 by default), config, the groups and
        their joints, skeleton, normalisation ``"pose"``, training range, provenance."""
        config = {**self.config.to_dict(), "groups": {g: list(GROUPS[g]) for g in self.solvers},
                  "chained": list(self.chained)}
        ex = {"x_range": self.x_range, **(extra or {})}
        return save_checkpoint(path, self.state(), kind=KIND, config=config, skeleton=self.skeleton,
                               norms={"pose": self.norm}, command=command, seed=seed, data=data, licence=licence,
                               extra=ex, half=half)

    @classmethod
    def load(cls, path, skeleton=None) -> "AESolvers":
        """Read :meth:`save`'s file; with ``skeleton`` it must be the one the weights were made for
        (joint names, parents, offsets), else a ``ValueError`` names the difference."""
        ck = load_checkpoint(path, kind=KIND, skeleton=skeleton)
        c = dict(ck["config"])
        groups, chained = c.pop("groups"), c.pop("chained")
        for g, joints in groups.items():
            if tuple(joints) != GROUPS.get(g):
                raise ValueError(f"checkpoint {path}: solver {g!r} was trained for joints {joints}, this posekit's "
                                 f"group {g!r} is {list(GROUPS.get(g, ()))}")
        cfg = AEConfig(**c)
        if "pose" not in ck["norms"]:
            raise ValueError(f"checkpoint {path} has no pose normalisation")
        norm = ck["norms"]["pose"]
        if np.shape(norm.mean) != (cfg.n_features,):
            raise ValueError(f"checkpoint {path}: its normalisation has {np.shape(norm.mean)} features, its config "
                             f"{cfg.n_features}")
        m = cls.new(ck["skeleton"], norm, cfg)
        state = ck["state"]
        part = lambda prefix: {k[len(prefix):]: v for k, v in state.items() if k.startswith(prefix)}  # noqa: E731
        m.ae.load_state_dict(part("ae."))
        for g in groups:
            m.solvers[g] = m.new_solver(g)
            m.solvers[g].load_state_dict(part(f"solver.{g}."))
        for g in chained:
            m.chained[g] = m.new_solver(g)
            m.chained[g].load_state_dict(part(f"chained.{g}."))
        m.x_range = ck["extra"].get("x_range")
        m.info = {k: ck[k] for k in ("command", "seed", "data", "licence", "path")} | {"extra": ck["extra"]}
        for net in (m.ae, *m.solvers.values(), *m.chained.values()):
            net.eval()
        return m

    def compile(self) -> "NumpyAESolvers":
        """The same networks as float32 numpy arrays, for fast single-pose solves."""
        return NumpyAESolvers(self)
