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

    def describe_for(theta0, theta1, what=""):
        def describe(got, expected):
            return (f"max error {np.abs(got - expected).max():.3g} with theta0 = {theta0:g}, theta1 = {theta1:g}"
                    f"{what}; kernel sqrt(d^2 + theta0^2), theta1 on K's diagonal? solve, not inverse?")
        return describe
    k = KERNELS["multiquadric"][0]
    for n, d, theta0, theta1, m, o in ((20, 3, 0.5, 1e-3, 7, 2), (40, 6, 2.0, 1e-2, 7, 2), (15, 2, 0.1, 1e-1, 7, 2),
                                       (12, 4, 1.0, 0.5, 1, 1),   # one query, one output: shapes (1, D) and (N, 1)
                                       (25, 3, 0.5, 1.0, 5, 3)):  # the same theta0 as case 1, another theta1
        X, Y, Xq = rng.normal(size=(n, d)), rng.normal(size=(n, o)), rng.normal(size=(m, d))
        expected = k(Xq, X, theta0) @ scipy.linalg.solve(k(X, X, theta0) + theta1 * np.eye(n), Y, assume_a="sym")
        what = " (one query, one output)" if m == 1 else ""
        cases.append(((X, Y, Xq, theta0, theta1), expected, describe_for(theta0, theta1, what)))
    Xq = X[:3].copy()  # queries at training inputs: the mean is not Y there (theta1 smooths)
    cases.append(((X, Y, Xq, 0.5, 1.0), k(Xq, X, 0.5) @ scipy.linalg.solve(k(X, X, 0.5) + np.eye(len(X)), Y,
                                                                            assume_a="sym"),
                  describe_for(0.5, 1.0, " (queries at training inputs)")))
    return report("check_gpr_mean", my_gpr_mean, cases, atol=1e-6, forbid=(GPR.fit, GPR.predict),
                  arg_names=("X", "Y", "Xq", "theta0", "theta1"))


@judged
def check_dls_step(my_dls_step) -> bool:
    """Check ``my_dls_step(J (X, C), dx (X,), damping) -> dy (C,)``: (J^T J + lambda^2 I)^-1 J^T dx."""
    rng = np.random.default_rng(6)
    cases = []

    def describe_for(lam, shape):
        def describe(got, expected):
            return (f"max error {np.abs(got - expected).max():.3g} (J {shape[0]} x {shape[1]}, damping {lam:g}); "
                    "(J^T J + damping^2 I) dy = J^T dx — damping squared on the diagonal, J^T on dx?")
        return describe
    for X, C, lam, dtype in ((9, 4, 0.1, float), (54, 34, 0.05, float), (6, 8, 0.5, float),
                             (7, 3, 0.0, float),          # no damping, J tall: plain least squares
                             (5, 5, 2.0, float),          # heavy damping: a short step along J^T dx
                             (8, 4, 0.2, np.float32)):    # float32 J and dx
        J, dx = rng.normal(size=(X, C)).astype(dtype), rng.normal(size=X).astype(dtype)
        Jd, dxd = J.astype(float), dx.astype(float)
        expected = np.linalg.solve(Jd.T @ Jd + lam**2 * np.eye(C), Jd.T @ dxd)
        cases.append(((J, dx, lam), expected, describe_for(lam, J.shape)))
    return report("check_dls_step", my_dls_step, cases, atol=1e-8, arg_names=("J", "dx", "damping"))


__all__ = ["check_gpr_mean", "check_dls_step"]
