"""The posing studio's files out and in: the chosen solver's pose as BVH, every view as a PNG, a start pose
read from a BVH file.

Introduced in ``notebooks/06_posing_studio.ipynb`` with :class:`posekit.viz.studio.PosingStudio`, whose mixin
this is. Every file is read back or linked for download in the studio's message line; written under the
studio's ``export_dir``. Positions in metres (:mod:`posekit.conventions`).

**Views as PNG: the views themselves.** The *views as PNG* button asks the page for every view's own pixels: a
page-side widget in the studio (:class:`~posekit.viz.canvas_capture.CanvasCapture`) reads each view's WebGL canvas
(``canvas.toDataURL()``; pythreejs keeps the drawn frame, ``preserveDrawingBuffer``) with the view's title and
status text as the page shows them, and sends them back; the kernel lays them out in one row, each title above its
view and its status lines (reached, worst effector, iterations, time) below
(:func:`~posekit.viz.views_picture.compose_views`), and writes the PNG. The picture is what the views show: the
same camera (an orbit or zoom included), colours, ghost, targets, scale and the status of the same solve. The page
answers after the button's handler has returned, so the file is written, and its link shown, a moment later.

A kernel without a page (a script, a notebook run by nbval, :meth:`StudioExport.export_png` called in a cell, where
the kernel cannot read the page's answer until the cell ends) gets the earlier drawing instead: each pose redrawn by
matplotlib, titled with its solve time — another camera and style than the views, and the message says so.
"""

from __future__ import annotations

import base64
import html
from pathlib import Path

import numpy as np

from ..ik.api import Pose

__all__ = ["StudioExport", "link"]


def link(path: Path, mime: str) -> str:
    """An HTML download link that carries the file ``path`` itself (a data URL: no server route needed)."""
    data = base64.b64encode(Path(path).read_bytes()).decode()
    name = html.escape(Path(path).name)
    return f"<a download='{name}' href='data:{mime};base64,{data}'>download {name}</a>"


class StudioExport:
    """Export and import for :class:`~posekit.viz.studio.PosingStudio` (a mixin: the studio holds ``editor``,
    ``skeleton``, ``start``, ``solvers``, ``export_solver``, ``export_dir`` and ``message``)."""

    def _pose_of(self, name):
        res = self.editor.results.get(name)
        if res is None or isinstance(res, Exception):
            raise ValueError(f"{name} has no pose to export" + (f" (it failed: {res})" if res is not None else ""))
        return res.pose

    def export_bvh(self, path=None, solver=None) -> Path:
        """Write ``solver``'s (default: the export choice's) pose as a one-frame BVH, read it back and say how
        far the read-back joints are from the view's."""
        from ..ik.keyframes import write_poses_bvh
        from ..io.bvh import read_bvh

        name = solver or self.export_solver.value
        pose = self._pose_of(name)
        path = Path(path or self.export_dir / f"pose_{name}.bvh")
        path.parent.mkdir(parents=True, exist_ok=True)
        write_poses_bvh(path, self.skeleton, [pose], self.start)
        back = read_bvh(path).global_positions()[0]
        diff = np.abs(back - pose.global_pos).max() * 1000
        self.message.row = "export"
        self.message.value = (f"wrote {html.escape(str(path))}: {html.escape(name)}'s pose, read back within "
                              f"{diff:.3f} mm — {link(path, 'text/plain')}")
        return path

    def export_png(self, path=None, from_page: bool = False) -> Path:
        """Write every view as one PNG (default ``export_dir/views.png``); returns its path.

        With ``from_page`` (the *views as PNG* button) and a page showing the studio, the views' own pixels, titles
        and status lines are read from the page and the file is written when they arrive (the module docstring);
        otherwise, or without a page, each pose is drawn here by matplotlib (another camera and style than the
        views, titled with its solve time) and the file is there when this returns."""
        path = Path(path or self.export_dir / "views.png")
        capture = getattr(self, "views_capture", None)
        if from_page and capture is not None and capture.shown:
            self.message.row = "export"
            self.message.value = f"reading the {len(self.solvers)} views from the page…"
            capture.capture(lambda views: self._write_views(path, views))
            return path
        return self._draw_views(path)

    def _write_views(self, path: Path, views) -> None:
        """Compose the pictures the page sent (:meth:`CanvasCapture.capture`) into ``path``; say so, or what went
        wrong, on the export line."""
        from .views_picture import compose_views

        self.message.row = "export"
        try:
            if not views or any(v["png"] is None for v in views):
                raise ValueError("the page sent no picture of some view (is every view drawn?)")
            image, _ = compose_views([v["png"] for v in views], [v["title"] for v in views],
                                     [v["label"] for v in views])
            path.parent.mkdir(parents=True, exist_ok=True)
            image.save(path)
        except (ValueError, OSError) as err:
            self.message.value = f"<span style='color:#b03a2e'>views as PNG: {html.escape(str(err))}</span>"
            return
        self.message.value = (f"wrote {html.escape(str(path))}: the {len(views)} views as the page shows them — "
                              f"{link(path, 'image/png')}")

    def _draw_views(self, path: Path) -> Path:
        """Draw every view's pose (matplotlib, one 3D axes each, titled with its solve time) into ``path``."""
        import matplotlib

        from matplotlib.figure import Figure

        from .plot import plot_pose

        matplotlib.rcParams.setdefault("figure.dpi", 100)
        names = self.solvers
        fig = Figure(figsize=(3.2 * len(names), 3.6))
        targets = [r["target"] for r in self.editor.rows if r["kind"] == "position"]
        for k, name in enumerate(names):
            ax = fig.add_subplot(1, len(names), k + 1, projection="3d")
            res = self.editor.results.get(name)
            if res is None or isinstance(res, Exception):
                ax.set_title(f"{name}\n(no pose)", fontsize=9)
                continue
            plot_pose(self.skeleton, res.pose.global_pos, ax=ax, targets=np.array(targets) if targets else None,
                      title=f"{name}\n{self.editor.times.get(name, 0):.1f} ms")
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=120, bbox_inches="tight")  # the side key stands above the panels (trimmed: 120 dpi)
        self.message.row = "export"
        self.message.value = (f"wrote {html.escape(str(path))}: the poses drawn by the kernel (no page to read the "
                              f"views from) — {link(path, 'image/png')}")
        return path

    def load_start_bvh(self, path, frame: int = 0):
        """Use frame ``frame`` of a BVH file (this skeleton's joints) as the start pose; re-solve. A malformed
        file or another skeleton raises ValueError naming the file (and line) and changes nothing."""
        from ..io.bvh import read_bvh

        motion = read_bvh(path)
        names = list(motion.skeleton.names)
        if names != list(self.skeleton.names):
            raise ValueError(f"{path}: its skeleton ({len(names)} joints: {', '.join(names[:4])}, ...) is not the "
                             f"studio's ({self.skeleton.n_joints}: {', '.join(self.skeleton.names[:4])}, ...)")
        if not 0 <= frame < motion.n_frames:
            raise ValueError(f"{path}: frame {frame} out of range (the file has {motion.n_frames})")
        lp = None if motion.local_pos is None else motion.local_pos[frame]
        self.start = Pose.from_rotations(self.skeleton, motion.local_rot[frame], motion.root_pos[frame], lp)
        self.session.start = self.editor.start = self.start
        self.editor.solve()
        self._refresh()
        self.message.row = "setup"  # a start pose comes through the upload box
        self.message.value = f"start pose: frame {frame} of {html.escape(str(path))}"
