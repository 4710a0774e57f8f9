"""A procedural animation rig for the DeepMimic humanoid: animator controls -> joint positions.

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb``. The rig function ``f(y) = x`` maps 34
controls ``y`` to the 18 joint positions ``x`` (metres, :mod:`posekit.conventions`). Lesson 02 learns
its inverse, as Holden, Saito & Komura (TVCG 2017) do for production rigs.

Controls, as an animator sees them:

* **root** (COG): ``root_tx/ty/tz`` (m, ``ty`` above the rest pelvis height), ``root_yaw``,
  ``root_roll``, ``root_pitch`` (rad);
* **spine** (FK): ``spine_lower_bend`` (at the pelvis), ``spine_upper_bend`` (at the chest),
  ``spine_side`` and ``spine_twist`` spread half-half over both;
* **neck** (FK): ``neck_nod``, ``neck_turn``, ``neck_tilt``;
* **arm IK handles**: ``{l,r}_hand_{x,y,z}`` (world, m) and ``{l,r}_elbow_swivel`` (rad, turns the
  elbow about the shoulder-hand line), solved by analytic two-bone IK;
* **leg IK handles**: ``{l,r}_foot_{x,y,z}`` (world, m), ``{l,r}_knee_swivel``, ``{l,r}_foot_pitch``;
* three controls no animation uses: ``{l,r}_hand_curl`` and ``jaw_open`` drive fingers and a jaw this
  skeleton does not have.

Like real rigs it is **not injective**: ``root_pitch`` and ``spine_lower_bend`` turn the same joint
about the same axis, so ``(a, 0)``, ``(0, a)`` and ``(a/2, a/2)`` give one and the same pose.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..ik.two_bone import two_bone_ik
from ..kinematics import fk
from ..skeleton import Skeleton

__all__ = ["HumanoidRig", "CONTROLS"]

_PI = np.pi
# name, low, high (the rig's hard limits; values outside are clamped and reported)
CONTROLS = [
    ("root_tx", -3.0, 3.0), ("root_ty", -0.6, 0.3), ("root_tz", -3.0, 3.0),
    ("root_yaw", -_PI, _PI), ("root_roll", -0.6, 0.6), ("root_pitch", -0.8, 0.8),
    ("spine_lower_bend", -0.8, 0.8), ("spine_upper_bend", -0.8, 0.8), ("spine_side", -0.8, 0.8),
    ("spine_twist", -1.0, 1.0),
    ("neck_nod", -0.8, 0.8), ("neck_turn", -1.2, 1.2), ("neck_tilt", -0.6, 0.6),
    ("l_hand_x", -3.5, 3.5), ("l_hand_y", -0.2, 2.5), ("l_hand_z", -3.5, 3.5), ("l_elbow_swivel", -1.5, 1.5),
    ("r_hand_x", -3.5, 3.5), ("r_hand_y", -0.2, 2.5), ("r_hand_z", -3.5, 3.5), ("r_elbow_swivel", -1.5, 1.5),
    ("l_foot_x", -3.5, 3.5), ("l_foot_y", -0.1, 1.5), ("l_foot_z", -3.5, 3.5), ("l_knee_swivel", -1.0, 1.0),
    ("l_foot_pitch", -0.8, 0.8),
    ("r_foot_x", -3.5, 3.5), ("r_foot_y", -0.1, 1.5), ("r_foot_z", -3.5, 3.5), ("r_knee_swivel", -1.0, 1.0),
    ("r_foot_pitch", -0.8, 0.8),
    ("l_hand_curl", 0.0, 1.0), ("r_hand_curl", 0.0, 1.0), ("jaw_open", 0.0, 1.0),
]


def _euler(order: str, angles) -> np.ndarray:
    """Intrinsic Euler angles to matrices: ``order`` of upper-case axes, e.g. ``"YZX"`` gives
    ``Ry(a0) @ Rz(a1) @ Rx(a2)``; angles (N, len(order)) in radians -> (N, 3, 3). (What
    ``scipy.spatial.transform.Rotation.from_euler(order, angles).as_matrix()`` gives, to rounding, at a
    fraction of its cost on the few poses a Jacobian step evaluates.)"""
    angles = np.asarray(angles, dtype=float)
    out = None
    for k, axis in enumerate(order):
        c, s = np.cos(angles[:, k]), np.sin(angles[:, k])
        a, b = {"X": (1, 2), "Y": (2, 0), "Z": (0, 1)}[axis]  # the plane it turns: a -> b
        R = np.zeros((len(angles), 3, 3))
        R[:, 3 - a - b, 3 - a - b] = 1.0
        R[:, a, a], R[:, b, b], R[:, a, b], R[:, b, a] = c, c, -s, s
        out = R if out is None else out @ R
    return out


def _axis(R, k):
    return R[..., :, k]


def _rotate_about(v, axis, angle):
    """Rotate vectors v (N, 3) about unit axes (N, 3) by angles (N,) (Rodrigues)."""
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    a0, a1, a2, v0, v1, v2 = axis[:, 0], axis[:, 1], axis[:, 2], v[:, 0], v[:, 1], v[:, 2]
    cross = np.stack([a1 * v2 - a2 * v1, a2 * v0 - a0 * v2, a0 * v1 - a1 * v0], 1)  # np.cross's sums, without its cost
    return v * c + cross * s + axis * np.sum(axis * v, axis=1, keepdims=True) * (1 - c)


@dataclass
class ClampReport:
    """Which controls were outside their range, and by how much (in control units)."""

    count: int
    worst: dict

    def __str__(self):
        if not self.count:
            return "all controls within range"
        items = ", ".join(f"{k} by {v:.3g}" for k, v in self.worst.items())
        return f"{self.count} values clamped; worst per control: {items}"


class HumanoidRig:
    """The rig function of lesson 02 on the DeepMimic skeleton (see the module docstring).

    Parameters
    ----------
    skeleton : Skeleton
        The shipped DeepMimic skeleton (``posekit.data.load_sample().skeleton``).
    """

    def __init__(self, skeleton: Skeleton):
        need = ["pelvis", "chest", "neck", "head", "left_shoulder", "left_elbow", "left_hand", "right_shoulder",
                "right_elbow", "right_hand", "left_hip", "left_knee", "left_foot", "left_toe", "right_hip",
                "right_knee", "right_foot", "right_toe"]
        missing = [r for r in need if r not in skeleton.roles]
        if missing or skeleton.index("pelvis") != 0:
            raise ValueError(f"HumanoidRig needs a humanoid skeleton with the pelvis as root and roles {need}; "
                             f"missing: {missing}")
        self.skeleton = skeleton
        self.names = [c[0] for c in CONTROLS]
        self.low = np.array([c[1] for c in CONTROLS])
        self.high = np.array([c[2] for c in CONTROLS])
        self.n_controls = len(CONTROLS)
        self._i = {n: k for k, n in enumerate(self.names)}
        self._j = {r: skeleton.index(r) for r in need}
        rest = fk(skeleton, np.broadcast_to(np.eye(3), (skeleton.n_joints, 3, 3)))[0]
        self.rest_pelvis_height = float(rest[0, 1] - min(rest[:, 1]))
        self._toe_offset = skeleton.offsets[self._j["left_toe"]].copy()
        self._toe_offset_r = skeleton.offsets[self._j["right_toe"]].copy()

    # ------------------------------------------------------------------ controls
    def index(self, name: str) -> int:
        if name not in self._i:
            raise ValueError(f"unknown rig control {name!r}; valid: {', '.join(self.names)}")
        return self._i[name]

    def default(self) -> np.ndarray:
        """Controls of the rest pose, shape (C,): feet under the hips, hands at the sides."""
        rest = fk(self.skeleton, np.broadcast_to(np.eye(3), (self.skeleton.n_joints, 3, 3)))[0]
        rest = rest - [0, rest[:, 1].min(), 0]
        y = np.zeros(self.n_controls)
        for side, s in (("l", "left"), ("r", "right")):
            y[[self._i[f"{side}_hand_{a}"] for a in "xyz"]] = rest[self._j[f"{s}_hand"]]
            y[[self._i[f"{side}_foot_{a}"] for a in "xyz"]] = rest[self._j[f"{s}_foot"]]
        return y

    def clamp(self, y):
        """Clamp controls to their ranges; returns ``(clamped, ClampReport)``."""
        y = np.asarray(y, dtype=float)
        c = np.clip(y, self.low, self.high)
        over = np.abs(c - y)
        most = over.reshape(-1, self.n_controls).max(0) if over.size else np.zeros(self.n_controls)
        worst = {self.names[k]: float(most[k]) for k in np.flatnonzero(most > 0)}
        return c, ClampReport(int(np.count_nonzero(over)), worst)

    def _check(self, y):
        y = np.asarray(y, dtype=float)
        if y.shape[-1:] != (self.n_controls,):
            raise ValueError(f"rig controls: expected shape (..., {self.n_controls}), got {y.shape}")
        if not np.all(np.isfinite(y)):
            raise ValueError("rig controls contain NaN or inf")
        return y

    # ------------------------------------------------------------------ the rig function
    def evaluate(self, y, clamp: bool = True) -> np.ndarray:
        """The rig function f: controls (..., C) -> joint positions (..., J, 3), metres.

        Controls outside their ranges are clamped (``clamp=True``), as a rig's limits would, with a
        RuntimeWarning saying which and by how much.
        """
        y = self._check(y)
        if clamp:
            c, report = self.clamp(y)
            if report.count:
                warnings.warn(f"rig controls outside their ranges were clamped: {report}", RuntimeWarning, stacklevel=2)
            y = c
        batch = y.shape[:-1]
        y = y.reshape(-1, self.n_controls)
        N, s, J = len(y), self.skeleton, self.skeleton.n_joints
        g = lambda n: y[:, self._i[n]]
        R = np.broadcast_to(np.eye(3), (N, J, 3, 3)).copy()
        half = lambda a: 0.5 * a
        # pelvis: COG yaw, roll, pitch, then the lower spine bend about the same axis as the pitch
        # (hence the rig is not injective), then half of the side bend and twist
        R[:, 0] = (_euler("YZX", np.stack([g("root_yaw"), g("root_roll"), g("root_pitch") + g("spine_lower_bend")], 1))
                   @ _euler("ZY", np.stack([half(g("spine_side")), half(g("spine_twist"))], 1)))
        R[:, self._j["chest"]] = _euler("XZY", np.stack([
            g("spine_upper_bend"), half(g("spine_side")), half(g("spine_twist"))], 1))
        R[:, self._j["neck"]] = _euler("XYZ", np.stack([g("neck_nod"), g("neck_turn"), g("neck_tilt")], 1))
        root = np.stack([g("root_tx"), g("root_ty") + self.rest_pelvis_height, g("root_tz")], 1)
        pos, grot = fk(s, R, root)
        yaw = _euler("Y", g("root_yaw")[:, None])
        chest = grot[:, self._j["chest"]]
        # the four limbs' two-bone problems, solved in one call (the law of cosines is elementwise: each limb's
        # answer is the one it gets alone): an arm from the shoulder, its elbow bending behind and down in the chest
        # frame; a leg from the hip, its knee forward in the facing frame; each bend swivelled about root -> target
        bends = {"elbow_swivel": -_axis(chest, 2) - _axis(chest, 1), "knee_swivel": _axis(yaw, 2)}
        placed, problems = [], []
        for side, full in (("l", "left"), ("r", "right")):
            for joints, goal, swivel in ((("shoulder", "elbow", "hand"), "hand", "elbow_swivel"),
                                         (("hip", "knee", "foot"), "foot", "knee_swivel")):
                start, mid, end = (self._j[f"{full}_{p}"] for p in joints)
                target = np.stack([g(f"{side}_{goal}_{ax}") for ax in "xyz"], 1)
                u = target - pos[:, start]
                u = u / np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-9)
                pole = pos[:, start] + _rotate_about(bends[swivel], u, g(f"{side}_{swivel}"))
                problems.append((pos[:, start], pos[:, mid], pos[:, end], target, pole))
                placed.append((mid, end))
        new_mid, new_end, _ = two_bone_ik(*(np.concatenate(x) for x in zip(*problems)))
        for k, (mid, end) in enumerate(placed):
            pos[:, mid], pos[:, end] = new_mid[k * N:(k + 1) * N], new_end[k * N:(k + 1) * N]
        for side, full in (("l", "left"), ("r", "right")):  # toe by foot pitch
            toe_rot = yaw @ _euler("X", g(f"{side}_foot_pitch")[:, None])
            off = self._toe_offset if side == "l" else self._toe_offset_r
            pos[:, self._j[f"{full}_toe"]] = pos[:, self._j[f"{full}_foot"]] + toe_rot @ off
        return pos.reshape(batch + (J, 3))

    def jacobian(self, y, eps: float = 1e-4, value: bool = False):
        """Finite-difference Jacobian dx/dy (central differences).

        Parameters
        ----------
        y : ndarray, shape (N, C)
        eps : float
            The step on each control, in its units.
        value : bool
            Also return the rig at ``y`` itself, from the same call.

        Returns
        -------
        ndarray, shape (N, J*3, C)
            The Jacobian; with ``value``, ``(x, J)`` where ``x`` (N, J*3) is :meth:`evaluate` at ``y`` without the
            clamp (the same numbers: each pose is evaluated on its own, whatever else is in the call).
        """
        y = self._check(y).reshape(-1, self.n_controls)
        N, C = y.shape
        steps = np.eye(C) * eps
        # both sides (and y) in one call: the rig's cost is mostly per call (N is often 1: a frame at a time)
        poses = [y[:, None, :] + steps, y[:, None, :] - steps] + ([y[:, None, :]] if value else [])
        out = self.evaluate(np.concatenate(poses, 1).reshape(-1, C), clamp=False).reshape(N, -1)
        width = self.skeleton.n_joints * 3
        both = out[:, :2 * C * width].reshape(N, 2, C, width)
        J = np.swapaxes((both[:, 0] - both[:, 1]) / (2 * eps), 1, 2)
        return (out[:, 2 * C * width:], J) if value else J
