"""The pose autoencoder and its latent-space solvers in numpy float32, read from a checkpoint without torch.

Introduced in ``notebooks/03_autoencoder_solvers.ipynb``: one solve is a few small matrix products
(Victor, Meyer & Bouakaz 2021, Sec. 3.3: ``E``, ``S_t``, ``D``), where torch's per-call cost, not arithmetic, sets
the time. :class:`NumpyAESolvers` holds the trained weights as arrays; :meth:`NumpyAESolvers.load` reads them
with :func:`posekit.learn.checkpoint.load_checkpoint` (``arrays=True``), so a process that only poses (the
studio's kernel) never imports torch. The solver groups and the chain order (Sec. 3.5) are defined here too.
"""

from __future__ import annotations

import numpy as np

__all__ = ["KIND", "WEIGHTS", "weights_path", "GROUPS", "CHAIN", "chain_groups", "stages", "NumpyAESolvers"]

KIND = "ae_solvers"

WEIGHTS = "ae_solvers.pt"
"""File name of the shipped weights in ``data_samples/weights/``."""


def weights_path(folder=None):
    """The weights' file, :data:`WEIGHTS` in ``folder`` or the shipped weights' folder
    (:func:`posekit.paths.weights_path`)."""
    from ... import paths

    return paths.weights_path(WEIGHTS, folder)


GROUPS = {
    "hands": ("left_hand", "right_hand"),
    "feet": ("left_foot", "right_foot"),
    "head": ("head",),
    "all": ("left_hand", "right_hand", "left_foot", "right_foot", "head"),
}
"""The joint sets (roles) of the paper's solvers: name -> joints, in the order of their targets."""

CHAIN = ("hands", "feet", "head")
"""The order in which chained solvers run (Sec. 3.5)."""


def chain_groups(joints, available=tuple(GROUPS)) -> list:
    """The groups of :data:`CHAIN` (those in ``available``) that the joint set ``joints`` (roles) covers,
    in chain order: the stages of a chained solve (Sec. 3.5)."""
    have = set(joints)
    return [g for g in CHAIN if g in available and set(GROUPS[g]) <= have]


def stages(groups, chain=None, chain_aware: bool = True, chained=()) -> list:
    """The stages of a solve: ``[(group, use its chaining-aware copy)]``.

    ``groups`` are the joint sets with targets. One group and no ``chain``: its own solver. Otherwise the
    chain of Sec. 3.5 in ``chain`` (default :data:`CHAIN`) order; with ``chain_aware`` every stage after
    the first runs its chaining-aware copy when there is one (``chained``)."""
    groups = list(groups)
    order = [g for g in (chain or CHAIN) if g in groups] if len(groups) > 1 or chain else groups
    return [(g, bool(chain_aware and i > 0 and g in chained)) for i, g in enumerate(order)]


def _layers(state: dict, prefix: str, names):
    """(W^T, b) float32 of the linear layers ``{prefix}{name}`` in order."""
    return [(np.asarray(state[f"{prefix}{n}.weight"]).T.astype(np.float32).copy(),
             np.asarray(state[f"{prefix}{n}.bias"]).astype(np.float32).copy()) for n in names]


def _mlp_names(state: dict, prefix: str) -> list:
    """The linear layers of an ``nn.Sequential`` in a state dict: ``net.0``, ``net.2``, ... in order."""
    idx = sorted({int(k[len(prefix):].split(".")[0]) for k in state
                  if k.startswith(prefix) and k.endswith(".weight")})
    if not idx:
        raise KeyError(prefix + "*")
    return [str(i) for i in idx]


