"""Pose metrics shared by every posing benchmark and lesson: one definition, every solver.

Introduced in ``notebooks/01_fabrik.ipynb`` (``posekit bench ik``); the learned solvers of lessons
03-05 report the same numbers on the same cases (:mod:`posekit.data.cases`). It lives in the data
layer so that training loops (solver layer) can use it too. Units and axes: :mod:`posekit.conventions`;
the functions take and return metres and radians, :func:`score_poses` reports mm and degrees.

Body joints
-----------
A pose is the body, not its placement in the world. :func:`body_joints` is every joint except the
skeleton root when the root is not the pelvis (``Skeleton.pelvis()``): Bandai's ``joint_Root`` is a
helper point below the pelvis that only carries the world position, so it is left out; on a skeleton
whose root *is* the pelvis (DeepMimic) every joint counts. Positions are compared **root-relative**:
relative to the pelvis, the joint every solver keeps in place.

Metrics (per case)
------------------
* effector error — the worst effector of the case: distance for position effectors (mm), angle for
  rotation and look-at effectors (degrees);
* MPJPE — mean over body joints of the distance to the true pose, pelvis-relative (mm);
* bone-length error — the largest change of a body bone's length from the start pose (mm);
* rotation error — mean geodesic angle over body joints between the result's and the true joint
  rotations (degrees): each joint relative to its parent, the top body joint (the pelvis) in the case
  frame; only for solvers that return local rotations;
* naturalness — pelvis-relative MPJPE from the result, in its own root frame, to the nearest training
  pose (:class:`NaturalnessIndex`, mm); the true pose's own distance is the floor a solver can be
  expected to reach.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..conventions import FORWARD
from ..kinematics import bone_lengths_of, fk
from ..rotations import geodesic_distance, quat_to_matrix, sixd_to_matrix
from ..transforms import to_root_space

__all__ = ["body_joints", "mpjpe", "bone_length_error", "rotation_error", "effector_errors", "pose_features",
           "NaturalnessIndex", "PoseScores", "score_poses", "ANGULAR_KINDS"]

ANGULAR_KINDS = ("rotation", "look_at")
"""Effector kinds whose error is an angle."""


def body_joints(skeleton) -> np.ndarray:
    """Indices of the joints that make up a pose, shape (B,): all but the root when the root is not
    the pelvis (see the module docstring)."""
    J = skeleton.n_joints
    return np.arange(1, J) if skeleton.pelvis() != 0 and J > 1 else np.arange(J)


def mpjpe(skeleton, global_pos, true_pos) -> np.ndarray:
    """Mean per-joint position error over body joints, pelvis-relative.

    Parameters
    ----------
    global_pos, true_pos : ndarray, shape (..., J, 3), metres

    Returns
    -------
    ndarray, shape (...), metres
    """
    b, pel = body_joints(skeleton), skeleton.pelvis()
    p, t = np.asarray(global_pos, dtype=float), np.asarray(true_pos, dtype=float)
    d = (p[..., b, :] - p[..., pel, None, :]) - (t[..., b, :] - t[..., pel, None, :])
    return np.linalg.norm(d, axis=-1).mean(axis=-1)


def bone_length_error(skeleton, global_pos, reference_pos) -> np.ndarray:
    """Largest change of a body bone's length (a bone from a body joint to its child), shape (...), metres."""
    body = np.zeros(skeleton.n_joints, dtype=bool)
    body[body_joints(skeleton)] = True
    bones = np.nonzero(body[np.maximum(skeleton.parents, 0)] & (skeleton.parents >= 0))[0]
    if len(bones) == 0:
        return np.zeros(np.shape(global_pos)[:-2])
    d = bone_lengths_of(skeleton, global_pos) - bone_lengths_of(skeleton, reference_pos)
    return np.abs(d[..., bones]).max(axis=-1)


def _joint_frames(skeleton, local_rot):
    """Rotation matrices of the body joints (..., B, 3, 3): relative to the parent, except a body joint
    whose parent is not a body joint (the pelvis below Bandai's joint_Root), which is in the case frame."""
    b = body_joints(skeleton)
    G = fk(skeleton, np.asarray(local_rot, dtype=float))[1]
    body = np.zeros(skeleton.n_joints, dtype=bool)
    body[b] = True
    p = skeleton.parents[b]
    rel = np.swapaxes(G[..., np.maximum(p, 0), :, :], -1, -2) @ G[..., b, :, :]
    top = (p < 0) | ~body[np.maximum(p, 0)]
    rel[..., top, :, :] = G[..., b[top], :, :]
    return rel


def rotation_error(skeleton, local_rot, true_rot) -> np.ndarray:
    """Mean geodesic angle over body joints between two sets of local rotations.

    Parameters
    ----------
    local_rot, true_rot : ndarray, shape (..., J, 4)
        Local quaternions ``(x, y, z, w)``, in the same frame (a case's root frame).

    Returns
    -------
    ndarray, shape (...), radians
    """
    return geodesic_distance(_joint_frames(skeleton, local_rot), _joint_frames(skeleton, true_rot)).mean(axis=-1)


