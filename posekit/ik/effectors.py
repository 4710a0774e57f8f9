"""Effectors — what a solver is asked to do: the record, its kinds, and effectors resolved to arrays.

Introduced in ``notebooks/01_fabrik.ipynb``. Units, axes and the quaternion order:
:mod:`posekit.conventions` (metres, radians, Y up, facing +Z, quaternions ``(x, y, z, w)``,
column vectors).

Three kinds of effector, each with its own error (Table 1 of Oreshkin et al. 2022 uses the same
three for ProtoRes):

==============  =========================================  ===========================================
kind            target                                     error (what ``tolerance`` bounds)
==============  =========================================  ===========================================
``position``    world point, shape (3,), metres            ``|p_j - t|``, metres
``rotation``    world orientation of the joint: a          geodesic angle ``angle(R_j^T R_t)``,
                quaternion (4,) ``(x, y, z, w)``, a 6D      radians in [0, pi]
                vector (6,) (first two matrix columns,
                :func:`posekit.rotations.sixd_to_matrix`)
                or a matrix (3, 3)
``look_at``     world point (3,) the joint should face,    angle between ``R_j a`` and ``t - p_j``,
                with ``axis`` ``a`` (3,), a direction in   radians in [0, pi]
                the joint's own frame
==============  =========================================  ===========================================

``p_j`` and ``R_j`` are the joint's world position and rotation (``global_pos``, ``global_rot`` of
:func:`posekit.kinematics.fk`). An effector set is *converged* when every error is at most its
effector's tolerance. How far a pose is from its effectors is the next module's:
:mod:`posekit.ik.effector_errors` (the solvers' one implementation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from ..conventions import FORWARD
from ..rotations import quat_to_matrix, sixd_to_matrix

__all__ = ["KINDS", "DEFAULT_TOLERANCE", "Effector", "ResolvedEffectors", "resolve_effectors", "as_resolved",
           "normalise_kind", "check_look_at"]

KINDS = ("position", "rotation", "look_at")
"""Every effector kind; ``"look-at"`` is accepted as a spelling of ``"look_at"``."""

KIND_CODES = {"position": 0, "rotation": 1, "look_at": 2}
"""Kind -> the integer the compiled kernels use."""

DEFAULT_TOLERANCE = {"position": 1e-3, "rotation": np.pi / 180, "look_at": np.pi / 180}
"""Tolerance of an effector that gives none: 1 mm for positions, 1 degree (pi/180 rad) for the
angular kinds (1 mm at the end of a 6 cm lever; a hand at 1 degree is visibly "right")."""

UNIT_TOL = 1e-3
"""How far a quaternion's norm, or ``R^T R`` of a matrix, may be from unit before it is refused."""

LOOK_AT_MIN_DISTANCE = 1e-6
"""A look-at target this close to its joint (metres) has no direction and is refused."""


def normalise_kind(kind) -> str:
    """The canonical spelling of an effector kind (``"look-at"`` -> ``"look_at"``); a ``ValueError``
    lists the valid kinds."""
    k = str(kind).replace("-", "_") if isinstance(kind, str) else kind
    if k not in KINDS:
        raise ValueError(f"unknown effector kind {kind!r}; valid kinds: {', '.join(KINDS)}")
    return k


@dataclass(frozen=True, eq=False)  # compared by identity: its targets are arrays
class Effector:
    """A goal for one joint (see the table of kinds in :mod:`posekit.ik.effectors`).

    Parameters
    ----------
    joint : str or int
        Joint name, role (``"left_hand"``) or index.
    target : array
        ``"position"``: shape (3,), metres, world frame. ``"rotation"``: the joint's world
        orientation as a quaternion (4,) ``(x, y, z, w)``, a 6D vector (6,) or a matrix (3, 3).
        ``"look_at"``: the world point (3,) the joint should face, metres.
    kind : str
        ``"position"`` (default), ``"rotation"`` or ``"look_at"`` (``"look-at"`` also accepted).
    tolerance : float, optional
        The effector counts as reached when its error is at most this: metres for ``"position"``,
        radians for the angular kinds. Default :data:`DEFAULT_TOLERANCE` (1 mm, 1 degree).
    weight : float
        Relative importance for solvers that trade effectors off (DLS, learned solvers); >= 0.
    axis : array, shape (3,), optional
        ``"look_at"`` only: the direction in the joint's own frame that should point at the target;
        default +Z, the facing direction of :mod:`posekit.conventions` (a head's forward in rest pose).
        Need not be unit length.

    Notes
    -----
    Construction only converts; everything is checked when a solver resolves the effectors
    (:func:`resolve_effectors`), or by :meth:`validate`, so a message names the joint and the skeleton.
    """

    joint: str | int
    target: np.ndarray
    kind: str = "position"
    tolerance: float | None = None
    weight: float = 1.0
    axis: np.ndarray | None = None

    def __post_init__(self):
        kind = self.kind.replace("-", "_") if isinstance(self.kind, str) else self.kind
        object.__setattr__(self, "kind", kind)
        object.__setattr__(self, "target", np.asarray(self.target, dtype=float))
        if self.tolerance is None and kind in DEFAULT_TOLERANCE:
            object.__setattr__(self, "tolerance", DEFAULT_TOLERANCE[kind])
        if kind == "look_at" and self.axis is None:
            object.__setattr__(self, "axis", FORWARD.copy())
        if self.axis is not None:
            object.__setattr__(self, "axis", np.asarray(self.axis, dtype=float))

    def validate(self, skeleton, kinds=KINDS) -> "Effector":
        """Check this effector on ``skeleton`` (see :func:`resolve_effectors`); returns it."""
        resolve_effectors(skeleton, [self], kinds)
        return self


