"""Gaussian-process regression (the posterior mean), hand-written in numpy, as in Holden, Saito &
Komura 2017 ("Learning Inverse Rig Mappings by Nonlinear Regression", TVCG), Sec. 4.

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb``.

Prediction (Eq. 2 of the paper, the Tikhonov-regularised posterior mean)::

    y(x*) = k(x*, X) (K + theta1 I)^-1 Y,      K_ij = k(x_i, x_j)

with the **multiquadric** kernel ``k(x, x') = sqrt(||x - x'||^2 + theta0^2)`` (Eq. 3). Inputs and outputs
are z-scored first. ``theta0`` is picked by a line search over ``[1e-4, 1e2]`` with repeated half-split
cross-validation, and the training set is **subsampled greedily** to a budget: farthest points
first, then the points the current model predicts worst.

A note on the solve: the squared-exponential and polynomial kernels give positive semi-definite
``K``, so ``K + theta1 I`` is factorised by Cholesky. The multiquadric is only *conditionally*
negative definite — its kernel matrix has one positive eigenvalue and the rest negative (the lesson
shows it) — so Cholesky does not exist; we factorise the symmetric indefinite system with LDL^T
(Bunch-Kaufman, ``scipy.linalg.solve(assume_a="sym")``). Neither path forms an inverse.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg

from ..data.dataset import NormStats

__all__ = ["KERNELS", "GPR", "cross_validate", "line_search_theta0", "greedy_subsample", "sq_distances"]


def sq_distances(A, B) -> np.ndarray:
    """Squared Euclidean distances between rows, shape (len(A), len(B))."""
    d = (A * A).sum(1)[:, None] + (B * B).sum(1)[None, :] - 2.0 * A @ B.T
    return np.maximum(d, 0.0)


KERNELS = {
    # name: (k(A, B, theta0), positive semi-definite?)
    "multiquadric": (lambda A, B, t: np.sqrt(sq_distances(A, B) + t * t), False),
    "squared_exponential": (lambda A, B, t: np.exp(-sq_distances(A, B) / (2.0 * t * t)), True),
    "linear": (lambda A, B, t: A @ B.T + t, True),
    "polynomial": (lambda A, B, t: (A @ B.T / A.shape[1] + t) ** 2, True),
}
"""Kernels compared in the lesson (``theta0`` is the length scale / offset of each)."""


class GPR:
    """The GP posterior mean with z-scored inputs and outputs.

    Parameters
    ----------
    kernel : str
        One of :data:`KERNELS`.
    theta0 : float
        Kernel parameter (multiquadric offset, squared-exponential length scale).
    theta1 : float
        Tikhonov regulariser (noise variance) added to the diagonal.
    """

    def __init__(self, kernel: str = "multiquadric", theta0: float = 1.0, theta1: float = 1e-3):
        if kernel not in KERNELS:
            raise ValueError(f"unknown kernel {kernel!r}; valid: {', '.join(KERNELS)}")
        if not (theta0 > 0 and theta1 >= 0):
            raise ValueError("theta0 must be > 0 and theta1 >= 0")
        self.kernel, self.theta0, self.theta1 = kernel, float(theta0), float(theta1)
        self.jitter = 0.0

    def _k(self, A, B):
        return KERNELS[self.kernel][0](A, B, self.theta0)

    def fit(self, X, Y) -> "GPR":
        """Fit on inputs X (N, D) and outputs Y (N, O).

        An ill-conditioned system gets jitter added to its diagonal (with a warning) until it is
        solvable; the result is never NaN.
        """
        X, Y = self._check(X, "X"), self._check(Y, "Y")
        if len(X) != len(Y):
            raise ValueError(f"X and Y need the same number of rows, got {len(X)} and {len(Y)}")
        self.x_norm, self.y_norm = NormStats.fit(X), NormStats.fit(Y)
        self.X = self.x_norm.normalize(X)
        K = self._k(self.X, self.X)
        Yn = self.y_norm.normalize(Y)
        psd = KERNELS[self.kernel][1]
        scale = max(float(np.abs(np.diag(K)).mean()), 1e-12)
        jitter = 0.0
        for attempt in range(8):
            A = K + (self.theta1 + jitter) * np.eye(len(K))
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("error", scipy.linalg.LinAlgWarning)
                    if psd:
                        self.alpha = scipy.linalg.cho_solve(scipy.linalg.cho_factor(A), Yn)
                    else:
                        self.alpha = scipy.linalg.solve(A, Yn, assume_a="sym")
                if np.all(np.isfinite(self.alpha)):
                    break
            except (np.linalg.LinAlgError, scipy.linalg.LinAlgWarning, ValueError):
                pass
            jitter = scale * 1e-10 * 100**attempt
        else:
            raise np.linalg.LinAlgError("kernel system stayed singular after adding jitter")
        if jitter:
            warnings.warn(f"GPR: kernel matrix ill-conditioned; added jitter {jitter:.3g} to the diagonal",
                          RuntimeWarning, stacklevel=2)
        self.jitter = jitter
        return self

    def predict(self, Xq) -> np.ndarray:
        """Posterior mean at query inputs (M, D) -> (M, O)."""
        Xq = self._check(Xq, "query")
        if Xq.shape[1] != self.X.shape[1]:
            raise ValueError(f"query: expected {self.X.shape[1]} features per row, got {Xq.shape[1]}")
        return self.y_norm.denormalize(self._k(self.x_norm.normalize(Xq), self.X) @ self.alpha)

    @staticmethod
    def _check(A, what):
        A = np.asarray(A, dtype=float)
        if A.ndim != 2 or len(A) == 0:
            raise ValueError(f"{what}: expected a 2-D array (rows, features), got shape {A.shape}")
        if not np.all(np.isfinite(A)):
            raise ValueError(f"{what} contains NaN or inf")
        return A


def cross_validate(X, Y, kernel: str, theta0: float, theta1: float = 1e-3, repeats: int = 3, seed: int = 0,
                   error=None) -> float:
    """Repeated half-split cross-validation: fit on a random half, score the other half.

    ``error(Y_true, Y_pred)`` defaults to the mean absolute z-scored output error.
    """
    rng = np.random.default_rng(seed)
    Y = np.asarray(Y, dtype=float)
    sd = np.maximum(Y.std(0), 1e-9)
    error = error or (lambda t, p: float(np.mean(np.abs(t - p) / sd)))
    scores = []
    for _ in range(repeats):
        perm = rng.permutation(len(X))
        a, b = perm[: len(X) // 2], perm[len(X) // 2:]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            m = GPR(kernel, theta0, theta1).fit(X[a], Y[a])
        scores.append(error(Y[b], m.predict(X[b])))
    return float(np.mean(scores))


def line_search_theta0(X, Y, kernel: str = "multiquadric", grid=None, theta1: float = 1e-3, repeats: int = 3,
                       seed: int = 0, error=None, rtol: float = 1e-6):
    """Pick theta0 over a log grid on [1e-4, 1e2] by cross-validation.

    Errors within ``rtol`` (relative) of the lowest count as a tie, and a tie goes to the
    *smallest* theta0. Without this rule the pick can rest on rounding noise: the linear kernel's
    theta0 is a constant offset that z-scored outputs barely feel, so its CV errors differ only
    around 1e-12 and the "best" value changed from machine to machine.

    Returns
    -------
    best : float
    table : list of (theta0, cv_error)
    """
    grid = np.logspace(-4, 2, 13) if grid is None else np.asarray(grid, dtype=float)
    table = [(float(t), cross_validate(X, Y, kernel, t, theta1, repeats, seed, error)) for t in grid]
    lowest = min(e for _, e in table)
    best = min(t for t, e in table if e <= lowest * (1.0 + rtol) + 1e-15)
    return best, table


def greedy_subsample(X, Y, budget: int, kernel: str = "multiquadric", theta0: float = 1.0, theta1: float = 1e-3,
                     step: int | None = None, seed: int = 0) -> np.ndarray:
    """Choose ``budget`` training rows: farthest-point sampling for the first half (in z-scored input
    space), then repeatedly add the ``step`` rows the current GPR predicts worst.

    Returns
    -------
    ndarray of int, shape (budget,)
    """
    X, Y = np.asarray(X, float), np.asarray(Y, float)
    if not 1 <= budget <= len(X):
        raise ValueError(f"budget must be in 1..{len(X)}, got {budget}")
    Z = NormStats.fit(X).normalize(X)
    sd = np.maximum(Y.std(0), 1e-9)
    rng = np.random.default_rng(seed)
    chosen = [int(rng.integers(len(Z)))]
    d = sq_distances(Z, Z[chosen])[:, 0]
    while len(chosen) < max(1, budget // 2):
        j = int(np.argmax(d))
        chosen.append(j)
        d = np.minimum(d, sq_distances(Z, Z[[j]])[:, 0])
    step = step or max(1, budget // 10)
    while len(chosen) < budget:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            m = GPR(kernel, theta0, theta1).fit(X[chosen], Y[chosen])
        err = np.abs(m.predict(X) - Y) / sd
        err = err.mean(1)
        err[chosen] = -np.inf
        add = np.argsort(-err)[: min(step, budget - len(chosen))]
        chosen.extend(int(a) for a in add)
    return np.array(chosen)
