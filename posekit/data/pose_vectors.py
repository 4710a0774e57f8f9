"""Poses as root-relative feature vectors: what every learned pose model of lessons 03-04 reads and writes.

Introduced in ``notebooks/03_autoencoder_solvers.ipynb`` (Victor et al. 2021, Sec. 3.2) and reused by
lesson 04's AE-GAN (:mod:`posekit.models.aegan.networks`). Units and
axes: :mod:`posekit.conventions` (metres, Y up, facing +Z).

A pose becomes one vector ``x`` of ``3 B`` numbers: the positions of its *body joints*
(:func:`posekit.data.metrics.body_joints`: every joint but a helper root such as Bandai's
``joint_Root``, which only carries the world position) in the pose's **root frame** — the pelvis
projected on the floor is the origin, the character faces +Z (:func:`posekit.transforms.to_root_space`).
The pelvis's x and z are therefore exactly 0; z-scoring (:class:`~posekit.records.NormStats`)
floors every standard deviation at :data:`STD_FLOOR` so those constant features do not divide by zero.

Mirroring (:func:`posekit.transforms.mirror_positions`) doubles the training poses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .metrics import body_joints
from .motion import MotionSet
from ..records import NormStats
from ..transforms import from_root_space, mirror_positions, rotate_y_positions, to_root_space

__all__ = ["STD_FLOOR", "pose_vectors", "poses_from_vectors", "targets_in_root_frame",
           "feature_columns", "PoseData", "pose_data", "split_pose_data"]

STD_FLOOR = 0.01
"""Smallest standard deviation of a feature in the z-score, metres (the pelvis x/z are exactly 0)."""


def pose_vectors(skeleton, global_pos):
    """Poses as feature vectors in their root frame.

    Parameters
    ----------
    skeleton : Skeleton
    global_pos : ndarray, shape (N, J, 3), metres

    Returns
    -------
    x : ndarray, shape (N, 3 B), metres
        Body joints (:func:`~posekit.data.metrics.body_joints`) in the root frame, flattened joint by
        joint (``x[:, 3 i : 3 i + 3]`` is body joint ``i``).
    origin : ndarray, shape (N, 3)
    angle : ndarray, shape (N,), radians
        The root frame (:func:`posekit.transforms.root_frame`), for :func:`poses_from_vectors`.
    """
    p = np.asarray(global_pos, dtype=float)
    if p.ndim != 3 or p.shape[1:] != (skeleton.n_joints, 3):
        raise ValueError(f"global_pos: expected shape (N, {skeleton.n_joints}, 3), got {p.shape}")
    local, origin, angle = to_root_space(skeleton, p)
    return local[:, body_joints(skeleton)].reshape(len(p), -1), origin, angle


def poses_from_vectors(skeleton, x, origin=None, angle=None) -> np.ndarray:
    """Inverse of :func:`pose_vectors`: global positions (N, J, 3) from feature vectors (N, 3 B).

    Joints that are not body joints (a helper root) are put back at their rest offset from the
    pelvis: the joints above the pelvis are taken not to rotate (true of Bandai's ``joint_Root``).
    Without ``origin``/``angle`` the poses stay in their root frame.
    """
    x = np.asarray(x, dtype=float)
    b = body_joints(skeleton)
    n = len(x)
    if x.shape[-1] != 3 * len(b):
        raise ValueError(f"x: expected {3 * len(b)} features ({len(b)} body joints of {skeleton.name or 'the skeleton'}"
                         f" x 3), got {x.shape[-1]}")
    local = np.zeros((n, skeleton.n_joints, 3))
    local[:, b] = x.reshape(n, len(b), 3)
    pel = skeleton.pelvis()
    j = pel
    while j != 0:  # the placement chain above the pelvis (Bandai: joint_Root, 0.94 m below Hips)
        parent = int(skeleton.parents[j])
        local[:, parent] = local[:, j] - skeleton.offsets[j]
        j = parent
    if origin is None:
        return local
    return from_root_space(local, origin, angle)


def targets_in_root_frame(points, origin, angle) -> np.ndarray:
    """World points (N, K, 3) expressed in the root frames ``origin`` (N, 3), ``angle`` (N,)."""
    return rotate_y_positions(np.asarray(points, dtype=float) - np.asarray(origin)[:, None, :], -np.asarray(angle))


def feature_columns(skeleton, joints) -> np.ndarray:
    """Columns of the feature vector holding ``joints`` (names, roles or indices), shape (3 K,)."""
    b = list(body_joints(skeleton))
    cols = []
    for j in joints:
        k = skeleton.index(j)
        if k not in b:
            raise ValueError(f"joint {skeleton.names[k]!r} is not a body joint of {skeleton.name or 'the skeleton'} "
                             "(a helper root carries no pose); choose a body joint")
        i = b.index(k)
        cols += [3 * i, 3 * i + 1, 3 * i + 2]
    return np.array(cols, dtype=np.int64)


@dataclass
class PoseData:
    """Training poses of one split as vectors, mirrored copies appended.

    Attributes
    ----------
    x : ndarray, shape (M, 3 B), float32, metres
        ``M = n`` poses, or ``2 n`` with mirroring (row ``n + i`` mirrors row ``i``).
    frames : ndarray of int, shape (n,)
        The MotionSet frames of the first ``n`` rows.
    mirrored : bool
    norm : NormStats
        z-score of ``x`` (std floored at :data:`STD_FLOOR`), fitted on these rows, or the one given.
    """

    x: np.ndarray
    frames: np.ndarray
    mirrored: bool
    norm: NormStats

    @property
    def n(self) -> int:
        """Poses before mirroring."""
        return len(self.frames)

    def normalized(self) -> np.ndarray:
        """``x`` z-scored, float32."""
        return self.norm.normalize(self.x).astype(np.float32)


def pose_data(motions: MotionSet, frames, mirror: bool = True, norm: NormStats | None = None) -> PoseData:
    """The poses of ``frames`` as :class:`PoseData` (mirrored copies appended when ``mirror``)."""
    frames = np.sort(np.asarray(frames, dtype=np.int64))
    if len(frames) == 0:
        raise ValueError(f"pose_data: no frames given from {motions.source!r}")
    s = motions.skeleton
    pos = motions.global_pos[frames]
    if mirror:
        pos = np.concatenate([pos, mirror_positions(s, pos)])
    x = pose_vectors(s, pos)[0]
    if norm is None:
        norm = NormStats.fit(x, eps=STD_FLOOR)
    return PoseData(x.astype(np.float32), frames, bool(mirror), norm)


def split_pose_data(motions: MotionSet | None = None, seed: int = 0):
    """What the learned lessons train on: the training split's poses (mirrored) and the val split's
    (not mirrored, the training normalisation) of ``motions`` (default the Bandai mini set, its own split;
    another set is split by clip with ``seed``, :func:`posekit.data.cases.case_split`).

    Returns
    -------
    motions : MotionSet
    train, val : PoseData
    how : str
        How the split was made.
    """
    from .cases import case_split

    if motions is None:
        from .bandai_mini import load_bandai_mini

        motions = load_bandai_mini()
    train, val, _, how = case_split(motions, seed)
    td = pose_data(motions, train, mirror=True)
    return motions, td, pose_data(motions, val, mirror=False, norm=td.norm), how
