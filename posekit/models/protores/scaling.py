"""Error against training compute: the frontier of the scaling study and a power law through it.

Introduced in ``notebooks/05_protores.ipynb`` (the scaling curve). ``posekit train protores-studies --scaling``
trains ProtoRes at several widths for several step counts (:data:`~posekit.models.protores.studies.SCALING_GRID`).
Each run's training compute is ``C = N D``: parameters ``N`` times poses seen ``D`` (steps x batch), the usual
proxy for training floating-point operations (about ``6 N D``). For each budget the best width gives the
*compute frontier*; a straight line through the frontier in log-log axes is the power law

    L(C) = a C^(-b)

and solving ``L(C) = L*`` for a target error says how much compute the curve predicts for it. Extrapolating a
power law fitted over one or two decades is a rough estimate, not a promise: the curve may bend (a data limit,
an error floor) before it gets there.
"""

from __future__ import annotations

import numpy as np

__all__ = ["frontier", "fit_power_law", "compute_for"]


def frontier(compute, error):
    """Indices of the runs on the compute frontier: sorted by compute, each with a lower error than every
    cheaper run.

    Parameters
    ----------
    compute, error : array, shape (R,)
        Each run's training compute (parameter-poses) and error (any unit, lower is better).

    Returns
    -------
    ndarray of int
    """
    compute, error = np.asarray(compute, float), np.asarray(error, float)
    if compute.shape != error.shape or compute.ndim != 1 or len(compute) == 0:
        raise ValueError(f"expected two arrays of the same length, got shapes {compute.shape} and {error.shape}")
    best, keep = np.inf, []
    for i in np.argsort(compute, kind="stable"):
        if error[i] < best:
            keep.append(int(i))
            best = error[i]
    return np.array(keep, dtype=int)


def fit_power_law(compute, error) -> tuple:
    """``(a, b)`` of ``error = a compute^(-b)``, least squares in log-log axes.

    Parameters
    ----------
    compute, error : array, shape (R,), R >= 2, all positive

    Returns
    -------
    a, b : float
        ``b > 0`` when error falls with compute.
    """
    compute, error = np.asarray(compute, float), np.asarray(error, float)
    if compute.shape != error.shape or len(compute) < 2:
        raise ValueError(f"a power law needs at least two runs, got {len(compute)}")
    if (compute <= 0).any() or (error <= 0).any():
        raise ValueError("compute and error must be positive (log-log fit)")
    slope, intercept = np.polyfit(np.log(compute), np.log(error), 1)
    return float(np.exp(intercept)), float(-slope)


def compute_for(target: float, a: float, b: float) -> float:
    """The compute at which ``a C^(-b)`` reaches ``target``: ``(a / target)^(1 / b)``; inf when the law does not
    fall (``b <= 0``)."""
    if b <= 0:
        return float("inf")
    return float((a / float(target)) ** (1.0 / b))
