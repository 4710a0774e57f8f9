"""Checkers for ``notebooks/02_inverse_rig_mapping.ipynb``."""

from __future__ import annotations

import numpy as np
import scipy.linalg

from ..invrig.gpr import GPR, KERNELS
from ._check import report
from ._judge import judged


@judged
def check_gpr_mean(my_gpr_mean) -> bool:
    """Check ``my_gpr_mean(X (N, D), Y (N, O), Xq (M, D), theta0, theta1) -> (M, O)``: the multiquadric
    posterior mean k(Xq, X) (K + theta1 I)^-1 Y of Holden et al. 2017 (Eqs. 2-3), no normalisation."""
    rng = np.random.default_rng(5)
    cases = []

    def describe(got, expected):
        return f"max error {np.abs(got - expected).max():.3g}; kernel sqrt(d^2 + theta0^2)? solve, not inverse?"
    for n, d, theta0, theta1 in ((20, 3, 0.5, 1e-3), (40, 6, 2.0, 1e-2), (15, 2, 0.1, 1e-1)):
        X, Y, Xq = rng.normal(size=(n, d)), rng.normal(size=(n, 2)), rng.normal(size=(7, d))
        k = KERNELS["multiquadric"][0]
        expected = k(Xq, X, theta0) @ scipy.linalg.solve(k(X, X, theta0) + theta1 * np.eye(n), Y, assume_a="sym")
        cases.append(((X, Y, Xq, theta0, theta1), expected, describe))
    return report("check_gpr_mean", my_gpr_mean, cases, atol=1e-6, forbid=(GPR.fit, GPR.predict),
                  arg_names=("X", "Y", "Xq", "theta0", "theta1"))


@judged
def check_dls_step(my_dls_step) -> bool:
    """Check ``my_dls_step(J (X, C), dx (X,), damping) -> dy (C,)``: (J^T J + lambda^2 I)^-1 J^T dx."""
    rng = np.random.default_rng(6)
    cases = []

    def describe(got, expected):
        return f"max error {np.abs(got - expected).max():.3g}; damping squared on the diagonal?"
    for X, C, lam in ((9, 4, 0.1), (54, 34, 0.05), (6, 8, 0.5)):
        J, dx = rng.normal(size=(X, C)), rng.normal(size=X)
        expected = np.linalg.solve(J.T @ J + lam**2 * np.eye(C), J.T @ dx)
        cases.append(((J, dx, lam), expected, describe))
    return report("check_dls_step", my_dls_step, cases, atol=1e-8, arg_names=("J", "dx", "damping"))


__all__ = ["check_gpr_mean", "check_dls_step"]
