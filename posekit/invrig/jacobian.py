"""Jacobian refinement of an inverse rig mapping (Holden, Saito & Komura 2017, Sec. 5).

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb``. Given joint positions ``x*`` and a first
guess of the controls ``y`` (from GPR or the network), iterate damped least squares on the rig
function ``f``::

    dx = x* - f(y),    dy = (J^T J + lambda^2 I)^-1 J^T dx,    y <- y + dy

with ``J = df/dy`` either *computed* by finite differences of the rig (C + 1 rig evaluations per
frame and step, central: 2C) or *learned*: GPR trained on finite-difference Jacobians at the
subsampled training poses, predicting ``J`` from ``y`` without touching the rig.
"""

from __future__ import annotations

import warnings

import numpy as np

from .gpr import GPR

__all__ = ["refine", "LearnedJacobian"]


def refine(rig, x_target, y0, jacobian="computed", iterations: int = 3, damping: float = 0.05):
    """Damped-least-squares refinement of controls.

    Parameters
    ----------
    rig : HumanoidRig
    x_target : ndarray, shape (N, J, 3), metres
    y0 : ndarray, shape (N, C)
        First guess (clamped to the rig's ranges before the first step).
    jacobian : "computed" or callable
        ``"computed"`` uses the rig's finite differences; a callable maps y (N, C) -> J (N, 3J, C).
    iterations : int
    damping : float
        lambda.

    Returns
    -------
    ndarray, shape (N, C), clamped to the rig's ranges.
    """
    x_target = np.asarray(x_target, dtype=float).reshape(len(y0), -1)
    y = np.clip(np.array(y0, dtype=float), rig.low, rig.high)  # the rig would clamp the guess anyway
    C = y.shape[1]
    computed = isinstance(jacobian, str) and jacobian == "computed"
    for _ in range(iterations):
        if computed:  # the rig at y and its Jacobian in one call (y is in range: no clamp to do)
            x, J = rig.jacobian(y, value=True)
        else:
            x, J = rig.evaluate(y).reshape(len(y), -1), jacobian(y)
        dx = x_target - x
        JT = np.swapaxes(J, 1, 2)
        A = JT @ J + damping**2 * np.eye(C)
        y = np.clip(y + np.linalg.solve(A, (JT @ dx[..., None]))[..., 0], rig.low, rig.high)
    return y


class LearnedJacobian:
    """GPR from controls to the (flattened) Jacobian, trained at given control vectors.

    Parameters
    ----------
    rig : HumanoidRig
    Y : ndarray, shape (M, C)
        Controls at which to compute finite-difference Jacobians for training (the subsampled set).
    theta0, theta1, kernel : GPR settings.
    """

    def __init__(self, rig, Y, theta0: float = 1.0, theta1: float = 1e-3, kernel: str = "multiquadric"):
        self.rig = rig
        Y = np.asarray(Y, dtype=float)
        J = rig.jacobian(Y)
        self.shape = J.shape[1:]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            self.gpr = GPR(kernel, theta0, theta1).fit(Y, J.reshape(len(Y), -1))

    def __call__(self, y):
        y = np.asarray(y, dtype=float)
        return self.gpr.predict(y).reshape((len(y),) + self.shape)
