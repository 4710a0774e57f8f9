r"""Jacobian IK by damped least squares (DLS; Wampler 1986, Nakamura & Hanafusa 1986), with position,
rotation and look-at effectors.

Introduced in ``notebooks/01_fabrik.ipynb`` as a baseline next to FABRIK. Conventions:
:mod:`posekit.conventions` (metres, radians, column vectors, world-frame rotation vectors).

The unknowns are one small world-frame rotation vector ``w_i`` (3 columns) per joint ``i`` that may
turn. Turning joint ``i`` by ``w_i`` rotates everything below it about ``p_i``, so to first order

* a joint's position moves by ``dp_e = w_i x (p_e - p_i)`` (``i`` a strict ancestor of ``e``):
  the block ``-[p_e - p_i]_x`` (Buss 2004, Sec. 2: ``ds/dtheta_j = v_j x (s - p_j)``);
* a joint's world rotation turns by ``w_i`` itself, ``dR_e = [w_i]_x R_e`` (``i`` = ``e`` or an
  ancestor): the block ``I``. A **rotation** effector's error is the rotation vector
  ``log(R_t R_e^T)`` (axis times angle, world frame; its length is the geodesic angle), whose
  derivative is ``I`` to first order — the orientation rows of the geometric Jacobian;
* a **look-at** effector with local axis ``a`` and target ``t`` wants ``u = R_e a`` along
  ``v = (t - p_e) / |t - p_e|``. Its error is the chord ``v - u`` (length ``2 sin(angle / 2)``);
  ``du/dw_i = w_i x u``, the block ``-[u]_x``, and, since ``p_e`` moves too,
  ``dv/dw_i = (I - v v^T) [p_e - p_i]_x / |t - p_e|`` for strict ancestors, so the block is
  ``-[u]_x - (I - v v^T) [p_e - p_i]_x / |t - p_e|``.

Stacking every effector's 3 rows (``weight`` times the error, angular rows also times
``angle_scale`` metres per radian so that metres and radians are commensurable — default 0.1: an
angle of 1 rad counts as 10 cm, 1 degree as 1.7 mm, about the 1 mm position tolerance), one step is

    dtheta = J^T (J J^T + lambda^2 I)^-1 dx

(Eq. 10 of Buss 2004, "Introduction to Inverse Kinematics with Jacobian Transpose, Pseudoinverse and
Damped Least Squares methods"): the damping ``lambda`` keeps steps finite near singular (stretched)
poses. Steps are repeated until every effector is within tolerance (the shared error function,
:func:`posekit.ik.effector_errors.errors_into`).
"""

from __future__ import annotations

import numpy as np

from .._jit import njit
from ..skeleton import Skeleton
from ._rigid import fk_one, log_rotation, pose_from, rodrigues, rotatable, rotate_joint, rotations_of
from .api import IKResult, SolverBase, base_index
from .effector_errors import errors_into
from .registry import register

__all__ = ["DLSSolver", "ANGLE_SCALE"]

ANGLE_SCALE = 0.1
"""Metres an angular error of one radian counts as in the DLS rows (1 degree ~ 1.7 mm)."""


@njit
def _error_rows(Pg, Rg, eff_idx, codes, targets, trot, axis, weights, angle_scale, dx, U, V, L):
    """The weighted error rows ``dx`` (3K,); for look-at effectors also ``u``, ``v`` and ``|t - p|``."""
    for k in range(eff_idx.shape[0]):
        e = eff_idx[k]
        if codes[k] == 0:
            for a in range(3):
                dx[3 * k + a] = weights[k] * (targets[k, a] - Pg[e, a])
        elif codes[k] == 1:
            M = np.empty((3, 3))  # R_t R_e^T
            for a in range(3):
                for b in range(3):
                    M[a, b] = trot[k, a, 0] * Rg[e, b, 0] + trot[k, a, 1] * Rg[e, b, 1] + trot[k, a, 2] * Rg[e, b, 2]
            wx, wy, wz = log_rotation(M)
            s = weights[k] * angle_scale
            dx[3 * k] = s * wx
            dx[3 * k + 1] = s * wy
            dx[3 * k + 2] = s * wz
        else:
            for a in range(3):
                U[k, a] = Rg[e, a, 0] * axis[k, 0] + Rg[e, a, 1] * axis[k, 1] + Rg[e, a, 2] * axis[k, 2]
            d0 = targets[k, 0] - Pg[e, 0]
            d1 = targets[k, 1] - Pg[e, 1]
            d2 = targets[k, 2] - Pg[e, 2]
            n = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            if n > 1e-12:
                V[k, 0] = d0 / n
                V[k, 1] = d1 / n
                V[k, 2] = d2 / n
            else:  # on the target: no direction (never at the start; check_look_at)
                for a in range(3):
                    V[k, a] = U[k, a]
            L[k] = max(n, 1e-12)
            s = weights[k] * angle_scale
            for a in range(3):
                dx[3 * k + a] = s * (V[k, a] - U[k, a])


