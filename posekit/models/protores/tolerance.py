"""The tolerance Lambda of an effector as a noise scale (Oreshkin et al. 2022, Appendix B), without torch.

Introduced in ``notebooks/05_protores.ipynb`` (the tolerance slider); the studio maps its sliders with
:func:`tolerance_to_sigma` before any network is loaded, so this module needs numpy only.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SIGMA_M", "ETA", "tolerance_to_sigma", "sigma_to_tolerance"]

SIGMA_M = 0.1
"""sigma_M: the noise scale of tolerance 1 (Appendix B): 0.1 m for positions, 0.1 rad for angles."""

ETA = 13.0
"""eta: the tolerance-to-noise exponent, ``sigma = sigma_M Lambda^eta`` (Appendix B)."""


def tolerance_to_sigma(lam):
    """``sigma = sigma_M Lambda^eta``: a tolerance in [0, 1] as a noise scale (metres or radians)."""
    return SIGMA_M * lam ** ETA


def sigma_to_tolerance(sigma):
    """The inverse of :func:`tolerance_to_sigma`: a noise scale in [0, sigma_M] as ``Lambda`` in [0, 1]."""
    return (np.asarray(sigma, dtype=float) / SIGMA_M) ** (1.0 / ETA)
