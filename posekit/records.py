"""The plain records every layer passes around: :class:`Pose` (a posed skeleton) and :class:`NormStats`
(a z-score).

They sit in the core, beside :mod:`posekit.skeleton` and :mod:`posekit.kinematics`, so that the data layer
(held-out cases hand out start poses), the solvers (:mod:`posekit.ik.api` takes and returns poses) and the
checkpoints (:mod:`posekit.learn.checkpoint` stores normalisations) share them without importing each
other. ``Pose`` is introduced in ``notebooks/01_fabrik.ipynb``, ``NormStats`` in
``notebooks/00_skeletons_and_poses.ipynb``. Units and axes: :mod:`posekit.conventions`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .kinematics import fk
from .skeleton import Skeleton

__all__ = ["Pose", "NormStats"]


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
        c = lambda a: None if a is None else np.array(a, copy=True)  # noqa: E731
        return Pose(self.global_pos.copy(), c(self.local_rot), c(self.root_pos), c(self.local_pos))



@dataclass
class NormStats:
    """Per-feature z-score statistics: ``(x - mean) / std``.

    Attributes
    ----------
    mean, std : ndarray, shape (D,) (or any feature shape)
    """

    mean: np.ndarray
    std: np.ndarray

    @classmethod
    def fit(cls, x, eps: float = 1e-6) -> "NormStats":
        """Statistics over the first axis of ``x`` (N, ...); ``std`` is floored at ``eps`` so
        constant features do not divide by zero."""
        x = np.asarray(x, dtype=float)
        if x.ndim < 1 or len(x) == 0:
            raise ValueError("NormStats.fit needs at least one sample")
        if not np.all(np.isfinite(x)):
            raise ValueError("NormStats.fit: data contains NaN or inf")
        return cls(x.mean(axis=0), np.maximum(x.std(axis=0), eps))

    def normalize(self, x):
        return (np.asarray(x, dtype=float) - self.mean) / self.std

    def denormalize(self, z):
        return np.asarray(z, dtype=float) * self.std + self.mean

    def to_arrays(self, prefix: str = "norm_") -> dict:
        """``{prefix + "mean": mean, prefix + "std": std}``, e.g. for ``np.savez`` or a checkpoint
        (:func:`posekit.learn.save_checkpoint`)."""
        return {prefix + "mean": self.mean, prefix + "std": self.std}

    @classmethod
    def from_arrays(cls, arrays, prefix: str = "norm_") -> "NormStats":
        """Inverse of :meth:`to_arrays` (float64 arrays)."""
        return cls(np.asarray(arrays[prefix + "mean"], dtype=float), np.asarray(arrays[prefix + "std"], dtype=float))

    def same_as(self, other: "NormStats", rtol: float = 1e-6) -> bool:
        """Same shapes and values to ``rtol``: a model trained on one must not be fed the other."""
        a, b = np.asarray(self.mean), np.asarray(other.mean)
        sa, sb = np.asarray(self.std), np.asarray(other.std)
        return (a.shape == b.shape and sa.shape == sb.shape and np.allclose(a, b, rtol=rtol)
                and np.allclose(sa, sb, rtol=rtol))