@njit
def _dls(Rl, root_pos, local_pos, parents, cols, ancestor, eff_idx, codes, targets, trot, axis, tols, weights,
         angle_scale, damping, max_step, max_iter):
    J = parents.shape[0]
    K = eff_idx.shape[0]
    n = cols.shape[0]
    Rg = np.empty((J, 3, 3))
    Pg = np.empty((J, 3))
    fk_one(parents, local_pos, Rl, root_pos, Rg, Pg)
    Jac = np.zeros((3 * K, 3 * n))
    dx = np.zeros(3 * K)
    err = np.empty(K)
    U = np.zeros((K, 3))
    V = np.zeros((K, 3))
    L = np.ones(K)
    B = np.empty((3, 3))
    it = 0
    while True:
        errors_into(Pg, Rg, eff_idx, codes, targets, trot, axis, err)
        done = True
        for k in range(K):
            if err[k] > tols[k]:
                done = False
        if done or it >= max_iter:
            return Pg, Rg, it, done
        _error_rows(Pg, Rg, eff_idx, codes, targets, trot, axis, weights, angle_scale, dx, U, V, L)
        Jac[:] = 0.0
        for k in range(K):
            e = eff_idx[k]
            for c in range(n):
                a = ancestor[k, c]  # 0: does not move effector k, 1: a strict ancestor, 2: the joint itself
                if a == 0:
                    continue
                r = Pg[e] - Pg[cols[c]]
                if codes[k] == 0:
                    # column a of the block is (axis_a x r): the block is -[r]_x
                    w = weights[k]
                    Jac[3 * k + 0, 3 * c + 1] = w * r[2]
                    Jac[3 * k + 0, 3 * c + 2] = -w * r[1]
                    Jac[3 * k + 1, 3 * c + 0] = -w * r[2]
                    Jac[3 * k + 1, 3 * c + 2] = w * r[0]
                    Jac[3 * k + 2, 3 * c + 0] = w * r[1]
                    Jac[3 * k + 2, 3 * c + 1] = -w * r[0]
                elif codes[k] == 1:
                    s = weights[k] * angle_scale
                    for i in range(3):
                        Jac[3 * k + i, 3 * c + i] = s
                else:
                    s = weights[k] * angle_scale
                    # -[u]_x
                    B[0, 0] = 0.0
                    B[0, 1] = U[k, 2]
                    B[0, 2] = -U[k, 1]
                    B[1, 0] = -U[k, 2]
                    B[1, 1] = 0.0
                    B[1, 2] = U[k, 0]
                    B[2, 0] = U[k, 1]
                    B[2, 1] = -U[k, 0]
                    B[2, 2] = 0.0
                    if a == 1:  # the joint moves too: - (I - v v^T) [r]_x / |t - p|
                        for col in range(3):
                            # [r]_x e_col = r x e_col
                            ex = 1.0 if col == 0 else 0.0
                            ey = 1.0 if col == 1 else 0.0
                            ez = 1.0 if col == 2 else 0.0
                            qx = r[1] * ez - r[2] * ey
                            qy = r[2] * ex - r[0] * ez
                            qz = r[0] * ey - r[1] * ex
                            vq = V[k, 0] * qx + V[k, 1] * qy + V[k, 2] * qz
                            B[0, col] -= (qx - V[k, 0] * vq) / L[k]
                            B[1, col] -= (qy - V[k, 1] * vq) / L[k]
                            B[2, col] -= (qz - V[k, 2] * vq) / L[k]
                    for i in range(3):
                        for m in range(3):
                            Jac[3 * k + i, 3 * c + m] = s * B[i, m]
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


class DLSSolver(SolverBase):
    """Damped-least-squares Jacobian IK behind the :class:`~posekit.ik.api.Solver` interface:
    position, rotation and look-at effectors (the module docstring has the Jacobian rows).

    Parameters
    ----------
    skeleton : Skeleton
    damping : float, metres
        lambda in the step above; larger is steadier and slower.
    max_iter : int
    max_step : float, radians
        Largest rotation-vector component per step.
    base : str, optional
        Joint whose position stays fixed (default the pelvis role); it may still turn. A position effector on
        it moves the start as a whole onto its target first (:func:`posekit.ik.api.base_on_target`).
    angle_scale : float, metres per radian
        Weight of the angular rows relative to position rows (:data:`ANGLE_SCALE`).
    """

    name = "dls"
    kinds = ("position", "rotation", "look_at")
    needs_start = True

    def __init__(self, skeleton: Skeleton, damping: float = 0.05, max_iter: int = 100, max_step: float = 0.3,
                 base: str | None = None, angle_scale: float = ANGLE_SCALE):
        self.skeleton = skeleton
        self.damping = float(damping)
        self.max_iter = int(max_iter)
        self.max_step = float(max_step)
        self.base = base_index(skeleton, base)
        if not angle_scale > 0:
            raise ValueError(f"angle_scale must be a positive number of metres per radian, got {angle_scale!r}")
        self.angle_scale = float(angle_scale)

    def _solve(self, start, res) -> IKResult:
        Rl, root, local_pos = rotations_of(self.skeleton, start, "DLS")
        turns_self = res.codes != 0
        movable = rotatable(self.skeleton, res.joints, self.base, turns_self)
        cols = np.nonzero(movable)[0].astype(np.int64)
        ancestor = np.zeros((len(res), len(cols)), dtype=np.int8)
        for k, e in enumerate(res.joints):
            chain = set(self.skeleton.chain(int(e), 0)[:-1])
            ancestor[k] = [1 if c in chain else (2 if c == e and turns_self[k] else 0) for c in cols]
        Pg, Rg, it, _ = _dls(Rl, root, local_pos, self.skeleton.parents, cols, ancestor, res.joints, res.codes,
                             np.ascontiguousarray(res.position), res.rotation, res.axis, res.tolerance, res.weight,
                             self.angle_scale, self.damping, self.max_step, self.max_iter)
        return self.result(pose_from(Rl, root, Pg, start.local_pos), res, it, global_rot=Rg)


register("dls", DLSSolver, kinds=DLSSolver.kinds, needs_start=True,
         description="Damped least squares on the Jacobian; position, rotation and look-at effectors",
         lesson="notebooks/01_fabrik.ipynb")
