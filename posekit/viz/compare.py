"""Several solvers posing the same skeleton side by side, live, in the notebook.

Introduced in ``notebooks/01_fabrik.ipynb`` (FABRIK, CCD and DLS); later lessons add their learned
solvers. Talks to solvers only through the :class:`~posekit.ik.api.Solver` interface.
"""

from __future__ import annotations

import html
import time
from dataclasses import replace

import numpy as np

from ..ik.api import Effector, Pose
from .viewer import SkeletonViewer

__all__ = ["SolverPanel", "solver_views", "status_line", "status_table", "worst_errors"]


def status_line(result, ms: float) -> str:
    """One solver's status under its view, as a small HTML table: reached or not, the worst effector
    error (mm for positions; degrees for rotation and look-at effectors, when there are any), iterations
    and time (ms)."""
    mark = "✓ reached" if result.converged else "✗ not reached"
    it = result.iterations
    return status_table(f"<b>{mark}</b>", [("worst effector", worst_errors(result)),
                                           (f"iteration{'' if it == 1 else 's'}", str(it)), ("time", f"{ms:.2f} ms")])


def worst_errors(result) -> str:
    """A result's worst effector errors as text: mm for positions, degrees for rotation and look-at effectors
    (each when there are any), e.g. ``"2.1 mm, 0.7°"``."""
    err = np.asarray(result.effector_error, dtype=float)
    kinds = tuple(getattr(result, "kinds", ()) or ("position",) * len(err))
    angular = np.array([k != "position" for k in kinds], dtype=bool)
    parts = []
    if (~angular).any():
        parts.append(f"{err[~angular].max() * 1000:.1f} mm")
    if angular.any():
        parts.append(f"{np.degrees(err[angular].max()):.1f}°")
    return ", ".join(parts)


def status_table(title: str, rows) -> str:
    """A title over a two-column HTML table of ``(label, value)`` rows (values right-aligned)."""
    body = "".join(f"<tr><td style='padding-right:10px'>{label}</td>"
                   f"<td style='text-align:right;font-family:monospace'>{value}</td></tr>" for label, value in rows)
    return f"{title}<table style='border-collapse:collapse'>{body}</table>"


def solver_views(skeleton, names, pose, truth=None, width: int = 300, height: int = 330):
    """One viewer per solver name (the first with the joint selector and target sliders), a status label
    under each: ``(viewers, labels, boxes)``, dicts by name and the list of titled boxes to lay out."""
    import ipywidgets as w

    viewers, labels, boxes = {}, {}, []
    for k, name in enumerate(names):
        v = SkeletonViewer(skeleton, pose, ghost=truth, width=width, height=height, controls=(k == 0))
        viewers[name], labels[name] = v, w.HTML()
        boxes.append(w.VBox([w.HTML(f"<b>{html.escape(str(name))}</b>"), v.renderer, labels[name]]))
    return viewers, labels, boxes


class SolverPanel:
    """One viewer per solver; the first viewer's joint selector, double-click picking and X/Y/Z
    sliders move a target, and every solver re-solves from the same start pose.

    Parameters
    ----------
    skeleton : Skeleton
    solvers : dict
        Name -> solver (anything with ``solve(start, effectors)``; e.g. from
        :func:`posekit.ik.make_solver`).
    start : Pose
        Start pose of every solve (rotation-based solvers need its rotations).
    effectors : list of Effector
        Initial effectors (one per joint: the viewer moves one point per joint); moving a joint
        without one adds a position effector, moving a look-at target moves the point looked at.
    truth : ndarray, shape (J, 3), optional
        Shown as the ghost in every viewer.

    Attributes
    ----------
    widget : ipywidgets.VBox
    results : dict
        Name -> last :class:`~posekit.ik.api.IKResult`, or the ``ValueError`` the solver raised (its
        view then shows the message and keeps its last pose; e.g. a neural solver asked for a joint set
        it has no network for).
    """

    def __init__(self, skeleton, solvers: dict, start: Pose, effectors, truth=None, width: int = 300,
                 height: int = 330):
        import ipywidgets as w

        self.skeleton = skeleton
        self.solvers = dict(solvers)
        self.start = start
        self.effectors = {skeleton.names[skeleton.index(e.joint)]: e for e in effectors}
        self.results = {}
        self.viewers, self.labels, boxes = solver_views(skeleton, self.solvers, start.global_pos, truth, width, height)
        first = next(iter(self.viewers.values()))
        first.on_target_change(self._on_target)
        self.widget = w.VBox([w.HBox(boxes), first.controls])
        self.solve()

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)

    def _on_target(self, joint, position):
        # the viewer moves points: a position or look-at effector keeps its kind, tolerance and weight
        # and gets the new point; a joint without one (or with a rotation effector) gets a position one
        old = self.effectors.get(joint)
        position = np.asarray(position, float)
        if old is not None and old.kind in ("position", "look_at"):
            self.effectors[joint] = replace(old, target=position)
        else:
            self.effectors[joint] = Effector(joint, position)
        self.solve()

    def move_target(self, joint, position):
        """Move (or add) the target of a joint and re-solve, as the sliders do."""
        name = self.skeleton.names[self.skeleton.index(joint)]
        next(iter(self.viewers.values())).move_target(name, position)

    def solve(self):
        """Solve with every solver and refresh the views."""
        effs = list(self.effectors.values())
        # points to draw: position and look-at targets (a rotation has none)
        targets = {self.skeleton.names[self.skeleton.index(e.joint)]: e.target for e in effs
                   if e.kind in ("position", "look_at")}
        looks = {self.skeleton.names[self.skeleton.index(e.joint)]: e.target for e in effs if e.kind == "look_at"}
        for name, solver in self.solvers.items():
            t = time.perf_counter()
            try:
                res = solver.solve(self.start, effs)
            except ValueError as err:  # a solver that refuses these effectors says why; the others go on
                self.results[name] = err
                self.labels[name].value = f"<b>✗ cannot solve</b><br>{html.escape(str(err))}"
                continue
            ms = (time.perf_counter() - t) * 1e3
            self.results[name] = res
            v = self.viewers[name]
            v.set_pose(res.pose.global_pos)
            v.set_targets(targets, looks)
            self.labels[name].value = status_line(res, ms)
