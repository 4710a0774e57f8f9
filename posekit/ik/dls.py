"""Jacobian IK by damped least squares (DLS; Wampler 1986, Nakamura & Hanafusa 1986).

Introduced in ``notebooks/01_fabrik.ipynb`` as a baseline next to FABRIK. Conventions:
:mod:`posekit.conventions`.

Each joint ``i`` that can move an effector gets three columns in the Jacobian: turning it by a small
rotation vector ``w`` about world axes moves effector ``e`` by ``w x (p_e - p_i)``. With the stacked
effector errors ``dx`` (targets minus positions, weighted) one step is

    dtheta = J^T (J J^T + lambda^2 I)^-1 dx

(Eq. 10 of Buss 2004, "Introduction to Inverse Kinematics with Jacobian Transpose, Pseudoinverse and
Damped Least Squares methods"): the damping ``lambda`` keeps steps finite near singular (stretched)
poses. Steps are repeated until every effector is within tolerance.
"""

from __future__ import annotations

import numpy as np

from .._jit import njit
from ..skeleton import Skeleton
from ._rigid import fk_one, pose_from, rodrigues, rotatable, rotate_joint, rotations_of
from .api import IKResult, Pose, base_index, resolve_effectors

__all__ = ["DLSSolver"]


@njit
def _dls(Rl, root_pos, local_pos, parents, cols, ancestor, eff_idx, targets, tols, weights, damping,
         max_step, max_iter):
    J = parents.shape[0]
    K = eff_idx.shape[0]
    n = cols.shape[0]
    Rg = np.empty((J, 3, 3))
    Pg = np.empty((J, 3))
    fk_one(parents, local_pos, Rl, root_pos, Rg, Pg)
    Jac = np.zeros((3 * K, 3 * n))
    dx = np.zeros(3 * K)
    it = 0
    while True:
        done = True
        for k in range(K):
            d = targets[k] - Pg[eff_idx[k]]
            if np.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2) > tols[k]:
                done = False
            dx[3 * k:3 * k + 3] = weights[k] * d
        if done or it >= max_iter:
            return Pg, it, done
        Jac[:] = 0.0
        for k in range(K):
            e = eff_idx[k]
            for c in range(n):
                if ancestor[k, c]:
                    r = Pg[e] - Pg[cols[c]]
                    # column a of the block is (axis_a x r): the block is -[r]_x
                    w = weights[k]
                    Jac[3 * k + 0, 3 * c + 1] = w * r[2]
                    Jac[3 * k + 0, 3 * c + 2] = -w * r[1]
                    Jac[3 * k + 1, 3 * c + 0] = -w * r[2]
                    Jac[3 * k + 1, 3 * c + 2] = w * r[0]
                    Jac[3 * k + 2, 3 * c + 0] = w * r[1]
                    Jac[3 * k + 2, 3 * c + 1] = -w * r[0]
        A = Jac @ Jac.T + damping * damping * np.eye(3 * K)
        dtheta = Jac.T @ np.linalg.solve(A, dx)
        big = np.abs(dtheta).max()
        if big > max_step:
            dtheta *= max_step / big
        # turn parents after children so each uses this iteration's parent frame (first order)
        for c in range(n - 1, -1, -1):
            j = cols[c]
            rotate_joint(Rl, Rg, parents, j, rodrigues(dtheta[3 * c], dtheta[3 * c + 1], dtheta[3 * c + 2]))
        fk_one(parents, local_pos, Rl, root_pos, Rg, Pg)
        it += 1


class DLSSolver:
    """Damped-least-squares Jacobian IK behind the :class:`~posekit.ik.api.Solver` interface.

    Parameters
    ----------
    skeleton : Skeleton
    damping : float, metres
        lambda in the step above; larger is steadier and slower.
    max_iter : int
    max_step : float, radians
        Largest rotation-vector component per step.
    base : str, optional
        Joint whose position stays fixed (default the pelvis role); it may still turn.
    """

    name = "dls"

    def __init__(self, skeleton: Skeleton, damping: float = 0.05, max_iter: int = 100, max_step: float = 0.3,
                 base: str | None = None):
        self.skeleton = skeleton
        self.damping = float(damping)
        self.max_iter = int(max_iter)
        self.max_step = float(max_step)
        self.base = base_index(skeleton, base)

    def solve(self, start: Pose, effectors) -> IKResult:
        Rl, root, local_pos = rotations_of(self.skeleton, start, "DLS")
        idx, targets, tols, weights = resolve_effectors(self.skeleton, effectors)
        movable = rotatable(self.skeleton, idx, self.base)
        cols = np.nonzero(movable)[0].astype(np.int64)
        ancestor = np.zeros((len(idx), len(cols)), dtype=np.bool_)
        for k, e in enumerate(idx):
            chain = set(self.skeleton.chain(int(e), 0)[:-1])
            ancestor[k] = [c in chain for c in cols]
        Pg, it, done = _dls(Rl, root, local_pos, self.skeleton.parents, cols, ancestor, idx.astype(np.int64),
                            np.ascontiguousarray(targets), tols, weights, self.damping, self.max_step,
                            self.max_iter)
        err = np.linalg.norm(Pg[idx] - targets, axis=1)
        return IKResult(pose_from(Rl, root, local_pos, Pg, self.skeleton, start), bool(np.all(err <= tols)), int(it), err)