@dataclass(frozen=True)
class ResolvedEffectors:
    """Effectors checked and turned into arrays for the kernels (:func:`resolve_effectors`).

    Attributes
    ----------
    joints : ndarray of int, shape (K,)
    kinds : tuple of str, length K
    codes : ndarray of int, shape (K,)
        :data:`KIND_CODES` of each kind.
    position : ndarray, shape (K, 3), metres
        The position target, or the look-at point; zeros for rotation effectors.
    rotation : ndarray, shape (K, 3, 3)
        The rotation target (an exact rotation); the identity for the other kinds.
    axis : ndarray, shape (K, 3)
        Unit look-at axis in the joint's frame; zeros for the other kinds.
    tolerance : ndarray, shape (K,), metres or radians
    weight : ndarray, shape (K,)
    """

    joints: np.ndarray
    kinds: tuple
    codes: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    axis: np.ndarray
    tolerance: np.ndarray
    weight: np.ndarray
    names: tuple = field(default=())

    def __len__(self):
        return len(self.joints)

    def has(self, kind: str) -> bool:
        """Whether any effector is of ``kind``."""
        return kind in self.kinds

    @property
    def angular(self) -> bool:
        """Whether any effector needs the joints' rotations."""
        return any(k != "position" for k in self.kinds)


def _rotation_target(e, where: str) -> np.ndarray:
    t = e.target
    if t.shape == (4,):
        n = float(np.linalg.norm(t))
        if abs(n - 1.0) > UNIT_TOL:
            raise ValueError(f"{where}: rotation target is not a unit quaternion (norm {n:.4g}); "
                             "normalise it (order x, y, z, w)")
        return quat_to_matrix(t / n)
    if t.shape == (6,):
        a1, a2 = t[:3], t[3:]
        n1, n2 = np.linalg.norm(a1), np.linalg.norm(a2)
        if n1 < 1e-9 or n2 < 1e-9 or np.linalg.norm(np.cross(a1, a2)) < 1e-6 * n1 * n2:
            raise ValueError(f"{where}: degenerate 6D rotation target (a zero column, or the two columns "
                             "parallel); expected the first two columns of a rotation matrix")
        return sixd_to_matrix(t)
    if t.shape == (3, 3):
        dev = float(np.abs(t.T @ t - np.eye(3)).max())
        det = float(np.linalg.det(t))
        if dev > UNIT_TOL or det <= 0:
            raise ValueError(f"{where}: rotation target is not a rotation matrix (max |R^T R - I| = {dev:.3g}, "
                             f"det = {det:.3g})")
        u, _, vt = np.linalg.svd(t)  # the nearest rotation: exact to rounding
        return u @ vt
    raise ValueError(f"{where}: rotation target must be a quaternion (4,) (x, y, z, w), a 6D vector (6,) or a "
                     f"matrix (3, 3); got shape {t.shape}")


def _number(x) -> float:
    if type(x) is float:
        return x
    try:
        return float(x)
    except (TypeError, ValueError):
        return float("nan")


