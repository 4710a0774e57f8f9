"""``MotionSet``: many clips of one skeleton in flat per-frame arrays.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``. Shapes and units:
:mod:`posekit.conventions`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..kinematics import fk
from ..skeleton import Skeleton

__all__ = ["MotionSet"]


@dataclass
class MotionSet:
    """Clips of one skeleton, frames of all clips concatenated.

    Attributes
    ----------
    skeleton : Skeleton
        J joints.
    local_rot : ndarray, shape (F, J, 4)
        Local quaternions ``(x, y, z, w)``.
    root_pos : ndarray, shape (F, 3), metres
    global_pos : ndarray, shape (F, J, 3), metres
        FK of the above (kept so position-based code needs no FK).
    clip_id : ndarray of int, shape (F,)
        Clip index of each frame; frames of a clip are contiguous and in time order.
    clip_names : list of str, length C
    frame_time : ndarray, shape (C,), seconds per frame of each clip
    local_pos : ndarray, shape (F, J, 3), optional
        Per-frame joint translations when the source animates more than the root (BVH position
        channels); None means ``skeleton.offsets``.
    source : str
        Where the data came from.
    units : posekit.io.rigs.UnitGuess, optional
        The file unit detected (or given) when read from BVH, and the scale applied to it.
    rig : str
        The naming convention recognised (``"cmu"``, ``"mixamo"``, ... see :mod:`posekit.io.rigs`).
    """

    skeleton: Skeleton
    local_rot: np.ndarray
    root_pos: np.ndarray
    global_pos: np.ndarray
    clip_id: np.ndarray
    clip_names: list
    frame_time: np.ndarray
    local_pos: np.ndarray | None = None
    source: str = ""
    units: object = None
    rig: str = ""
    _starts: np.ndarray = field(default=None, repr=False)

    def __post_init__(self):
        F, J = len(self.local_rot), self.skeleton.n_joints
        self.local_rot = np.asarray(self.local_rot, dtype=float)
        self.root_pos = np.asarray(self.root_pos, dtype=float)
        self.global_pos = np.asarray(self.global_pos, dtype=float)
        self.clip_id = np.asarray(self.clip_id, dtype=np.int64)
        self.clip_names = [str(c) for c in self.clip_names]
        self.frame_time = np.asarray(self.frame_time, dtype=float).reshape(-1)
        for name, arr, shape in (("local_rot", self.local_rot, (F, J, 4)), ("root_pos", self.root_pos, (F, 3)),
                                 ("global_pos", self.global_pos, (F, J, 3)), ("clip_id", self.clip_id, (F,))):
            if arr.shape != shape:
                raise ValueError(f"MotionSet.{name}: expected shape {shape}, got {arr.shape}")
        if self.local_pos is not None:
            self.local_pos = np.asarray(self.local_pos, dtype=float)
            if self.local_pos.shape != (F, J, 3):
                raise ValueError(f"MotionSet.local_pos: expected shape {(F, J, 3)}, got {self.local_pos.shape}")
        C = len(self.clip_names)
        if self.frame_time.shape != (C,):
            raise ValueError(f"MotionSet.frame_time: expected one value per clip ({C}), got {self.frame_time.shape}")
        if F and (self.clip_id.min() < 0 or self.clip_id.max() >= C or np.any(np.diff(self.clip_id) < 0)):
            raise ValueError("MotionSet.clip_id: expected non-decreasing clip indices in 0..C-1")
        self._starts = np.searchsorted(self.clip_id, np.arange(C + 1))

    # ------------------------------------------------------------------ sizes
    @property
    def n_frames(self) -> int:
        return int(self.local_rot.shape[0])

    @property
    def n_clips(self) -> int:
        return len(self.clip_names)

    def __len__(self) -> int:
        return self.n_frames

    def clip_frames(self, clip) -> np.ndarray:
        """Frame indices of one clip (by index or name), in time order."""
        c = self.clip_names.index(clip) if isinstance(clip, str) else int(clip)
        if not 0 <= c < self.n_clips:
            raise ValueError(f"clip {clip!r} not found; valid: {', '.join(self.clip_names)}")
        return np.arange(self._starts[c], self._starts[c + 1])

    def clip_lengths(self) -> np.ndarray:
        """Frames per clip, shape (C,)."""
        return np.diff(self._starts)

    def duration(self) -> float:
        """Total duration in seconds."""
        return float(np.sum(self.clip_lengths() * self.frame_time))

    def summary(self) -> list[dict]:
        """One row per clip: name, frames, seconds."""
        return [
            {"clip": n, "frames": int(k), "seconds": round(float(k * t), 2)}
            for n, k, t in zip(self.clip_names, self.clip_lengths(), self.frame_time)
        ]

    # ------------------------------------------------------------------ views
    def select(self, frames) -> "MotionSet":
        """A new set of the given frames (sorted by clip; clips with no frame are dropped)."""
        frames = np.sort(np.asarray(frames, dtype=np.int64))
        kept = np.unique(self.clip_id[frames])
        remap = np.full(self.n_clips, -1)
        remap[kept] = np.arange(len(kept))
        return MotionSet(
            self.skeleton, self.local_rot[frames], self.root_pos[frames], self.global_pos[frames],
            remap[self.clip_id[frames]], [self.clip_names[c] for c in kept], self.frame_time[kept],
            None if self.local_pos is None else self.local_pos[frames], self.source, self.units, self.rig,
        )

    def recompute_global(self) -> "MotionSet":
        """Recompute ``global_pos`` by FK (after editing rotations)."""
        if self.local_pos is None:
            self.global_pos = fk(self.skeleton, self.local_rot, self.root_pos)[0]
        else:
            self.global_pos = fk(self.skeleton, self.local_rot, self.root_pos, self.local_pos)[0]
        return self

    # ------------------------------------------------------------------ io
    def arrays(self) -> dict:
        """The arrays :meth:`save` writes: the skeleton's (``skeleton_*``), ``local_rot``, ``root_pos``,
        ``global_pos``, ``clip_id``, ``clip_names``, ``frame_time`` and, when set, ``local_pos``."""
        arrays = {
            **self.skeleton.to_arrays(),
            "local_rot": self.local_rot, "root_pos": self.root_pos, "global_pos": self.global_pos,
            "clip_id": self.clip_id, "clip_names": np.array(self.clip_names, dtype=str),
            "frame_time": self.frame_time,
        }
        if self.local_pos is not None:
            arrays["local_pos"] = self.local_pos
        return arrays

    def save(self, path, **extra):
        """Save as ``.npz`` (see :meth:`load`); ``extra`` arrays are stored beside :meth:`arrays` (``posekit data
        convert`` adds ``names``, ``parents`` and ``positions`` for readers that want positions only)."""
        np.savez_compressed(path, **self.arrays(), **extra)

    @classmethod
    def load(cls, path, source: str | None = None) -> "MotionSet":
        """Load a file written by :meth:`save`, by ``posekit data convert`` or by ``posekit data build-sample``.

        Raises
        ------
        ValueError
            A sentence naming the file when it is not an ``.npz`` numpy can read, lacks an array a motion set
            needs (a file of joint positions only, as ``posekit data convert`` wrote before it kept rotations,
            is told apart), or holds arrays of the wrong shapes.
        """
        import zipfile

        path = str(path)
        try:
            z = np.load(path, allow_pickle=False)
            if not hasattr(z, "files"):
                raise ValueError(f"{path}: holds one numpy array, not an .npz archive of named arrays")
            with z:
                have = set(z.files)
                need = {"skeleton_names", "skeleton_parents", "skeleton_offsets", "skeleton_roles", "skeleton_name",
                        "local_rot", "root_pos", "global_pos", "clip_id", "clip_names", "frame_time"}
                lacking = sorted(need - have)
                if lacking:
                    if {"names", "parents", "positions"} <= have:
                        raise ValueError(f"{path}: holds joint positions only (an older `posekit data convert` wrote "
                                         "it), without the joint rotations posekit's commands need; convert the BVH "
                                         "again with this posekit's `posekit data convert`")
                    shown = ", ".join(lacking[:4]) + (f" and {len(lacking) - 4} more" if len(lacking) > 4 else "")
                    raise ValueError(f"{path}: not a posekit motion file: it lacks {shown} (posekit reads the .npz "
                                     "files that `posekit data convert` and MotionSet.save write)")
                return cls(
                    Skeleton.from_arrays(z), z["local_rot"], z["root_pos"], z["global_pos"], z["clip_id"],
                    list(z["clip_names"]), z["frame_time"], z["local_pos"] if "local_pos" in z.files else None,
                    source or path,
                )
        except ValueError as e:
            text = str(e)
            if text.startswith(path + ":"):
                raise
            if "pickle" in text:  # numpy's advice to load with allow_pickle: never ours to give
                raise ValueError(f"{path}: not a posekit .npz (numpy cannot read it as an archive of arrays)") from None
            raise ValueError(f"{path}: not a posekit motion file ({text})") from None
        except (zipfile.BadZipFile, EOFError, KeyError, OSError) as e:
            if isinstance(e, (FileNotFoundError, IsADirectoryError, PermissionError)):
                raise
            raise ValueError(f"{path}: a broken .npz (numpy cannot read it: {e})") from None
