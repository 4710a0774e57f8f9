"""The one interface every posing solver implements: ``Effector``, ``Pose``, ``IKResult``, ``Solver``.

Introduced in ``notebooks/01_fabrik.ipynb``. FABRIK, CCD and damped least squares implement it now;
the neural solvers, AE-GAN latent optimisation and ProtoRes implement it in later lessons, and the
benchmark (:mod:`posekit.bench.ik`) and the viewer only ever talk to this interface.

Units and axes: :mod:`posekit.conventions` (metres, Y up, facing +Z).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, Sequence, runtime_checkable

import numpy as np

from ..kinematics import fk
from ..skeleton import Skeleton

__all__ = ["Effector", "Pose", "IKResult", "Solver", "EFFECTOR_SETS", "effector_set", "resolve_effectors",
           "KINDS"]

KINDS = ("position",)
"""Effector kinds solvers understand so far (rotation and look-at arrive with ProtoRes, lesson 05)."""

EFFECTOR_SETS = {
    "2": ("left_hand", "right_hand"),
    "5": ("left_hand", "right_hand", "left_foot", "right_foot", "head"),  # Victor & Meyer 2020
    "5point": ("chest", "left_hand", "right_hand", "left_foot", "right_foot"),  # Oreshkin et al. 2021
}
"""Named effector sets, as joint roles."""


@dataclass(frozen=True)
class Effector:
    """A goal for one joint.

    Parameters
    ----------
    joint : str or int
        Joint name, role (``"left_hand"``) or index.
    target : array, shape (3,), metres
        Where the joint should be (world frame).
    kind : str
        ``"position"`` (the only kind so far).
    tolerance : float, metres
        The effector counts as reached when its error is below this.
    weight : float
        Relative importance for solvers that trade effectors off (DLS, learned solvers).
    """

    joint: str | int
    target: np.ndarray
    kind: str = "position"
    tolerance: float = 1e-3
    weight: float = 1.0

    def __post_init__(self):
        object.__setattr__(self, "target", np.asarray(self.target, dtype=float))


@dataclass
class Pose:
    """A posed skeleton. ``global_pos`` is always there; rotation-based solvers also fill
    ``local_rot`` and ``root_pos``.

    Attributes
    ----------
    global_pos : ndarray, shape (J, 3), metres
    local_rot : ndarray, shape (J, 4), optional
        Local quaternions ``(x, y, z, w)``.
    root_pos : ndarray, shape (3,), optional
    local_pos : ndarray, shape (J, 3), optional
        Per-joint translations when they differ from the skeleton's offsets (BVH position channels).
    """

    global_pos: np.ndarray
    local_rot: np.ndarray | None = None
    root_pos: np.ndarray | None = None
    local_pos: np.ndarray | None = None

    @classmethod
    def from_rotations(cls, skeleton: Skeleton, local_rot, root_pos, local_pos=None) -> "Pose":
        """Pose from local quaternions (J, 4) and root position (3,), positions by FK."""
        local_rot = np.asarray(local_rot, dtype=float)
        root_pos = np.asarray(root_pos, dtype=float)
        lp = None if local_pos is None else np.asarray(local_pos, dtype=float)
        return cls(fk(skeleton, local_rot, root_pos, lp)[0], local_rot, root_pos, lp)

    def copy(self) -> "Pose":
        c = lambda a: None if a is None else np.array(a, copy=True)
        return Pose(self.global_pos.copy(), c(self.local_rot), c(self.root_pos), c(self.local_pos))


@dataclass
class IKResult:
    """What a solver returns.

    Attributes
    ----------
    pose : Pose
    converged : bool
        Every effector within its tolerance.
    iterations : int
    effector_error : ndarray, shape (K,), metres
        Distance of each effector from its target.
    info : dict
        Solver-specific extras.
    """

    pose: Pose
    converged: bool
    iterations: int
    effector_error: np.ndarray
    info: dict = field(default_factory=dict)


@runtime_checkable
class Solver(Protocol):
    """Anything that poses a skeleton to meet effectors: ``solve(start, effectors) -> IKResult``."""

    name: str
    skeleton: Skeleton

    def solve(self, start: Pose, effectors: Sequence[Effector]) -> IKResult:
        ...


def effector_set(skeleton: Skeleton, name: str, pose_pos, tolerance: float = 1e-3) -> list[Effector]:
    """Effectors of a named set (:data:`EFFECTOR_SETS`) placed at the joints of ``pose_pos`` (J, 3)."""
    if name not in EFFECTOR_SETS:
        raise ValueError(f"unknown effector set {name!r}; valid: {', '.join(EFFECTOR_SETS)}")
    skeleton.require_roles(EFFECTOR_SETS[name], f"effector set {name!r}")
    pose_pos = np.asarray(pose_pos, dtype=float)
    return [Effector(role, pose_pos[skeleton.index(role)], tolerance=tolerance) for role in EFFECTOR_SETS[name]]


def resolve_effectors(skeleton: Skeleton, effectors: Sequence[Effector], kinds=KINDS):
    """Validate effectors; returns joint indices (K,), targets (K, 3), tolerances (K,), weights (K,).

    Raises
    ------
    ValueError
        No effectors, an unknown joint (the message lists valid names), an unsupported kind, a target
        that is not 3 finite numbers, a non-positive tolerance, or two effectors on one joint.
    """
    if len(effectors) == 0:
        raise ValueError("expected at least one Effector")
    idx, targets, tols, weights = [], [], [], []
    for e in effectors:
        if not isinstance(e, Effector):
            raise ValueError(f"expected Effector objects, got {type(e).__name__}")
        if e.kind not in kinds:
            raise ValueError(f"effector on {e.joint!r}: kind {e.kind!r} is not supported here; expected one of {kinds}")
        j = skeleton.index(e.joint)
        if e.target.shape != (3,):
            raise ValueError(f"effector on {e.joint!r}: target must have shape (3,), got {e.target.shape}")
        if not np.all(np.isfinite(e.target)):
            raise ValueError(f"effector on {e.joint!r}: target contains NaN or inf")
        if not (e.tolerance > 0 and np.isfinite(e.tolerance)):
            raise ValueError(f"effector on {e.joint!r}: tolerance must be a positive number of metres")
        if j in idx:
            raise ValueError(f"two effectors on joint {skeleton.names[j]}")
        idx.append(j)
        targets.append(e.target)
        tols.append(float(e.tolerance))
        weights.append(float(e.weight))
    return np.array(idx), np.array(targets), np.array(tols), np.array(weights)


def base_index(skeleton: Skeleton, base=None) -> int:
    """The joint a solver keeps in place: ``base`` if given, else the pelvis role, else joint 0."""
    return skeleton.index(base) if base is not None else skeleton.pelvis()


def check_pose(skeleton: Skeleton, start: Pose) -> np.ndarray:
    """Validate a start pose; returns its global positions (J, 3)."""
    if not isinstance(start, Pose):
        raise ValueError(f"expected a Pose as the start pose, got {type(start).__name__}")
    p = np.asarray(start.global_pos, dtype=float)
    if p.shape != (skeleton.n_joints, 3):
        raise ValueError(f"start pose: expected global_pos of shape ({skeleton.n_joints}, 3), got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError("start pose contains NaN or inf")
    return p
