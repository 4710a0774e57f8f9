"""FABRIK — Forward And Backward Reaching Inverse Kinematics (Aristidou & Lasenby 2011).

Introduced in ``notebooks/01_fabrik.ipynb``, where the single chain is derived step by step.
Units and axes: :mod:`posekit.conventions` (metres, Y up, facing +Z).

* :func:`fabrik_chain` — one chain, readable numpy (Algorithm 1 of the paper): the backward pass
  puts the end on the target and walks to the base keeping bone lengths, the forward pass puts
  the base back and walks out again. An unreachable target stretches the chain straight at it.
* :class:`FabrikSolver` — the whole body with several end effectors (Sec. 4.2 of the paper): the
  backward pass runs from every effector towards the base; a *sub-base* (a joint where chains
  meet, e.g. the chest) goes to the centroid of the positions its chains propose; the forward pass
  then runs from the fixed base (the pelvis) outwards. Optional joint constraints (Sec. 5): cone
  limits on a bone's angle to its parent bone (shoulders, hips, elbows, knees) and a hinge rule
  that knees do not bend forward. The kernel is compiled with numba.
* :func:`fix_bone_lengths` — the backward pass alone, which restores bone lengths of predicted
  positions (the post-processing of Victor & Meyer 2020, Sec. 3.4).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._jit import njit
from ..skeleton import Skeleton
from .api import IKResult, Pose, base_index, check_pose, resolve_effectors

__all__ = ["fabrik_chain", "FabrikSolver", "Constraints", "default_constraints", "fix_bone_lengths",
           "chain_lengths"]


# ---------------------------------------------------------------------------------------- one chain
def chain_lengths(positions) -> np.ndarray:
    """Bone lengths of a chain of joint positions (n+1, 3) -> (n,)."""
    positions = np.asarray(positions, dtype=float)
    return np.linalg.norm(np.diff(positions, axis=0), axis=1)


def fabrik_chain(positions, target, tolerance: float = 1e-3, max_iter: int = 20, return_history: bool = False):
    """FABRIK on a single chain (Algorithm 1 of Aristidou & Lasenby 2011).

    Parameters
    ----------
    positions : ndarray, shape (n+1, 3), metres
        Joint positions from the base (index 0, stays fixed) to the end effector (index n).
    target : ndarray, shape (3,), metres
    tolerance : float, metres
        Stop when the end is this close to the target.
    max_iter : int
    return_history : bool
        Also return the positions after every iteration (for figures).

    Returns
    -------
    positions : ndarray, shape (n+1, 3)
    converged : bool
        False for an unreachable target (the chain is then stretched straight towards it).
    iterations : int
    history : list of ndarray, only with ``return_history``
    """
    p = np.array(positions, dtype=float)
    t = np.asarray(target, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 2:
        raise ValueError(f"positions: expected shape (n+1, 3) with n >= 1, got {p.shape}")
    if t.shape != (3,) or not np.all(np.isfinite(t)) or not np.all(np.isfinite(p)):
        raise ValueError("target must be 3 finite numbers and positions finite")
    d = chain_lengths(p)
    if np.any(d < 1e-9):
        raise ValueError(f"zero-length bone in the chain (bone {int(np.argmin(d))})")
    history = [p.copy()]
    base = p[0].copy()
    if np.linalg.norm(t - base) > d.sum():  # unreachable: stretch towards the target
        for i in range(len(d)):
            u = (t - p[i]) / np.linalg.norm(t - p[i])
            p[i + 1] = p[i] + d[i] * u
        history.append(p.copy())
        out = (p, False, 1)
        return out + (history,) if return_history else out
    it = 0
    while np.linalg.norm(p[-1] - t) > tolerance and it < max_iter:
        p[-1] = t  # backward: end on the target, walk to the base
        for i in range(len(d) - 1, -1, -1):
            u = p[i] - p[i + 1]
            p[i] = p[i + 1] + d[i] * u / np.linalg.norm(u)
        p[0] = base  # forward: base back in place, walk to the end
        for i in range(len(d)):
            u = p[i + 1] - p[i]
            p[i + 1] = p[i] + d[i] * u / np.linalg.norm(u)
        it += 1
        history.append(p.copy())
    out = (p, bool(np.linalg.norm(p[-1] - t) <= tolerance), it)
    return out + (history,) if return_history else out


# ---------------------------------------------------------------------------------------- full body
@dataclass
class Constraints:
    """Joint limits for :class:`FabrikSolver` (Sec. 5 of Aristidou & Lasenby 2011, simplified to
    circular cones).

    Attributes
    ----------
    max_angle : dict
        Joint name -> largest angle (radians) between the bone parent->joint and the extension of the
        parent's own bone. On the elbow's child (the wrist) it limits how far the elbow folds; on the
        elbow it bounds the upper arm's cone at the shoulder.
    no_forward_bend : tuple of str
        Joints whose bone may only fold one way relative to the parent bone (the ankles: knees are
        hinges that fold backwards). With ``lat`` the right-to-left hip vector and ``e`` the parent
        bone, the bone ``u`` must satisfy ``u . (lat x e) >= -sin 15deg`` (15 deg of slack for leg
        twist, which positions alone cannot see); otherwise it is mirrored.
    """

    max_angle: dict = field(default_factory=dict)
    no_forward_bend: tuple = ()


def default_constraints(skeleton: Skeleton) -> Constraints:
    """Limits for a humanoid with the standard roles, fitted to the DeepMimic clips (every frame of
    the shipped sample satisfies them; ``notebooks/01_fabrik.ipynb`` measures this):
    shoulder cone 150 deg, hip cone 125 deg, elbow fold 160 deg, knee fold 165 deg, and knees fold
    backwards (the data's largest values: 149, 107, 139 and 158 deg; a wrong-way knee bend of at most
    13 deg)."""
    deg = np.radians
    limits = {}
    for side in ("left", "right"):
        for role, angle in ((f"{side}_elbow", 150), (f"{side}_knee", 125), (f"{side}_hand", 160),
                            (f"{side}_foot", 165)):
            if role in skeleton.roles:
                limits[skeleton.roles[role]] = deg(angle)
    no_fwd = tuple(skeleton.roles[r] for r in ("left_foot", "right_foot") if r in skeleton.roles)
    return Constraints(limits, no_fwd)


_HINGE_SLACK = np.sin(np.radians(15.0))


@njit
def _fabrik_tree(pos, parents, lengths, child_start, child_idx, active, fixed, slot, eff_idx, targets, tols,
                 max_iter, limit_cos, no_fwd, left_hip, right_hip, use_constraints, sub_eff, sub_reach):
    """Full-body FABRIK in place on ``pos`` (J, 3). Returns (iterations, converged)."""
    J = pos.shape[0]
    K = targets.shape[0]
    back = pos.copy()
    it = 0
    while True:
        done = True
        for k in range(K):
            j = eff_idx[k]
            dx = pos[j, 0] - targets[k, 0]
            dy = pos[j, 1] - targets[k, 1]
            dz = pos[j, 2] - targets[k, 2]
            if dx * dx + dy * dy + dz * dz > tols[k] * tols[k]:
                done = False
        if done or it >= max_iter:
            return it, done
        # ---- backward: effectors to their targets, sub-bases to the centroid of proposals
        for j in range(J - 1, -1, -1):
            if fixed[j] or not active[j]:
                back[j, 0] = pos[j, 0]
                back[j, 1] = pos[j, 1]
                back[j, 2] = pos[j, 2]
                continue
            if slot[j] >= 0:
                back[j, 0] = targets[slot[j], 0]
                back[j, 1] = targets[slot[j], 1]
                back[j, 2] = targets[slot[j], 2]
                continue
            ax = 0.0
            ay = 0.0
            az = 0.0
            n = 0.0
            for ci in range(child_start[j], child_start[j + 1]):
                c = child_idx[ci]
                if not active[c]:
                    continue
                ux = pos[j, 0] - back[c, 0]
                uy = pos[j, 1] - back[c, 1]
                uz = pos[j, 2] - back[c, 2]
                L = np.sqrt(ux * ux + uy * uy + uz * uz)
                if L < 1e-12:
                    ux = pos[j, 0] - pos[c, 0]
                    uy = pos[j, 1] - pos[c, 1]
                    uz = pos[j, 2] - pos[c, 2]
                    L = np.sqrt(ux * ux + uy * uy + uz * uz)
                s = lengths[c] / L
                # weight of this chain's proposal: the less slack the chain has left to reach its
                # effector from here, the more it decides where the sub-base goes
                e = sub_eff[c]
                tx = targets[e, 0] - pos[j, 0]
                ty = targets[e, 1] - pos[j, 1]
                tz = targets[e, 2] - pos[j, 2]
                slack = sub_reach[c] - np.sqrt(tx * tx + ty * ty + tz * tz)
                w = 1.0 / (max(slack, 0.0) + 0.01)
                ax += w * (back[c, 0] + ux * s)
                ay += w * (back[c, 1] + uy * s)
                az += w * (back[c, 2] + uz * s)
                n += w
            back[j, 0] = ax / n
            back[j, 1] = ay / n
            back[j, 2] = az / n
        # ---- forward: from the fixed base outwards, keeping bone lengths
        for j in range(J):
            if fixed[j]:
                continue
            p = parents[j]
            if active[j]:
                ux = back[j, 0] - pos[p, 0]
                uy = back[j, 1] - pos[p, 1]
                uz = back[j, 2] - pos[p, 2]
            else:
                ux = pos[j, 0] - pos[p, 0]
                uy = pos[j, 1] - pos[p, 1]
                uz = pos[j, 2] - pos[p, 2]
            L = np.sqrt(ux * ux + uy * uy + uz * uz)
            if L < 1e-12:
                ux, uy, uz, L = 0.0, 1.0, 0.0, 1.0
            ux /= L
            uy /= L
            uz /= L
            if use_constraints and parents[p] >= 0:
                g = parents[p]
                ex = pos[p, 0] - pos[g, 0]
                ey = pos[p, 1] - pos[g, 1]
                ez = pos[p, 2] - pos[g, 2]
                eL = np.sqrt(ex * ex + ey * ey + ez * ez)
                if eL > 1e-12:
                    ex /= eL
                    ey /= eL
                    ez /= eL
                    if no_fwd[j] and left_hip >= 0:
                        # hinge rule: with lat = left hip - right hip and f = lat x e (the side a
                        # knee folds to), a bone bending the wrong way (u.f < -sin 15 deg) is
                        # mirrored to the right side
                        lx = pos[left_hip, 0] - pos[right_hip, 0]
                        ly = pos[left_hip, 1] - pos[right_hip, 1]
                        lz = pos[left_hip, 2] - pos[right_hip, 2]
                        px = ly * ez - lz * ey
                        py = lz * ex - lx * ez
                        pz = lx * ey - ly * ex
                        pL = np.sqrt(px * px + py * py + pz * pz)
                        if pL > 1e-12:
                            px /= pL
                            py /= pL
                            pz /= pL
                            s = ux * px + uy * py + uz * pz
                            if s < -_HINGE_SLACK:
                                ux -= 2.0 * s * px
                                uy -= 2.0 * s * py
                                uz -= 2.0 * s * pz
                    cosang = ux * ex + uy * ey + uz * ez
                    if cosang < limit_cos[j]:  # outside the cone: rotate onto its rim
                        vx = ux - cosang * ex
                        vy = uy - cosang * ey
                        vz = uz - cosang * ez
                        vL = np.sqrt(vx * vx + vy * vy + vz * vz)
                        if vL < 1e-12:  # pointing straight back: any perpendicular will do
                            vx, vy, vz = -ey, ex, 0.0
                            vL = np.sqrt(vx * vx + vy * vy)
                            if vL < 1e-12:
                                vx, vy, vz, vL = 0.0, -ez, ey, np.sqrt(ez * ez + ey * ey)
                        sin_l = np.sqrt(max(0.0, 1.0 - limit_cos[j] * limit_cos[j]))
                        ux = limit_cos[j] * ex + sin_l * vx / vL
                        uy = limit_cos[j] * ey + sin_l * vy / vL
                        uz = limit_cos[j] * ez + sin_l * vz / vL
            pos[j, 0] = pos[p, 0] + lengths[j] * ux
            pos[j, 1] = pos[p, 1] + lengths[j] * uy
            pos[j, 2] = pos[p, 2] + lengths[j] * uz
        it += 1


class FabrikSolver:
    """Full-body FABRIK behind the :class:`~posekit.ik.api.Solver` interface.

    Parameters
    ----------
    skeleton : Skeleton
    max_iter : int
        Iteration cap (Aristidou & Lasenby report convergence in a few iterations).
    base : str
        The joint that stays fixed, with all its ancestors (default the pelvis role, else joint 0).
    constraints : Constraints, True or None
        Joint limits; ``True`` uses :func:`default_constraints`.

    Notes
    -----
    Bone lengths come from the start pose, so the solver works on any skeleton whose start pose is
    given. Effector tolerances come from the :class:`Effector` objects.
    """

    name = "fabrik"

    def __init__(self, skeleton: Skeleton, max_iter: int = 20, base: str | None = None, constraints=None):
        self.skeleton = skeleton
        self.max_iter = int(max_iter)
        J = skeleton.n_joints
        b = self.base = base_index(skeleton, base)
        fixed = np.zeros(J, dtype=np.bool_)
        fixed[skeleton.chain(b, 0)] = True
        self._fixed = fixed
        order = np.argsort(skeleton.parents[1:], kind="stable") + 1
        counts = np.bincount(skeleton.parents[1:], minlength=J)
        self._child_start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        self._child_idx = order.astype(np.int64)
        if constraints is True:
            constraints = default_constraints(skeleton)
        self.constraints = constraints
        self._limit_cos = np.full(J, -2.0)
        self._no_fwd = np.zeros(J, dtype=np.bool_)
        self._hips = (-1, -1)
        if constraints is not None:
            for name, angle in constraints.max_angle.items():
                self._limit_cos[skeleton.index(name)] = np.cos(angle)
            for name in constraints.no_forward_bend:
                self._no_fwd[skeleton.index(name)] = True
            if "left_hip" in skeleton.roles and "right_hip" in skeleton.roles:
                self._hips = (skeleton.index("left_hip"), skeleton.index("right_hip"))

    def _active(self, eff_idx):
        active = np.zeros(self.skeleton.n_joints, dtype=np.bool_)
        for j in eff_idx:
            while j >= 0 and not active[j]:
                active[j] = True
                j = self.skeleton.parents[j]
        return active

    def _chains(self, eff_idx, lengths):
        """For every joint c: the effector (slot) closest below it, and the chain length from c's
        parent down to that effector."""
        J = self.skeleton.n_joints
        sub_eff = np.zeros(J, dtype=np.int64)
        sub_reach = np.full(J, np.inf)
        for k, e in enumerate(eff_idx):
            length, j = 0.0, int(e)
            while j > 0:
                length += lengths[j]
                if length < sub_reach[j]:
                    sub_reach[j], sub_eff[j] = length, k
                j = int(self.skeleton.parents[j])
        return sub_eff, sub_reach

    def solve(self, start: Pose, effectors) -> IKResult:
        """Pose the skeleton so the effectors reach their targets; bone lengths are kept."""
        p = check_pose(self.skeleton, start)
        idx, targets, tols, _ = resolve_effectors(self.skeleton, effectors)
        lengths = np.linalg.norm(p - p[np.maximum(self.skeleton.parents, 0)], axis=1)
        lengths[0] = 0.0
        movable = ~self._fixed
        if np.any(lengths[movable] < 1e-9):
            j = int(np.nonzero(movable & (lengths < 1e-9))[0][0])
            raise ValueError(f"zero-length bone to joint {self.skeleton.names[j]}; FABRIK needs every bone > 0")
        slot = np.full(self.skeleton.n_joints, -1, dtype=np.int64)
        slot[idx] = np.arange(len(idx))
        pos = np.ascontiguousarray(p, dtype=float).copy()
        sub_eff, sub_reach = self._chains(idx, lengths)
        it, done = _fabrik_tree(pos, self.skeleton.parents, lengths, self._child_start, self._child_idx,
                                self._active(idx), self._fixed, slot, idx.astype(np.int64),
                                np.ascontiguousarray(targets), tols,
                                self.max_iter, self._limit_cos, self._no_fwd, self._hips[0], self._hips[1],
                                self.constraints is not None, sub_eff, sub_reach)
        err = np.linalg.norm(pos[idx] - targets, axis=1)
        return IKResult(Pose(pos), bool(np.all(err <= tols)), int(it), err)


def fix_bone_lengths(skeleton: Skeleton, global_pos, lengths=None, keep: str = "leaves") -> np.ndarray:
    """Restore bone lengths of predicted joint positions with one FABRIK pass.

    Parameters
    ----------
    global_pos : ndarray, shape (..., J, 3), metres
        Positions whose bones may have the wrong length (e.g. a network's output).
    lengths : ndarray, shape (J,), optional
        Wanted bone lengths; default ``skeleton.bone_lengths()``.
    keep : {"leaves", "root"}
        ``"leaves"``: the backward pass of FABRIK — leaves stay where they are and every parent is
        placed at the right distance from its children (at the centroid where several children
        meet), so the hands and feet keep their positions; then one forward pass from the root
        (now moved) makes every bone exact. ``"root"``: only the forward pass from the root.

    Returns
    -------
    ndarray, shape (..., J, 3) with every bone length equal to ``lengths``.
    """
    pos = np.array(global_pos, dtype=float)
    J = skeleton.n_joints
    if pos.shape[-2:] != (J, 3):
        raise ValueError(f"global_pos: expected shape (..., {J}, 3), got {pos.shape}")
    if not np.all(np.isfinite(pos)):
        raise ValueError("global_pos contains NaN or inf")
    L = skeleton.bone_lengths() if lengths is None else np.asarray(lengths, dtype=float)
    parents = skeleton.parents

    def place(child, parent_pos, length):
        u = child - parent_pos
        n = np.linalg.norm(u, axis=-1, keepdims=True)
        return parent_pos + length * u / np.maximum(n, 1e-12)

    if keep == "leaves":
        back = pos.copy()
        for j in range(J - 1, 0, -1):
            kids = np.nonzero(parents == j)[0]
            if len(kids):
                back[..., j, :] = np.mean([place(back[..., j, :], back[..., c, :], L[c]) for c in kids], axis=0)
        kids = np.nonzero(parents == 0)[0]
        back[..., 0, :] = np.mean([place(back[..., 0, :], back[..., c, :], L[c]) for c in kids], axis=0)
        pos = back
    elif keep != "root":
        raise ValueError(f"keep must be 'leaves' or 'root', got {keep!r}")
    out = pos.copy()
    for j in range(1, J):
        out[..., j, :] = place(pos[..., j, :], out[..., parents[j], :], L[j])
    return out
