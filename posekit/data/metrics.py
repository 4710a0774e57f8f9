"""Pose metrics: how far a pose is from another, from its start and from the poses a model trained on.

Introduced in ``notebooks/01_fabrik.ipynb`` (``posekit bench ik``); the learned solvers of lessons
03-05 report the same numbers on the same cases (:mod:`posekit.data.cases`). It lives in the data
layer so that training loops (solver layer) can use it too; scoring a solver's poses against their
effectors (which needs the effectors' one error definition, :mod:`posekit.ik.effector_errors`) is
:mod:`posekit.evaluation.pose_scores`. Units and axes: :mod:`posekit.conventions`; the functions take and
return metres and radians.

Body joints
-----------
A pose is the body, not its placement in the world. :func:`body_joints` is every joint except the
skeleton root when the root is not the pelvis (``Skeleton.pelvis()``): Bandai's ``joint_Root`` is a
helper point below the pelvis that only carries the world position, so it is left out; on a skeleton
whose root *is* the pelvis (DeepMimic) every joint counts. Positions are compared **root-relative**:
relative to the pelvis, the joint every solver keeps in place.

Metrics (per pose)
------------------
* MPJPE — mean over body joints of the distance to the true pose, pelvis-relative;
* bone-length error — the largest change of a body bone's length from the start pose;
* rotation error — mean geodesic angle over body joints between the result's and the true joint
  rotations: each joint relative to its parent, the top body joint (the pelvis) in the case frame;
* naturalness — pelvis-relative MPJPE from the result, in its own root frame, to the nearest training
  pose (:class:`NaturalnessIndex`); the true pose's own distance is the floor a solver can be expected
  to reach.
"""

from __future__ import annotations

import numpy as np

from ..kinematics import bone_lengths_of, fk
from ..rotations import geodesic_distance
from ..transforms import to_root_space

__all__ = ["body_joints", "mpjpe", "bone_length_error", "rotation_error", "pose_features", "NaturalnessIndex"]


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
    are re-ranked by the mean per-joint distance, so the reported value is MPJPE-style. A query of at most
    :attr:`BRUTE_MAX` poses is answered by one matrix product over every kept pose instead (the same exact
    search, without scikit-learn's per-call cost: what an IK solver pays to judge its own answers).

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

    BRUTE_MAX = 16
    """Queries of at most this many poses skip scikit-learn (:meth:`distance`)."""

    def __init__(self, skeleton, global_pos, max_poses: int = 20_000, seed: int = 0, candidates: int = 8):
        global_pos = np.asarray(global_pos, dtype=float)
        if len(global_pos) == 0:
            raise ValueError("NaturalnessIndex needs at least one training pose")
        n = len(global_pos)
        self.kept = np.sort(np.random.default_rng(seed).choice(n, max_poses, replace=False)) if n > max_poses \
            else np.arange(n)
        self.skeleton = skeleton
        self.features = pose_features(skeleton, global_pos[self.kept])
        self.candidates = int(min(candidates, len(self.kept)))
        self._nn = None  # scikit-learn's tree, fitted at the first large query
        self._sq = (self.features ** 2).sum(-1)  # (N,): |f|^2 of every kept pose, for the small-query path

    def __len__(self):
        return len(self.kept)

    def distance(self, global_pos) -> np.ndarray:
        """Mean per-joint distance to the nearest training pose, shape (...), metres."""
        global_pos = np.asarray(global_pos, dtype=float)
        batch = global_pos.shape[:-2]
        f = pose_features(self.skeleton, global_pos)
        if len(f) <= self.BRUTE_MAX:  # |f - g|^2 = |g|^2 - 2 f.g + |f|^2 against every kept pose
            d2 = self._sq[None] - 2.0 * (f @ self.features.T)
            k = self.candidates
            idx = np.argpartition(d2, k - 1, axis=1)[:, :k] if k < d2.shape[1] else np.broadcast_to(
                np.arange(d2.shape[1]), d2.shape)
        else:
            if self._nn is None:
                from sklearn.neighbors import NearestNeighbors

                self._nn = NearestNeighbors(n_neighbors=self.candidates).fit(self.features)
            idx = self._nn.kneighbors(f, return_distance=False)  # (N, candidates)
        d = f[:, None, :] - self.features[idx]
        per_joint = np.linalg.norm(d.reshape(*d.shape[:2], -1, 3), axis=-1).mean(axis=-1)
        return per_joint.min(axis=1).reshape(batch)
