"""Cyclic Coordinate Descent (CCD) IK on joint rotations (Wang & Chen 1991; Kenwright 2012).

Introduced in ``notebooks/01_fabrik.ipynb`` as a baseline next to FABRIK. Conventions:
:mod:`posekit.conventions`.

For each effector in turn, walk from its parent joint up to the base; at each joint ``i`` turn it by
the shortest rotation that takes the direction to the end effector, ``e - p_i``, onto the direction
to the target, ``t - p_i``. Repeat the sweeps until every effector is within tolerance. Bone lengths
are exact by construction (only rotations change); the base keeps its position.
"""

from __future__ import annotations

import numpy as np

from .._jit import njit
from ..skeleton import Skeleton
from ._rigid import fk_one, pose_from, rotatable, rotate_joint, rotation_between, rotations_of
from .api import IKResult, Pose, base_index, resolve_effectors

__all__ = ["CCDSolver"]


@njit
def _ccd(Rl, root_pos, local_pos, parents, movable, eff_idx, targets, tols, max_iter):
    J = parents.shape[0]
    K = eff_idx.shape[0]
    Rg = np.empty((J, 3, 3))
    Pg = np.empty((J, 3))
    fk_one(parents, local_pos, Rl, root_pos, Rg, Pg)
    it = 0
    while True:
        done = True
        for k in range(K):
            d = Pg[eff_idx[k]] - targets[k]
            if np.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2) > tols[k]:
                done = False
        if done or it >= max_iter:
            return Pg, it, done
        for k in range(K):
            e = eff_idx[k]
            j = parents[e]
            while j >= 0 and movable[j]:
                R = rotation_between(Pg[e] - Pg[j], targets[k] - Pg[j])
                rotate_joint(Rl, Rg, parents, j, R)
                fk_one(parents, local_pos, Rl, root_pos, Rg, Pg)
                j = parents[j]
        it += 1


class CCDSolver:
    """CCD behind the :class:`~posekit.ik.api.Solver` interface; needs a start pose with rotations.

    Parameters
    ----------
    skeleton : Skeleton
    max_iter : int
        Sweeps over all effectors.
    base : str, optional
        Joint whose position stays fixed (default the pelvis role); it may still turn.
    """

    name = "ccd"

    def __init__(self, skeleton: Skeleton, max_iter: int = 50, base: str | None = None):
        self.skeleton = skeleton
        self.max_iter = int(max_iter)
        self.base = base_index(skeleton, base)

    def solve(self, start: Pose, effectors) -> IKResult:
        Rl, root, local_pos = rotations_of(self.skeleton, start, "CCD")
        idx, targets, tols, _ = resolve_effectors(self.skeleton, effectors)
        movable = rotatable(self.skeleton, idx, self.base)
        Pg, it, done = _ccd(Rl, root, local_pos, self.skeleton.parents, movable, idx.astype(np.int64),
                            np.ascontiguousarray(targets), tols, self.max_iter)
        err = np.linalg.norm(Pg[idx] - targets, axis=1)
        return IKResult(pose_from(Rl, root, local_pos, Pg, self.skeleton, start), bool(np.all(err <= tols)), int(it), err)
