"""Cyclic Coordinate Descent (CCD) IK on joint rotations (Wang & Chen 1991; Kenwright 2012).

Introduced in ``notebooks/01_fabrik.ipynb`` as a baseline next to FABRIK. Conventions:
:mod:`posekit.conventions`.

For each effector in turn, walk from its parent joint up to the base; at each joint ``i`` turn it by
the shortest rotation that takes the direction to the end effector, ``e - p_i``, onto the direction
to the target, ``t - p_i``. Repeat the sweeps until every effector is within tolerance. Bone lengths
are exact by construction (only rotations change); the base keeps its position (the start is first moved
as a whole onto a position effector on it, when there is one: :func:`posekit.ik.api.base_on_target`).

CCD here honours position effectors only (``kinds = ("position",)``): a rotation goal would need a
second, competing turn per joint and a rule for sharing it, which is what the Jacobian of
:mod:`posekit.ik.dls` does properly. Use ``"dls"`` for rotation and look-at effectors.
"""

from __future__ import annotations

import numpy as np

from .._jit import njit
from ..skeleton import Skeleton
from ._rigid import fk_one, pose_from, rotatable, rotate_joint, rotation_between, rotations_of
from .api import IKResult, SolverBase, base_index
from .effector_errors import errors_into
from .registry import register

__all__ = ["CCDSolver"]


@njit
def _ccd(Rl, root_pos, local_pos, parents, movable, eff_idx, codes, targets, trot, axis, tols, max_iter):
    J = parents.shape[0]
    K = eff_idx.shape[0]
    Rg = np.empty((J, 3, 3))
    Pg = np.empty((J, 3))
    err = np.empty(K)
    fk_one(parents, local_pos, Rl, root_pos, Rg, Pg)
    it = 0
    while True:
        errors_into(Pg, Rg, eff_idx, codes, targets, trot, axis, err)
        done = True
        for k in range(K):
            if err[k] > tols[k]:
                done = False
        if done or it >= max_iter:
            return Pg, Rg, it, done
        for k in range(K):
            e = eff_idx[k]
            j = parents[e]
            while j >= 0 and movable[j]:
                R = rotation_between(Pg[e] - Pg[j], targets[k] - Pg[j])
                rotate_joint(Rl, Rg, parents, j, R)
                fk_one(parents, local_pos, Rl, root_pos, Rg, Pg)
                j = parents[j]
        it += 1


class CCDSolver(SolverBase):
    """CCD behind the :class:`~posekit.ik.api.Solver` interface; needs a start pose with rotations.

    Parameters
    ----------
    skeleton : Skeleton
    max_iter : int
        Sweeps over all effectors.
    base : str, optional
        Joint whose position stays fixed (default the pelvis role); it may still turn.
        A position effector on it moves the start as a whole onto its target first
        (:func:`posekit.ik.api.base_on_target`).
    """

    name = "ccd"
    kinds = ("position",)
    needs_start = True

    def __init__(self, skeleton: Skeleton, max_iter: int = 50, base: str | None = None):
        self.skeleton = skeleton
        self.max_iter = int(max_iter)
        self.base = base_index(skeleton, base)

    def _solve(self, start, res) -> IKResult:
        Rl, root, local_pos = rotations_of(self.skeleton, start, "CCD")
        movable = rotatable(self.skeleton, res.joints, self.base)
        Pg, Rg, it, _ = _ccd(Rl, root, local_pos, self.skeleton.parents, movable, res.joints, res.codes,
                             np.ascontiguousarray(res.position), res.rotation, res.axis, res.tolerance, self.max_iter)
        return self.result(pose_from(Rl, root, Pg, start.local_pos), res, it, global_rot=Rg)


register("ccd", CCDSolver, kinds=CCDSolver.kinds, needs_start=True,
         description="Cyclic Coordinate Descent: turn each joint towards its target, sweep after sweep",
         lesson="notebooks/01_fabrik.ipynb")