class NumpyAESolvers:
    """:class:`~posekit.models.pose_autoencoder.networks.AESolvers` in numpy float32: ``encode``, ``decode``, ``solve`` on (N, ...) arrays.

    Same numbers as the torch modules (to float32 rounding); no autograd, no per-call dispatch cost.
    """

    def __init__(self, m):
        state = {k: v.detach().cpu().numpy() for k, v in m.state().items()}
        self._build(state, m.config.tied, list(m.solvers), list(m.chained))
        self.skeleton, self.norm, self.x_range, self.info = m.skeleton, m.norm, m.x_range, m.info

    @classmethod
    def load(cls, path, skeleton=None) -> "NumpyAESolvers":
        """The networks of an :meth:`AESolvers.save <posekit.models.pose_autoencoder.networks.AESolvers.save>`
        file, read without torch, with its ``skeleton``, ``norm``, ``x_range`` and ``info``; with ``skeleton`` it
        must be the one the weights were made for, else a ``ValueError`` names the difference."""
        from ...learn.checkpoint import load_checkpoint

        ck = load_checkpoint(path, kind=KIND, skeleton=skeleton, arrays=True)
        groups, chained = ck["config"]["groups"], ck["config"]["chained"]
        for g, joints in groups.items():
            if tuple(joints) != GROUPS.get(g):
                raise ValueError(f"checkpoint {path}: solver {g!r} was trained for joints {joints}, this posekit's "
                                 f"group {g!r} is {list(GROUPS.get(g, ()))}")
        if "pose" not in ck["norms"]:
            raise ValueError(f"checkpoint {path} has no pose normalisation")
        self = cls.__new__(cls)
        try:
            self._build(ck["state"], bool(ck["config"].get("tied", True)), list(groups), list(chained))
        except KeyError as err:
            raise ValueError(f"checkpoint {path}: the networks do not match its config (missing {err})") from None
        n = ck["config"]["n_features"]
        if self.enc[0][0].shape[0] != n or np.shape(ck["norms"]["pose"].mean) != (n,):
            raise ValueError(f"checkpoint {path}: its encoder or normalisation does not take its config's {n} features")
        self.skeleton, self.norm, self.x_range = ck["skeleton"], ck["norms"]["pose"], ck["extra"].get("x_range")
        self.info = {k: ck[k] for k in ("command", "seed", "data", "licence", "path")} | {"extra": ck["extra"]}
        return self

    def _build(self, state: dict, tied: bool, groups, chained):
        self.enc = _layers(state, "ae.", ("enc1", "enc2", "enc3"))
        if tied:  # x = W1^T relu(W2^T relu(W3^T z)): the encoder's matrices, transposed, no biases
            self.dec = [(w.T.copy(), None) for w, _ in reversed(self.enc)]
        else:
            self.dec = _layers(state, "ae.", ("dec1", "dec2", "dec3"))
        self.solvers = {g: _layers(state, f"solver.{g}.net.", _mlp_names(state, f"solver.{g}.net."))
                        for g in groups}
        self.chained = {g: _layers(state, f"chained.{g}.net.", _mlp_names(state, f"chained.{g}.net."))
                        for g in chained}
        self._sizes = {"ae": sum(int(np.asarray(v).size) for k, v in state.items() if k.startswith("ae."))}
        for g in groups:
            self._sizes[g] = sum(int(np.asarray(v).size) for k, v in state.items() if k.startswith(f"solver.{g}."))

    def n_parameters(self, groups=()) -> int:
        """Parameters of the autoencoder plus the named solvers (:meth:`AESolvers.n_parameters
        <posekit.models.pose_autoencoder.networks.AESolvers.n_parameters>`)."""
        return self._sizes["ae"] + sum(self._sizes[g] for g in groups)

    @staticmethod
    def _mlp(layers, h):
        for i, (w, b) in enumerate(layers):
            h = h @ w
            if b is not None:
                h += b
            if i < len(layers) - 1:
                np.maximum(h, 0.0, out=h)
        return h

    def encode(self, x):
        return self._mlp(self.enc, np.asarray(x, dtype=np.float32))

    def decode(self, z):
        return self._mlp(self.dec, np.asarray(z, dtype=np.float32))

    def latent(self, z, targets: dict, chain=None, chain_aware: bool = True, reencode: bool = False):
        """:meth:`AESolvers.latent <posekit.models.pose_autoencoder.networks.AESolvers.latent>` in numpy.

        ``reencode``: between two stages, decode the code and encode the pose again, ``z = E(D(z))`` — the
        chaining of the authors' code (``CombinedSequentialIKSolver``), where the paper's Sec. 3.5 composes the
        solvers in the latent space."""
        plan = stages(targets, chain, chain_aware, self.chained)
        for k, (g, aware) in enumerate(plan):
            if reencode and k:
                z = self.encode(self.decode(z))
            z = self._mlp((self.chained if aware else self.solvers)[g],
                          np.concatenate([z, np.asarray(targets[g], dtype=np.float32)], axis=-1))
        return z
