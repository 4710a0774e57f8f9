"""Reference solutions of lesson 02's exercises (instructor version; ``posekit exercises solutions 02`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_gpr_mean", "exercise_dls_step"]


def exercise_gpr_mean(X, Y, Xq, theta0, theta1):
    """Posterior mean of Gaussian-process regression with the multiquadric kernel (Holden et al. 2017, Eqs. 2-3).

    ``y(Xq) = k(Xq, X) (K + theta1 I)^-1 Y`` with ``K_ij = k(x_i, x_j) = sqrt(|x_i - x_j|^2 + theta0^2)``. No
    normalisation here (the caller z-scores). The system is solved once, never inverted; the multiquadric
    kernel is not positive definite, so it is solved as symmetric indefinite (LDL^T), not by Cholesky.

    Parameters
    ----------
    X : ndarray, shape (N, D)
        Training inputs.
    Y : ndarray, shape (N, O)
        Training outputs.
    Xq : ndarray, shape (M, D)
        Query inputs.
    theta0 : float
        Kernel parameter (in the inputs' units).
    theta1 : float
        Regularisation added to the diagonal.

    Returns
    -------
    ndarray, shape (M, O)
    """
    import numpy as np
    import scipy.linalg

    def multiquadric(A, B):
        # all pairwise squared distances between the rows of A (n, D) and of B (m, D): shape (n, m)
        sq = ((A[:, None, :] - B[None, :, :]) ** 2).sum(axis=-1)
        return np.sqrt(sq + theta0**2)

    K = multiquadric(X, X) + theta1 * np.eye(len(X))
    alpha = scipy.linalg.solve(K, Y, assume_a="sym")  # alpha = (K + theta1 I)^-1 Y
    return multiquadric(Xq, X) @ alpha


def exercise_dls_step(J, dx, damping):
    """One damped-least-squares step (Holden et al. 2017, Sec. 5; Buss 2004).

    ``dy = (J^T J + lambda^2 I)^-1 J^T dx``: the control change that best explains the joint-position
    change ``dx``, with the damping keeping the step finite where ``J^T J`` is (nearly) singular.

    Parameters
    ----------
    J : ndarray, shape (X, C)
        Jacobian of the rig's joint coordinates with respect to its controls.
    dx : ndarray, shape (X,)
        Wanted change of the joint coordinates, ``x* - f(y)``.
    damping : float
        ``lambda``; it is squared on the diagonal.

    Returns
    -------
    ndarray, shape (C,)
    """
    import numpy as np

    C = J.shape[1]
    A = J.T @ J + damping**2 * np.eye(C)
    return np.linalg.solve(A, J.T @ dx)  # solve the linear system rather than inverting A
