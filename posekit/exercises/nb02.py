"""Checkers for ``notebooks/02_inverse_rig_mapping.ipynb``.

Section 4 writes the GP mean by hand and picks ``theta0`` by repeated half-split cross-validation; exercise 1 asks
for the leave-one-out predictions of every training pose in closed form, from one solve (the cross-validation
the lesson did not run). Section 5 states damped least squares; exercise 2 asks for the step of a variant the
lesson only argues for: each control's own scale and a pull towards the learned guess (a prior), so that a
redundant pair of controls stays where the animator would put it. Each checker starts with a generic case,
accepts float32 answers, and refuses an answer that calls the posekit function it is compared against or changes
its inputs.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from ..invrig.gpr import GPR, KERNELS, cross_validate, line_search_theta0
from ..invrig.jacobian import refine
from ._check import report
from ._judge import judged


# -- exercise 1: leave-one-out predictions in closed form -----------------------------------------------------------

def gpr_loo_reference(X, Y, theta0, theta1):
    """What :func:`check_gpr_loo` expects, by brute force: for every training pose ``i``, the multiquadric GP mean
    (no normalisation) fitted on the other N - 1 poses, at ``X[i]``; shape (N, O)."""
    X, Y = np.asarray(X, dtype=float), np.asarray(Y, dtype=float)
    k = KERNELS["multiquadric"][0]
    out = np.zeros((len(X), Y.shape[1]))
    for i in range(len(X)):
        rest = np.arange(len(X)) != i
        A = k(X[rest], X[rest], theta0) + theta1 * np.eye(len(X) - 1)
        out[i] = k(X[i:i + 1], X[rest], theta0) @ scipy.linalg.solve(A, Y[rest], assume_a="sym")
    return out


@judged
def check_gpr_loo(my_gpr_loo) -> bool:
    """Check ``my_gpr_loo(X (N, D), Y (N, O), theta0, theta1) -> (N, O)``: each training pose's prediction by
    the multiquadric GP mean fitted on all the *other* poses (leave-one-out), no normalisation
    (:func:`gpr_loo_reference`); a closed form from one solve is the exercise, a loop of N fits gives the same
    numbers."""
    rng = np.random.default_rng(5)
    k = KERNELS["multiquadric"][0]
    cases = []

    def describe_for(X, Y, theta0, theta1, what=""):
        G = k(X, X, theta0) + theta1 * np.eye(len(X))
        alpha = np.linalg.solve(G, Y)
        fitted = k(X, X, theta0) @ alpha                    # the mean *with* each pose, at each pose
        no_diag = Y - alpha                                 # the divide by (G^-1)_ii forgotten
        try:  # theta1 forgotten (K alone is singular when a pose is repeated)
            K_inv = np.linalg.inv(k(X, X, theta0))
            inv_k = Y - (K_inv @ Y) / np.diag(K_inv)[:, None]
        except np.linalg.LinAlgError:
            inv_k = np.full_like(Y, np.nan)

        def describe(got, exp):
            i = np.unravel_index(int(np.argmax(np.abs(got - exp))), exp.shape)
            said = (f"pose {i[0]}, output {i[1]}: got {got[i]:.6g}, expected {exp[i]:.6g} (theta0 = {theta0:g}, "
                    f"theta1 = {theta1:g}{what})")
            if np.allclose(got, fitted, atol=1e-6):
                return said + ": that is the mean fitted on every pose, the left-out one included — leave it out"
            if np.allclose(got, no_diag, atol=1e-6):
                return said + ": y_i - alpha_i; the residual is alpha_i / (G^-1)_ii, G = K + theta1 I"
            if theta1 > 0 and np.allclose(got, inv_k, atol=1e-6):
                return said + ": theta1 left off G = K + theta1 I"
            return said + ": y_i - [G^-1 Y]_i / [G^-1]_ii with G = K + theta1 I and the kernel sqrt(d^2 + theta0^2)?"
        return describe

    for n, d, o, theta0, theta1 in ((20, 3, 2, 0.5, 1e-2),       # generic
                                    (40, 6, 3, 2.0, 1e-3),
                                    (15, 2, 1, 0.3, 1e-2),       # one output: Y (N, 1)
                                    (12, 4, 2, 1.0, 2.0),        # heavy regularisation
                                    (25, 3, 2, 0.5, 3.0)):       # the same theta0 as case 1, another theta1
        X, Y = rng.normal(size=(n, d)), rng.normal(size=(n, o))
        cases.append(((X, Y, theta0, theta1), gpr_loo_reference(X, Y, theta0, theta1),
                      describe_for(X, Y, theta0, theta1)))
    X = rng.normal(size=(10, 3))  # two poses repeated: left out, each is predicted from its twin
    X[7], X[8] = X[2], X[3]
    Y = rng.normal(size=(10, 2))
    cases.append(((X, Y, 0.7, 0.05), gpr_loo_reference(X, Y, 0.7, 0.05),
                  describe_for(X, Y, 0.7, 0.05, ", poses 2 and 3 repeated as 7 and 8")))
    r32 = np.random.default_rng(2)  # float32 inputs, a well-conditioned G (float32 arithmetic keeps 5 digits there)
    X32, Y32 = r32.normal(size=(14, 3)).astype(np.float32), r32.normal(size=(14, 2)).astype(np.float32)
    cases.append(((X32, Y32, 0.5, 0.01), gpr_loo_reference(X32, Y32, 0.5, 0.01),
                  describe_for(X32.astype(float), Y32.astype(float), 0.5, 0.01, ", float32 inputs")))
    return report("check_gpr_loo", my_gpr_loo, cases, atol=1e-6,
                  forbid=(GPR.fit, GPR.predict, cross_validate, line_search_theta0, gpr_loo_reference),
                  arg_names=("X", "Y", "theta0", "theta1"))


# -- exercise 2: a damped step with each control's scale and a prior ------------------------------------------------

def dls_prior_reference(J, dx, y, y_prior, damping, weights):
    """What :func:`check_dls_prior` expects: the minimiser ``dy`` of
    ``|J dy - dx|^2 + damping^2 |weights * (y + dy - y_prior)|^2``, from its normal equations
    ``(J^T J + damping^2 W^2) dy = J^T dx + damping^2 W^2 (y_prior - y)``, ``W = diag(weights)``."""
    J, dx, y, yp, w = (np.asarray(a, dtype=float) for a in (J, dx, y, y_prior, weights))
    W2 = np.diag(w**2)
    return np.linalg.solve(J.T @ J + damping**2 * W2, J.T @ dx + damping**2 * W2 @ (yp - y))


@judged
def check_dls_prior(my_dls_prior) -> bool:
    """Check ``my_dls_prior(J (M, C), dx (M,), y (C,), y_prior (C,), damping, weights (C,)) -> dy (C,)``: the step
    that minimises ``|J dy - dx|^2 + damping^2 sum_c (weights_c (y_c + dy_c - y_prior_c))^2``
    (:func:`dls_prior_reference`)."""
    rng = np.random.default_rng(6)
    cases = []

    def describe_for(J, dx, y, yp, lam, w, what=""):
        J, dx, y, yp, w = (np.asarray(a, dtype=float) for a in (J, dx, y, yp, w))
        C = J.shape[1]
        slips = {
            "the weights not squared: the penalty is (w_c (y_c + dy_c - prior_c))^2, so W^2 on both sides":
                np.linalg.solve(J.T @ J + lam**2 * np.diag(w), J.T @ dx + lam**2 * np.diag(w) @ (yp - y)),
            "the pull towards y_prior missing from the right-hand side (damping^2 W^2 (y_prior - y))":
                np.linalg.solve(J.T @ J + lam**2 * np.diag(w**2), J.T @ dx),
            "the pull points away from y_prior: it is y_prior - y, not y - y_prior":
                np.linalg.solve(J.T @ J + lam**2 * np.diag(w**2), J.T @ dx + lam**2 * w**2 * (y - yp)),
            "the damping not squared":
                np.linalg.solve(J.T @ J + lam * np.diag(w**2), J.T @ dx + lam * w**2 * (yp - y)),
            "the weights ignored (every control penalised alike)":
                np.linalg.solve(J.T @ J + lam**2 * np.eye(C), J.T @ dx + lam**2 * (yp - y)),
        }

        def describe(got, exp):
            c = int(np.argmax(np.abs(got - exp)))
            said = (f"dy[{c}] is {got[c]:.6g}, expected {exp[c]:.6g} (J {J.shape[0]} x {C}, damping {lam:g}{what})")
            for why, wrong in slips.items():
                if np.allclose(got, wrong, atol=1e-7, rtol=1e-5) and not np.allclose(wrong, exp, atol=1e-7):
                    return said + ": " + why
            return said + ": (J^T J + damping^2 W^2) dy = J^T dx + damping^2 W^2 (y_prior - y)?"
        return describe

    def case(J, dx, y, yp, lam, w, what=""):
        cases.append(((J, dx, y, yp, lam, w), dls_prior_reference(J, dx, y, yp, lam, w),
                      describe_for(J, dx, y, yp, lam, w, what)))
    for M, C, lam in ((9, 4, 0.3), (54, 34, 0.05), (6, 8, 0.5)):    # generic; the lesson's size; wide J
        case(rng.normal(size=(M, C)), rng.normal(size=M), rng.normal(size=C), rng.normal(size=C), lam,
             rng.uniform(0.2, 3.0, C))
    J = rng.normal(size=(7, 5))
    J[:, 3] = 0.0  # an unused control (jaw_open): only the prior moves it, all the way to y_prior
    case(J, rng.normal(size=7), rng.normal(size=5), rng.normal(size=5), 0.2, rng.uniform(0.5, 2.0, 5),
         ", control 3 moves no joint")
    y = rng.normal(size=4)
    case(rng.normal(size=(6, 4)), rng.normal(size=6), y, y.copy(), 0.4, np.array([0.5, 1.0, 2.0, 4.0]),
         ", y already at y_prior")
    case(rng.normal(size=(8, 3)), rng.normal(size=8), rng.normal(size=3), rng.normal(size=3), 0.0,
         np.ones(3), ", no damping: plain least squares")
    case(rng.normal(size=(5, 5)), rng.normal(size=5), rng.normal(size=5), rng.normal(size=5), 30.0,
         rng.uniform(0.5, 2.0, 5), ", heavy damping: dy nearly y_prior - y")
    f32 = [rng.normal(size=(8, 4)), rng.normal(size=8), rng.normal(size=4), rng.normal(size=4)]
    case(*(a.astype(np.float32) for a in f32), 0.2, rng.uniform(0.5, 2.0, 4).astype(np.float32), ", float32")
    return report("check_dls_prior", my_dls_prior, cases, atol=1e-8, forbid=(refine, dls_prior_reference),
                  arg_names=("J", "dx", "y", "y_prior", "damping", "weights"))


__all__ = ["check_gpr_loo", "check_dls_prior"]