def _rotation_target(target) -> np.ndarray:
    t = np.asarray(target, dtype=float)
    if t.shape == (4,):
        return quat_to_matrix(t / np.linalg.norm(t))
    if t.shape == (6,):
        return sixd_to_matrix(t)
    if t.shape == (3, 3):
        return t
    raise ValueError(f"rotation effector target: expected a quaternion (4,), 6D (6,) or matrix (3, 3), got {t.shape}")


def effector_errors(skeleton, effectors, global_pos, local_rot=None):
    """Errors of one pose against its effectors, measured on the pose (not as a solver reports them).

    The kinds follow :mod:`posekit.ik.effectors`: ``"position"`` (target (3,), metres: distance),
    ``"rotation"`` (the joint's world orientation as a quaternion (4,), 6D (6,) or matrix (3, 3):
    geodesic angle) and ``"look_at"`` (a point (3,) the joint's ``axis``, default +Z, should face:
    the angle between them).

    Parameters
    ----------
    effectors : sequence of Effector
        Anything with ``joint``, ``target``, ``kind`` (and ``axis`` for look-at).
    global_pos : ndarray, shape (J, 3), metres
    local_rot : ndarray, shape (J, 4), optional
        Needed for angular effectors (their error is NaN without it).

    Returns
    -------
    position : ndarray, shape (K_pos,), metres
    angle : ndarray, shape (K_ang,), radians
    """
    pos_err, ang_err, G = [], [], None
    for e in effectors:
        j = skeleton.index(e.joint)
        kind = str(getattr(e, "kind", "position")).replace("-", "_")
        if kind not in ANGULAR_KINDS:
            pos_err.append(np.linalg.norm(global_pos[j] - np.asarray(e.target, dtype=float)))
            continue
        if local_rot is None:
            ang_err.append(np.nan)
            continue
        if G is None:
            G = fk(skeleton, np.asarray(local_rot, dtype=float))[1]  # rotations need no translations
        if kind == "rotation":
            ang_err.append(float(geodesic_distance(G[j], _rotation_target(e.target))))
        else:
            a = getattr(e, "axis", None)
            axis = G[j] @ (FORWARD if a is None else np.asarray(a, dtype=float))
            to = np.asarray(e.target, dtype=float) - global_pos[j]
            c = axis @ to / max(np.linalg.norm(axis) * np.linalg.norm(to), 1e-12)
            ang_err.append(float(np.arccos(np.clip(c, -1.0, 1.0))))
    return np.array(pos_err), np.array(ang_err)


def pose_features(skeleton, global_pos) -> np.ndarray:
    """Poses as vectors for nearest-neighbour search: each in its own root frame, pelvis-relative,
    body joints flattened, shape (N, 3B), metres."""
    p = np.asarray(global_pos, dtype=float).reshape(-1, skeleton.n_joints, 3)
    local = to_root_space(skeleton, p)[0]
    b = body_joints(skeleton)
    return (local[:, b] - local[:, skeleton.pelvis(), None]).reshape(len(p), -1)


class NaturalnessIndex:
    """Distance from a pose to the nearest training pose: a proxy for "looks like real motion".

    Poses are compared by :func:`pose_features` (own root frame, pelvis-relative, body joints). The
    ``candidates`` nearest training poses in Euclidean distance (scikit-learn ``NearestNeighbors``)
    are re-ranked by the mean per-joint distance, so the reported value is MPJPE-style.

    Parameters
    ----------
    skeleton : Skeleton
    global_pos : ndarray, shape (N, J, 3), metres
        Training poses (e.g. ``motions.global_pos[cases.train_frames]``).
    max_poses : int
        Keep at most this many, a seeded random subset (the query cost grows with it).
    seed : int
    candidates : int

    Attributes
    ----------
    kept : ndarray of int
        Which rows of ``global_pos`` are in the index.
    """

    def __init__(self, skeleton, global_pos, max_poses: int = 20_000, seed: int = 0, candidates: int = 8):
        from sklearn.neighbors import NearestNeighbors

        global_pos = np.asarray(global_pos, dtype=float)
        if len(global_pos) == 0:
            raise ValueError("NaturalnessIndex needs at least one training pose")
        n = len(global_pos)
        self.kept = np.sort(np.random.default_rng(seed).choice(n, max_poses, replace=False)) if n > max_poses \
            else np.arange(n)
        self.skeleton = skeleton
        self.features = pose_features(skeleton, global_pos[self.kept])
        self.candidates = int(min(candidates, len(self.kept)))
        self._nn = NearestNeighbors(n_neighbors=self.candidates).fit(self.features)

    def __len__(self):
        return len(self.kept)

    def distance(self, global_pos) -> np.ndarray:
        """Mean per-joint distance to the nearest training pose, shape (...), metres."""
        global_pos = np.asarray(global_pos, dtype=float)
        batch = global_pos.shape[:-2]
        f = pose_features(self.skeleton, global_pos)
        idx = self._nn.kneighbors(f, return_distance=False)  # (N, candidates)
        d = f[:, None, :] - self.features[idx]
        per_joint = np.linalg.norm(d.reshape(*d.shape[:2], -1, 3), axis=-1).mean(axis=-1)
        return per_joint.min(axis=1).reshape(batch)