def resolve_effectors(skeleton, effectors: Sequence[Effector], kinds=KINDS, solver: str | None = None
                      ) -> ResolvedEffectors:
    """Check effectors against a skeleton and the kinds a solver supports; returns their arrays.

    Parameters
    ----------
    skeleton : Skeleton
    effectors : sequence of Effector
    kinds : tuple of str
        The kinds the caller supports (a solver's ``kinds``).
    solver : str, optional
        The solver's name, for the messages.

    Returns
    -------
    ResolvedEffectors

    Raises
    ------
    ValueError
        No effectors; an object that is not an Effector; an unknown or unsupported kind (naming the
        solver and what it supports); an unknown joint (the message lists valid names); a target of the
        wrong shape for its kind, or with NaN/inf; a rotation that is not unit or is degenerate; a zero or
        non-finite look-at axis; a tolerance that is not a positive number; a negative weight; two
        effectors of one kind on one joint, or a rotation and a look-at effector on one joint.
    """
    who = f"solver {solver!r}" if solver else "this solver"
    if len(effectors) == 0:
        raise ValueError("expected at least one Effector")
    kinds = tuple(normalise_kind(k) for k in kinds)
    K = len(effectors)
    joints = np.empty(K, dtype=np.int64)
    names, kind_of = [], []
    pos = np.zeros((K, 3))
    rot = np.zeros((K, 3, 3))
    rot[:] = np.eye(3)
    axes = np.zeros((K, 3))
    tols = np.empty(K)
    weights = np.empty(K)
    seen = {}
    for k, e in enumerate(effectors):
        if not isinstance(e, Effector):
            raise ValueError(f"expected Effector objects, got {type(e).__name__}")
        kind = e.kind if e.kind in KIND_CODES else normalise_kind(e.kind)
        if kind not in kinds:
            raise ValueError(f"{who} does not support effector kind {e.kind!r} (effector on {e.joint!r}); "
                             f"it supports: {', '.join(kinds)}")
        j = skeleton.index(e.joint)
        where = f"{kind} effector on {skeleton.names[j]}"
        t = e.target
        if kind == "rotation":
            if not np.isfinite(t).all():
                raise ValueError(f"{where}: target contains NaN or inf")
            rot[k] = _rotation_target(e, where)
        else:
            if t.shape != (3,):
                raise ValueError(f"{where}: target must have shape (3,) (a world point, metres), got {t.shape}")
            x, y, z = float(t[0]), float(t[1]), float(t[2])
            if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
                raise ValueError(f"{where}: target contains NaN or inf")
            pos[k] = t
        tol = _number(e.tolerance)
        if not (math.isfinite(tol) and tol > 0):
            unit = "metres" if kind == "position" else "radians"
            raise ValueError(f"{where}: tolerance must be a positive number of {unit}, got {e.tolerance!r}")
        weight = _number(e.weight)
        if not (math.isfinite(weight) and weight >= 0):
            raise ValueError(f"{where}: weight must be a finite number >= 0, got {e.weight!r}")
        if kind == "look_at":
            ax = np.asarray(e.axis, dtype=float)
            if ax.shape != (3,) or not np.all(np.isfinite(ax)) or np.linalg.norm(ax) < 1e-9:
                raise ValueError(f"{where}: axis must be a finite non-zero direction of shape (3,) in the joint's "
                                 f"frame, got {e.axis!r}")
            axes[k] = ax / np.linalg.norm(ax)
        if j in seen:
            for k_other in seen[j]:
                if k_other == kind:
                    raise ValueError(f"two {kind} effectors on joint {skeleton.names[j]}")
                if {k_other, kind} == {"rotation", "look_at"}:
                    raise ValueError(f"a rotation and a look-at effector on joint {skeleton.names[j]}: the rotation "
                                     "already fixes where the joint faces; keep one")
            seen[j].append(kind)
        else:
            seen[j] = [kind]
        joints[k] = j
        names.append(skeleton.names[j])
        kind_of.append(kind)
        tols[k] = tol
        weights[k] = weight
    return ResolvedEffectors(joints, tuple(kind_of), np.array([KIND_CODES[k] for k in kind_of], dtype=np.int64),
                             pos, rot, axes, tols, weights, tuple(names))


def as_resolved(skeleton, effectors, kinds=KINDS, solver=None) -> ResolvedEffectors:
    """``effectors`` if already resolved, else :func:`resolve_effectors` of them."""
    if isinstance(effectors, ResolvedEffectors):
        return effectors
    return resolve_effectors(skeleton, effectors, kinds, solver)


def check_look_at(res: ResolvedEffectors, global_pos, who: str = "start pose"):
    """Refuse look-at targets that sit on their joint in ``global_pos`` (J, 3): no direction to face."""
    if "look_at" not in res.kinds:
        return
    for k in np.nonzero(res.codes == KIND_CODES["look_at"])[0]:
        d = float(np.linalg.norm(res.position[k] - global_pos[res.joints[k]]))
        if d < LOOK_AT_MIN_DISTANCE:
            raise ValueError(f"look_at effector on {res.names[k]}: the target is on the joint itself in the {who} "
                             f"({d * 1000:.3g} mm away), so there is no direction to face")
