"""Effectors — what a solver is asked to do — and the one function that says how far a pose is from them.

Introduced in ``notebooks/01_fabrik.ipynb``. Units, axes and the quaternion order:
:mod:`posekit.conventions` (metres, radians, Y up, facing +Z, quaternions ``(x, y, z, w)``,
column vectors).

Three kinds of effector, each with its own error (Table 1 of Oreshkin et al. 2021 uses the same
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
effector's tolerance. :func:`effector_errors` (one pose) and :func:`effector_errors_batch` (B poses)
are the solvers' one implementation: every solver reports its errors through them and its
iteration loop stops on the same compiled kernel (:func:`errors_into`). (The benchmark scores
results independently, in :mod:`posekit.data.metrics`, so that a solver cannot grade itself.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from .._jit import njit
from ..conventions import FORWARD
from ..rotations import quat_to_matrix, sixd_to_matrix

__all__ = ["KINDS", "DEFAULT_TOLERANCE", "Effector", "ResolvedEffectors", "resolve_effectors", "effector_errors",
           "effector_errors_batch", "normalise_kind", "errors_into", "errors_of", "position_errors_into",
           "position_errors"]

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


# ------------------------------------------------------------------------------------ the errors
@njit
def _distance(Pg, j, tpos, k):
    dx = Pg[j, 0] - tpos[k, 0]
    dy = Pg[j, 1] - tpos[k, 1]
    dz = Pg[j, 2] - tpos[k, 2]
    return np.sqrt(dx * dx + dy * dy + dz * dz)


@njit
def position_errors_into(Pg, joints, tpos, out):
    """:func:`errors_into` for position effectors only (the FABRIK kernel, which has no rotations)."""
    for k in range(joints.shape[0]):
        out[k] = _distance(Pg, joints[k], tpos, k)


def position_errors(p, t, axis: int = -1):
    """:func:`errors_into`'s position error in numpy, ``sqrt(dx^2 + dy^2 + dz^2)`` along ``axis``
    (the same operations in the same order, so the same bits; used by the batched FABRIK)."""
    return np.sqrt(((p - t) ** 2).sum(axis=axis))


@njit
def errors_into(Pg, Rg, joints, codes, tpos, trot, axis, out):
    """Every effector error of one pose into ``out`` (K,): the definition the solvers share.

    ``Pg`` (J, 3) and ``Rg`` (J, 3, 3) are world positions and rotations (``Rg`` is read only for
    the angular kinds); ``tpos`` (K, 3), ``trot`` (K, 3, 3), ``axis`` (K, 3) as in
    :class:`ResolvedEffectors`.

    * position: ``sqrt(dx^2 + dy^2 + dz^2)``, metres;
    * rotation: the geodesic angle of ``M = R_j^T R_t``,
      ``atan2(|vee(M - M^T)| / 2, (tr M - 1) / 2)`` (accurate near 0 and pi, unlike ``arccos``);
    * look_at: the angle between ``u = R_j a`` and ``w = t - p_j``, ``atan2(|u x w|, u . w)``
      (pi when the joint sits on its target).
    """
    for k in range(joints.shape[0]):
        j = joints[k]
        c = codes[k]
        if c == 0:
            out[k] = _distance(Pg, j, tpos, k)
        elif c == 1:
            tr = 0.0
            for i in range(3):
                for m in range(3):
                    tr += Rg[j, m, i] * trot[k, m, i]
            # M = R_j^T R_t; its skew part M[a, b] - M[b, a]
            s0 = 0.0
            s1 = 0.0
            s2 = 0.0
            for m in range(3):
                s0 += Rg[j, m, 2] * trot[k, m, 1] - Rg[j, m, 1] * trot[k, m, 2]
                s1 += Rg[j, m, 0] * trot[k, m, 2] - Rg[j, m, 2] * trot[k, m, 0]
                s2 += Rg[j, m, 1] * trot[k, m, 0] - Rg[j, m, 0] * trot[k, m, 1]
            out[k] = np.arctan2(0.5 * np.sqrt(s0 * s0 + s1 * s1 + s2 * s2), 0.5 * (tr - 1.0))
        else:
            ux = Rg[j, 0, 0] * axis[k, 0] + Rg[j, 0, 1] * axis[k, 1] + Rg[j, 0, 2] * axis[k, 2]
            uy = Rg[j, 1, 0] * axis[k, 0] + Rg[j, 1, 1] * axis[k, 1] + Rg[j, 1, 2] * axis[k, 2]
            uz = Rg[j, 2, 0] * axis[k, 0] + Rg[j, 2, 1] * axis[k, 1] + Rg[j, 2, 2] * axis[k, 2]
            wx = tpos[k, 0] - Pg[j, 0]
            wy = tpos[k, 1] - Pg[j, 1]
            wz = tpos[k, 2] - Pg[j, 2]
            if wx * wx + wy * wy + wz * wz < 1e-24:
                out[k] = np.pi
            else:
                cx = uy * wz - uz * wy
                cy = uz * wx - ux * wz
                cz = ux * wy - uy * wx
                out[k] = np.arctan2(np.sqrt(cx * cx + cy * cy + cz * cz), ux * wx + uy * wy + uz * wz)


@njit
def _errors_batch(Pg, Rg, joints, codes, tpos, trot, axis, out):
    for b in range(Pg.shape[0]):
        errors_into(Pg[b], Rg[b], joints, codes, tpos[b], trot[b], axis[b], out[b])


def _global_rotations(skeleton, pose):
    from ..kinematics import fk

    if pose.local_rot is None:
        return None
    root = None if pose.root_pos is None else np.asarray(pose.root_pos, dtype=float)
    lp = None if pose.local_pos is None else np.asarray(pose.local_pos, dtype=float)
    return fk(skeleton, np.asarray(pose.local_rot, dtype=float), root, lp)[1]


def effector_errors(skeleton, pose, effectors) -> tuple[np.ndarray, bool]:
    """How far one pose is from its effectors.

    Parameters
    ----------
    skeleton : Skeleton
    pose : Pose
        ``global_pos`` gives the positions; rotation and look-at effectors also need ``local_rot``
        (global rotations by :func:`posekit.kinematics.fk`).
    effectors : sequence of Effector, or ResolvedEffectors

    Returns
    -------
    errors : ndarray, shape (K,)
        Metres for position effectors, radians for rotation and look-at effectors (see the module
        table).
    converged : bool
        Every error at most its effector's tolerance.
    """
    res = as_resolved(skeleton, effectors)
    pos = np.asarray(pose.global_pos, dtype=float)
    if pos.shape != (skeleton.n_joints, 3):
        raise ValueError(f"pose: expected global_pos of shape ({skeleton.n_joints}, 3), got {pos.shape}")
    rot = None
    if res.angular:
        rot = _global_rotations(skeleton, pose)
        if rot is None:
            k = next(i for i, kind in enumerate(res.kinds) if kind != "position")
            raise ValueError(f"{res.kinds[k]} effector on {res.names[k]}: the pose has no rotations (local_rot); "
                             "only position errors can be measured on it")
    return errors_of(pos, rot, res)


def errors_of(global_pos, global_rot, res: ResolvedEffectors) -> tuple[np.ndarray, bool]:
    """:func:`errors_into` on one pose, ``global_pos`` (J, 3) and ``global_rot`` (J, 3, 3) or None
    (position effectors only), for resolved effectors: (errors (K,), converged)."""
    if global_rot is None:
        if res.angular:
            raise ValueError("rotation and look-at effectors need the joints' rotations; got none")
        global_rot = _NO_ROT
    out = np.empty(len(res))
    errors_into(np.ascontiguousarray(global_pos, dtype=float), np.ascontiguousarray(global_rot, dtype=float),
                res.joints, res.codes, res.position, res.rotation, res.axis, out)
    return out, bool((out <= res.tolerance).all())


_NO_ROT = np.zeros((1, 3, 3))


def _stack(skeleton, effectors, B):
    """One ResolvedEffectors, or B of them with the same joints and kinds -> arrays with a batch axis."""
    if isinstance(effectors, ResolvedEffectors) or (len(effectors) and isinstance(effectors[0], Effector)):
        r = as_resolved(skeleton, effectors)
        rep = lambda a: np.broadcast_to(a, (B,) + a.shape)  # noqa: E731
        return r, rep(r.position), rep(r.rotation), rep(r.axis), rep(r.tolerance)
    rs = [as_resolved(skeleton, e) for e in effectors]
    if len(rs) != B:
        raise ValueError(f"expected {B} effector lists (one per pose), got {len(rs)}")
    r = rs[0]
    for i, o in enumerate(rs[1:], 1):
        if o.kinds != r.kinds or not np.array_equal(o.joints, r.joints):
            raise ValueError(f"effector list {i} has other joints or kinds than list 0; a batch shares them")
    return (r, np.stack([o.position for o in rs]), np.stack([o.rotation for o in rs]),
            np.stack([o.axis for o in rs]), np.stack([o.tolerance for o in rs]))


def effector_errors_batch(skeleton, global_pos, global_rot, effectors) -> tuple[np.ndarray, np.ndarray]:
    """:func:`effector_errors` over a batch of poses.

    Parameters
    ----------
    skeleton : Skeleton
    global_pos : ndarray, shape (B, J, 3), metres
    global_rot : ndarray, shape (B, J, 3, 3), or None
        World rotations (``fk(...)[1]``); needed only for rotation and look-at effectors.
    effectors : sequence of Effector (shared by every pose), sequence of B such sequences (the same
        joints and kinds, their own targets), or ResolvedEffectors

    Returns
    -------
    errors : ndarray, shape (B, K), metres or radians per kind
    converged : ndarray of bool, shape (B,)
    """
    P = np.ascontiguousarray(global_pos, dtype=float)
    J = skeleton.n_joints
    if P.ndim != 3 or P.shape[1:] != (J, 3):
        raise ValueError(f"global_pos: expected shape (B, {J}, 3), got {P.shape}")
    B = P.shape[0]
    r, tpos, trot, axis, tol = _stack(skeleton, effectors, B)
    if r.angular:
        if global_rot is None:
            raise ValueError("rotation and look-at effectors need global_rot (B, J, 3, 3); got None")
        R = np.ascontiguousarray(global_rot, dtype=float)
        if R.shape != (B, J, 3, 3):
            raise ValueError(f"global_rot: expected shape ({B}, {J}, 3, 3), got {R.shape}")
    else:
        R = np.zeros((B, 1, 3, 3))  # not read: position errors only
    out = np.empty((B, len(r)))
    _errors_batch(P, R, r.joints, r.codes, np.ascontiguousarray(tpos), np.ascontiguousarray(trot),
                  np.ascontiguousarray(axis), out)
    return out, np.all(out <= tol, axis=1)
