"""The posing studio's timeline: key effector setups, in-betweens posed by one solver, played back and
exported as an animated BVH.

Introduced in ``notebooks/06_posing_studio.ipynb`` with :class:`posekit.viz.studio.PosingStudio`, whose mixin
this is; the in-betweens and the sequence solve are :mod:`posekit.ik.keyframes`.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from .studio_export import link

__all__ = ["StudioTimeline"]


class StudioTimeline:
    """Keys and their animation for :class:`~posekit.viz.studio.PosingStudio` (a mixin: the studio holds
    ``session`` (whose keys these are), ``editor``, ``frames``, ``keys_label``, ``timeline_box``, ``inbetweens``, ``ease``, ``size``,
    ``start``, ``export_solver``, ``export_dir`` and ``message``)."""

    def add_key(self):
        """Store the current effectors as the next key of the timeline."""
        self.session.add_key()  # refuses no effectors, or others than the first key's
        self.keys_label.value = f"{len(self.keys)} key{'s' if len(self.keys) > 1 else ''}"

    def clear_keys(self):
        """Forget every key and the built animation."""
        self.session.clear_keys()
        self.frames = []
        self.keys_label.value = "no keys yet"
        self.timeline_box.children = ()

    def build_animation(self, solver=None):
        """Pose the keys and their in-betweens with ``solver`` (default the export choice), each frame from
        the previous one, and show them in a player. Returns the results, one per frame."""
        from ..ik.keyframes import inbetween_effectors, solve_sequence
        from .viewer import SkeletonViewer

        name = solver or self.export_solver.value
        if len(self.keys) < 2:
            raise ValueError(f"a timeline needs at least two keys, got {len(self.keys)}: pose, add key, pose, add key")
        s = self.session.solvers[name]
        frames = inbetween_effectors(self.skeleton, self.session.key_effectors(name), int(self.inbetweens.value),
                                     self.ease.value)
        self.frames = solve_sequence(s, self.start, frames, progress=True)
        self._frames_solver = name
        h = self.size[1]
        v = SkeletonViewer(self.skeleton, self.frames[0].pose.global_pos, width=2 * (self.size[0] or 420), height=h,
                           controls=False)
        v.player(np.stack([r.pose.global_pos for r in self.frames]))
        self.timeline_viewer = v
        self.timeline_box.children = (v.widget,)
        self.message.row = "timeline"
        self.message.value = f"{len(self.frames)} frames posed by {html.escape(name)}"
        return self.frames

    def export_animation(self, path=None, frame_time: float = 1 / 30) -> Path:
        """Write the built animation as a BVH (``frame_time`` seconds per frame) and read it back."""
        from ..ik.keyframes import write_poses_bvh
        from ..io.bvh import read_bvh

        if not self.frames:
            raise ValueError("build the animation first (two keys or more, then build animation)")
        path = Path(path or self.export_dir / f"animation_{self._frames_solver}.bvh")
        path.parent.mkdir(parents=True, exist_ok=True)
        poses = [r.pose for r in self.frames]
        write_poses_bvh(path, self.skeleton, poses, self.start, frame_time)
        back = read_bvh(path)
        diff = np.abs(back.global_positions() - np.stack([p.global_pos for p in poses])).max() * 1000
        self.message.row = "timeline"
        self.message.value = (f"wrote {html.escape(str(path))}: {back.n_frames} frames at {1 / frame_time:.0f} fps, "
                              f"read back within {diff:.3f} mm — {link(path, 'text/plain')}")
        return path
