"""Measuring a pose latent space: is it invertible, and is every point a pose?

Introduced in ``notebooks/04_aegan_latent_space.ipynb``, where the AE-GAN (Victor & Meyer, JFIG 2020) is
set against lesson 03's plain autoencoder (Victor et al. 2021) with the same code:

* **Invertibility** — ``x -> z -> x`` (poses back, mean per-joint error in mm) and ``z -> x -> z``
  (codes back, mean absolute error per number, for codes drawn from the space's prior);
* **"Every point is a pose"** — poses decoded from prior samples and from the midpoints of encoded
  pose pairs, scored by bone-length error (the largest change of a bone's length, mm), the naturalness
  proxy (distance to the nearest training pose, :class:`posekit.data.metrics.NaturalnessIndex`, mm) and
  the AE-GAN's pose discriminator (the probability that the pose is real: one judge for both spaces);
  and their **spread** (the mean per-joint distance between two of them, mm: a space that decodes
  every code to a few safe poses scores well on naturalness and badly here).

A space is anything with ``encode(x)``, ``decode(z)`` (z-scored pose vectors, numpy) and
``sample(n, rng)``. The AE-GAN samples its prior (uniform on ``[-1, 1]^32``); the plain autoencoder has
none, so it is given the fairest simple one: the Gaussian (mean and covariance) of its training codes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from ...data.metrics import bone_length_error
from ...data.pose_vectors import poses_from_vectors

__all__ = ["AEGANSpace", "AutoencoderSpace", "invertibility", "decoded_scores", "spread_mm", "compare_spaces"]


class AEGANSpace:
    """The AE-GAN's encoder, generator and prior as a space."""

    def __init__(self, model):
        self.model, self.latent, self.name = model, model.config.latent, "AE-GAN"

    def encode(self, x):
        return self.model.encode(x)

    def decode(self, z):
        return self.model.decode(z)

    def sample(self, n: int, rng):
        return rng.uniform(-1.0, 1.0, (n, self.latent)).astype(np.float32)


class AutoencoderSpace:
    """Lesson 03's autoencoder (:class:`~posekit.models.pose_autoencoder.networks.AESolvers`) as a space; its prior is the
    Gaussian of the codes of ``x_train`` (z-scored training poses)."""

    def __init__(self, ae_solvers, x_train):
        self.ae, self.name = ae_solvers.ae, "autoencoder (lesson 03)"
        z = self.encode(x_train)
        self.mean, self.cov = z.mean(0), np.cov(z, rowvar=False)
        self.latent = z.shape[1]

    def encode(self, x):
        with torch.no_grad():
            return self.ae.encode(torch.as_tensor(np.asarray(x, np.float32))).numpy()

    def decode(self, z):
        with torch.no_grad():
            return self.ae.decode(torch.as_tensor(np.asarray(z, np.float32))).numpy()

    def sample(self, n: int, rng):
        return rng.multivariate_normal(self.mean, self.cov, n).astype(np.float32)


def _mm(norm, a, b) -> np.ndarray:
    d = (np.asarray(a) - np.asarray(b)) * norm.std.astype(np.float32)
    return np.linalg.norm(d.reshape(len(d), -1, 3), axis=-1).mean(-1) * 1000


def invertibility(space, x, norm, n_codes: int = 1000, seed: int = 0) -> dict:
    """``x_mm``: mean per-joint error of ``decode(encode(x))`` (mm, median over poses); ``z_abs``: median
    mean absolute error of ``encode(decode(z))`` for ``n_codes`` prior samples."""
    rng = np.random.default_rng(seed)
    xr = space.decode(space.encode(x))
    z = space.sample(n_codes, rng)
    zr = space.encode(space.decode(z))
    return {"x_mm": float(np.median(_mm(norm, xr, x))), "z_abs": float(np.median(np.abs(zr - z).mean(-1)))}


@dataclass
class DecodedScores:
    """Medians over decoded poses (mm; ``real`` a probability)."""

    bone_mm: float
    natural_mm: float
    real: float
    spread_mm: float

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def decoded_scores(x_decoded, skeleton, norm, natural, reference_pos, judge=None) -> DecodedScores:
    """Bone-length error, naturalness proxy and the ``judge``'s realness of z-scored poses (N, 3 B).

    Parameters
    ----------
    natural : NaturalnessIndex
    reference_pos : ndarray, shape (J, 3)
        Any real pose of ``skeleton`` (its bone lengths are the true ones).
    judge : callable, optional
        z-scored poses -> probability real (the AE-GAN's pose discriminator).
    """
    pos = poses_from_vectors(skeleton, np.asarray(x_decoded, float) * norm.std + norm.mean)
    bone = bone_length_error(skeleton, pos, np.asarray(reference_pos)[None])
    real = float(np.median(judge(x_decoded))) if judge is not None else float("nan")
    return DecodedScores(float(np.median(bone) * 1000), float(np.median(natural.distance(pos)) * 1000), real,
                         spread_mm(skeleton, pos))


def spread_mm(skeleton, global_pos) -> float:
    """Mean per-joint distance between consecutive poses of ``global_pos`` (N, J, 3), each in its own root
    frame and pelvis-relative (:func:`posekit.data.metrics.pose_features`), median over pairs, mm."""
    from ...data.metrics import pose_features

    f = pose_features(skeleton, global_pos)
    d = (f[1:] - f[:-1]).reshape(len(f) - 1, -1, 3)
    return float(np.median(np.linalg.norm(d, axis=-1).mean(-1)) * 1000)


def compare_spaces(spaces, x_test, skeleton, norm, natural, reference_pos, judge=None, n: int = 1000,
                   seed: int = 0) -> dict:
    """Every measurement of the module docstring for each space: ``{name: {...}}``, the same test poses,
    prior draws of ``n`` codes and ``n`` pairs of test poses (midpoints) for each."""
    rng = np.random.default_rng(seed)
    pairs = rng.integers(0, len(x_test), (n, 2))
    out = {}
    for sp in spaces:
        r = {"latent": int(sp.latent), **invertibility(sp, x_test, norm, n, seed)}
        prior = sp.decode(sp.sample(n, np.random.default_rng(seed + 1)))
        r["prior"] = decoded_scores(prior, skeleton, norm, natural, reference_pos, judge).as_dict()
        z = sp.encode(x_test)
        mid = sp.decode(0.5 * (z[pairs[:, 0]] + z[pairs[:, 1]]))
        r["interp"] = decoded_scores(mid, skeleton, norm, natural, reference_pos, judge).as_dict()
        out[sp.name] = r
    return out
