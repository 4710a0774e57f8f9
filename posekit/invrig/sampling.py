"""Supersampling rig controls to train a network on more than the animator made (Holden, Saito &
Komura 2017, Sec. 6 and Algorithm 2).

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb``. Each method fits a distribution to the
animation's control vectors, draws new ones, and clips them to the rig's ranges; the rig then gives
the joint positions, so every sample is an exact (x, y) training pair.

* ``uniform`` — per control, uniform between the data's min and max;
* ``gaussian`` — per control, a normal with the data's mean and standard deviation;
* ``mvn`` — one multivariate normal with the data's mean and covariance;
* ``gmm`` — a Gaussian mixture (scikit-learn, full covariances);
* ``pca`` — Algorithm 2 as we read it: project the controls on their principal components (those
  holding 99.9 % of the variance), whiten, draw from a unit Gaussian there and project back, scaled
  by ``spread`` (1.0 reproduces the data's covariance in those components; wider covers more).
"""

from __future__ import annotations

import numpy as np

__all__ = ["METHODS", "sample_controls"]

METHODS = ("uniform", "gaussian", "mvn", "gmm", "pca")


def sample_controls(method: str, Y, n: int, low, high, seed: int = 0, spread: float = 1.0, gmm_components: int = 8):
    """Draw ``n`` control vectors like ``Y`` (N, C); returns (n, C) clipped to ``[low, high]``."""
    Y = np.asarray(Y, dtype=float)
    rng = np.random.default_rng(seed)
    mean = Y.mean(0)
    if method == "uniform":
        out = rng.uniform(Y.min(0), Y.max(0), size=(n, Y.shape[1]))
    elif method == "gaussian":
        out = rng.normal(mean, Y.std(0), size=(n, Y.shape[1]))
    elif method == "mvn":
        out = rng.multivariate_normal(mean, np.cov(Y, rowvar=False), size=n, method="eigh")
    elif method == "gmm":
        from sklearn.mixture import GaussianMixture

        gm = GaussianMixture(gmm_components, covariance_type="full", reg_covar=1e-6, random_state=seed).fit(Y)
        out = gm.sample(n)[0][rng.permutation(n)]
    elif method == "pca":
        U, S, Vt = np.linalg.svd(Y - mean, full_matrices=False)
        var = S**2 / max(len(Y) - 1, 1)
        k = int(np.searchsorted(np.cumsum(var) / var.sum(), 0.999) + 1)
        z = rng.normal(size=(n, k)) * spread
        out = mean + (z * np.sqrt(var[:k])) @ Vt[:k]
    else:
        raise ValueError(f"unknown sampling method {method!r}; valid: {', '.join(METHODS)}")
    return np.clip(out, low, high)