@dataclass
class PoseScores:
    """Per-case metrics of one method on one set of cases (see the module docstring).

    Attributes
    ----------
    effector_mm : ndarray, shape (N,)
        Worst position effector of each case.
    effector_deg : ndarray, shape (N,) or None
        Worst angular effector (None when there is none).
    mpjpe_mm, bone_mm : ndarray, shape (N,)
    rotation_deg : ndarray, shape (N,) or None
        None when the method returned no local rotations.
    natural_mm, natural_floor_mm : ndarray, shape (N,) or None
        None without a :class:`NaturalnessIndex`.
    converged : ndarray of bool, shape (N,)
        Every effector of the case within its tolerance (measured here, not as the solver says).
    """

    effector_mm: np.ndarray
    effector_deg: np.ndarray | None
    mpjpe_mm: np.ndarray
    bone_mm: np.ndarray
    rotation_deg: np.ndarray | None
    natural_mm: np.ndarray | None
    natural_floor_mm: np.ndarray | None
    converged: np.ndarray

    def summary(self) -> dict:
        """The benchmark's JSON keys: medians over cases, the worst case for bone lengths."""
        med = lambda a: None if a is None else float(np.median(a))
        out = {
            "effector_error_mm_median": med(self.effector_mm),
            "effector_error_deg_median": med(self.effector_deg),
            "mpjpe_mm_median": med(self.mpjpe_mm),
            "bone_length_error_mm_max": float(np.max(self.bone_mm)),
            "rotation_error_deg_median": med(self.rotation_deg),
            "natural_mm_median": med(self.natural_mm),
            "natural_floor_mm_median": med(self.natural_floor_mm),
            "converged_fraction": float(np.mean(self.converged)),
        }
        return {k: v for k, v in out.items() if v is not None}


def score_poses(cases, result_pos, effectors, result_rot=None, natural: NaturalnessIndex | None = None,
                natural_floor=None, tolerance: float = 1e-3) -> PoseScores:
    """Score a method's poses on :class:`posekit.data.cases.Cases`, with the same code for every method.

    Parameters
    ----------
    cases : Cases
    result_pos : ndarray, shape (N, J, 3), metres
    effectors : sequence of sequence of Effector
        The effectors of each case.
    result_rot : ndarray, shape (N, J, 4), optional
        Local quaternions the method returned (rotation error and angular effectors).
    natural : NaturalnessIndex, optional
    natural_floor : ndarray, shape (N,), metres, optional
        ``natural.distance(cases.target_pos)``, passed in when scoring many methods on the same cases.
    tolerance : float, metres
        For position effectors that carry no tolerance of their own (angular ones: 1 degree).
    """
    s = cases.skeleton
    result_pos = np.asarray(result_pos, dtype=float)
    eff_mm, eff_deg, conv = [], [], []
    for i, effs in enumerate(effectors):
        rot = None if result_rot is None else result_rot[i]
        p, a = effector_errors(s, effs, result_pos[i], rot)
        eff_mm.append(p.max() * 1e3 if len(p) else 0.0)
        eff_deg.append(np.degrees(a.max()) if len(a) else np.nan)
        angular = np.array([str(getattr(e, "kind", "position")).replace("-", "_") in ANGULAR_KINDS for e in effs])
        tol = np.array([t if t is not None else (np.pi / 180 if ang else tolerance)
                        for t, ang in zip((getattr(e, "tolerance", None) for e in effs), angular)])
        err = np.empty(len(effs))
        err[~angular], err[angular] = p, a
        conv.append(bool(np.all(err <= tol + 1e-12)))
    eff_deg = np.array(eff_deg)
    rot_deg = None
    if result_rot is not None and cases.target_rot is not None:
        rot_deg = np.degrees(rotation_error(s, result_rot, cases.target_rot))
    nat = floor = None
    if natural is not None:
        nat = natural.distance(result_pos) * 1e3
        floor = (natural.distance(cases.target_pos) if natural_floor is None else np.asarray(natural_floor)) * 1e3
    return PoseScores(np.array(eff_mm), None if np.all(np.isnan(eff_deg)) else eff_deg,
                      mpjpe(s, result_pos, cases.target_pos) * 1e3,
                      bone_length_error(s, result_pos, cases.start_pos) * 1e3, rot_deg, nat, floor, np.array(conv))
