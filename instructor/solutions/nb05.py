"""Reference solutions of lesson 05's exercises (instructor version; ``posekit exercises solutions 05`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_step", "exercise_weight", "exercise_centroid"]


def exercise_step(b, f, e_prev, r):
    """One proto-residual step of ProtoRes's encoder (Oreshkin et al. 2022, Eq. 2), after the block's layers.

    The forecasts accumulate into each effector's encoding, ``e = e_prev + f``; the prototype is the mean
    encoding over the effectors, ``p = mean_i e_i``; the next block reads each effector minus what the set
    already explains, ``x_next = relu(b - p / r)``.

    Parameters
    ----------
    b : ndarray, shape (N, d)
        The block's backcast, one row per effector.
    f : ndarray, shape (N, d)
        The block's forecast.
    e_prev : ndarray, shape (N, d)
        Encodings accumulated by the earlier blocks.
    r : int
        Number of the block just run, from 1 (the authors' code divides by it).

    Returns
    -------
    e : ndarray, shape (N, d)
    p : ndarray, shape (d,)
    x_next : ndarray, shape (N, d)
    """
    import numpy as np

    e = e_prev + f
    p = e.mean(axis=0)                   # mean over the effectors: independent of their order
    x_next = np.maximum(b - p / r, 0.0)  # p is broadcast to every effector's row
    return e, p, x_next


def exercise_weight(lam):
    """ProtoRes's tolerance: training noise scale and loss weight of each effector (Oreshkin et al. 2022,
    Sec. 2.2-2.3, Appendix B).

    ``sigma = sigma_M Lambda^eta`` with ``sigma_M = 0.1`` (metres or radians) and ``eta = 13``; the loss
    weight ``min(W_M, 1 / sigma)`` with ``W_M = 1000``. An exact effector (``sigma = 0``) gets ``W_M``.

    Parameters
    ----------
    lam : ndarray, shape (K,)
        Tolerances ``Lambda`` in [0, 1].

    Returns
    -------
    sigma : ndarray, shape (K,)
    weight : ndarray, shape (K,)
    """
    import numpy as np

    sigma_m, eta, w_m = 0.1, 13.0, 1000.0
    sigma = sigma_m * np.asarray(lam, dtype=float) ** eta
    # 1 / sigma is at least W_M wherever sigma <= 1 / W_M, so flooring sigma there avoids dividing by 0
    weight = np.minimum(w_m, 1.0 / np.maximum(sigma, 1.0 / w_m))
    return sigma, weight


def exercise_centroid(kind, value, lam):
    """Tolerance-weighted centroid of a request's position effectors (Oreshkin et al. 2022, Sec. 2.1).

    ``c = sum_i w_i p_i / sum_i w_i`` over the position effectors, with ``w_i = 1 - Lambda_i + 1e-3`` (a
    tight effector counts most); rotations and look-at targets do not count. The origin when the request has
    no position effector.

    Parameters
    ----------
    kind : ndarray of int, shape (N,)
        0 position, 1 rotation, 2 look-at.
    value : ndarray, shape (N, 6)
        Effector values; a position effector's position is ``value[:, :3]``, metres.
    lam : ndarray, shape (N,)
        Tolerances ``Lambda`` in [0, 1].

    Returns
    -------
    ndarray, shape (3,), metres
    """
    import numpy as np

    is_position = np.asarray(kind) == 0
    w = is_position * (1.0 - np.asarray(lam, dtype=float) + 1e-3)  # 0 for the other kinds
    if w.sum() == 0:
        return np.zeros(3)
    return (w[:, None] * value[:, :3]).sum(axis=0) / w.sum()
