"""Several solvers posing the same skeleton side by side, live, in the notebook.

Introduced in ``notebooks/01_fabrik.ipynb`` (FABRIK, CCD and DLS); later lessons add their learned
solvers. Talks to solvers only through the :class:`~posekit.ik.api.Solver` interface.
"""

from __future__ import annotations

import time

import numpy as np

from ..ik.api import Effector, Pose
from .viewer import SkeletonViewer

__all__ = ["SolverPanel"]


def status_line(result, ms: float) -> str:
    """One solver's status under its view, as HTML on three lines: reached or not, the worst
    effector error (mm), iterations and time (ms)."""
    mark = "✓ reached" if result.converged else "✗ not reached"
    it = result.iterations
    return (f"<b>{mark}</b><br>worst effector {result.effector_error.max() * 1000:.1f} mm<br>"
            f"{it} iteration{'' if it == 1 else 's'}, {ms:.2f} ms")


class SolverPanel:
    """One viewer per solver; the first viewer's joint selector, double-click picking and X/Y/Z
    sliders move a target, and every solver re-solves from the same start pose.

    Parameters
    ----------
    skeleton : Skeleton
    solvers : dict
        Name -> solver (anything with ``solve(start, effectors)``).
    start : Pose
        Start pose of every solve (rotation-based solvers need its rotations).
    effectors : list of Effector
        Initial effectors; moving a joint without one adds it.
    truth : ndarray, shape (J, 3), optional
        Shown as the ghost in every viewer.

    Attributes
    ----------
    widget : ipywidgets.VBox
    results : dict
        Name -> last :class:`~posekit.ik.api.IKResult`.
    """

    def __init__(self, skeleton, solvers: dict, start: Pose, effectors, truth=None, width: int = 300,
                 height: int = 330):
        import ipywidgets as w

        self.skeleton = skeleton
        self.solvers = dict(solvers)
        self.start = start
        self.effectors = {skeleton.names[skeleton.index(e.joint)]: e for e in effectors}
        self.viewers, self.labels, self.results = {}, {}, {}
        boxes = []
        for k, name in enumerate(self.solvers):
            v = SkeletonViewer(skeleton, start.global_pos, ghost=truth, width=width, height=height, controls=(k == 0))
            self.viewers[name] = v
            self.labels[name] = w.HTML()
            boxes.append(w.VBox([w.HTML(f"<b>{name}</b>"), v.renderer, self.labels[name]]))
        first = next(iter(self.viewers.values()))
        first.on_target_change(self._on_target)
        self.widget = w.VBox([w.HBox(boxes), first.controls])
        self.solve()

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)

    def _on_target(self, joint, position):
        old = self.effectors.get(joint)
        tol = old.tolerance if old is not None else 1e-3
        self.effectors[joint] = Effector(joint, np.asarray(position, float), tolerance=tol)
        self.solve()

    def move_target(self, joint, position):
        """Move (or add) the target of a joint and re-solve, as the sliders do."""
        name = self.skeleton.names[self.skeleton.index(joint)]
        next(iter(self.viewers.values())).move_target(name, position)

    def solve(self):
        """Solve with every solver and refresh the views."""
        effs = list(self.effectors.values())
        targets = {e.joint if isinstance(e.joint, str) else self.skeleton.names[e.joint]: e.target for e in effs}
        for name, solver in self.solvers.items():
            t = time.perf_counter()
            res = solver.solve(self.start, effs)
            ms = (time.perf_counter() - t) * 1e3
            self.results[name] = res
            v = self.viewers[name]
            v.set_pose(res.pose.global_pos)
            v.set_targets(targets)
            self.labels[name].value = status_line(res, ms)
