"""Reference solutions of lesson 02's exercises (instructor version; ``posekit exercises solutions 02`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_gpr_loo", "exercise_dls_prior"]


def exercise_gpr_loo(X, Y, theta0, theta1):
    """Leave-one-out predictions of the multiquadric GP mean (Holden et al. 2017, Eqs. 2-3), from one solve.

    With ``G = K + theta1 I`` and ``alpha = G^-1 Y``, the mean fitted without pose ``i``, at ``x_i``, is
    ``y_i - alpha_i / (G^-1)_ii`` (Rasmussen & Williams 2006, Eq. 5.12; block inversion of ``G``, which needs ``G``
    symmetric and invertible, not positive definite: the multiquadric's ``G`` qualifies). One factorisation
    replaces N fits.

    Parameters
    ----------
    X : ndarray, shape (N, D)
        Training inputs (already normalised, or not: no normalisation here).
    Y : ndarray, shape (N, O)
        Training outputs.
    theta0 : float
        The kernel's offset, ``k(a, b) = sqrt(|a - b|^2 + theta0^2)``.
    theta1 : float
        The regulariser on the diagonal.

    Returns
    -------
    ndarray, shape (N, O)
        Row ``i``: the prediction at ``X[i]`` of the GP fitted on every other row.
    """
    import numpy as np
    import scipy.linalg

    X, Y = np.asarray(X, dtype=float), np.asarray(Y, dtype=float)
    d2 = ((X[:, None, :] - X[None, :, :]) ** 2).sum(-1)
    G = np.sqrt(d2 + theta0**2) + theta1 * np.eye(len(X))
    G_inv = scipy.linalg.inv(G)   # the diagonal of the inverse is needed, so here the inverse is the tool
    alpha = G_inv @ Y
    return Y - alpha / np.diag(G_inv)[:, None]


def exercise_dls_prior(J, dx, y, y_prior, damping, weights):
    """A damped-least-squares step with each control's own scale and a pull towards a prior (a learned guess).

    Minimises ``|J dy - dx|^2 + damping^2 |W (y + dy - y_prior)|^2`` with ``W = diag(weights)``. Setting the
    gradient to zero gives ``(J^T J + damping^2 W^2) dy = J^T dx + damping^2 W^2 (y_prior - y)``: section 5's step
    when every weight is 1 and ``y`` is already ``y_prior``. A control that moves no joint goes all the way to its
    prior; a redundant pair is split as the prior splits it.

    Parameters
    ----------
    J : ndarray, shape (M, C)
        The rig's Jacobian at ``y``.
    dx : ndarray, shape (M,)
        The joint error ``x_* - f(y)``.
    y, y_prior : ndarray, shape (C,)
        The current controls and the prior (the regression's guess).
    damping : float
    weights : ndarray, shape (C,)
        Each control's weight (e.g. 1 / its training standard deviation).

    Returns
    -------
    ndarray, shape (C,)
    """
    import numpy as np

    J, dx, y, y_prior, w = (np.asarray(a, dtype=float) for a in (J, dx, y, y_prior, weights))
    W2 = np.diag(w**2)
    return np.linalg.solve(J.T @ J + damping**2 * W2, J.T @ dx + damping**2 * W2 @ (y_prior - y))
