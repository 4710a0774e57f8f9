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
from ..ik.effectors import resolve_effectors
from .screen_fit import stylesheet, view_box_layout
from .shared import widget
from .viewer import SkeletonViewer, show_widget

__all__ = ["SolverPanel", "ignored_effectors", "reached_mark", "solver_views", "solve_views", "status_line",
           "status_table", "views_row", "worst_errors"]


def _kinds_text(kinds) -> str:
    """Effector kinds as a person writes them, each once, in order: ``"rotation, look-at"``."""
    return ", ".join(dict.fromkeys(k.replace("_", "-") for k in kinds))


def status_line(result, ms: float, joints=None, ignored=()) -> str:
    """One solver's status under its view, as a small HTML table: reached or not, the worst effector
    error and its joint (mm for positions; degrees for rotation and look-at effectors, when there are any),
    iterations and time (ms). ``ignored``: effectors the solver was not given because it does not honour
    their kind — the view says so ("look-at ignored") and never calls them reached."""
    it = result.iterations
    excluded = f"<br>{_kinds_text(e.kind for e in ignored)} not measured" if ignored else ""
    return status_table(f"<b>{reached_mark(result, ignored)}</b>",
                        [("worst effector", worst_errors(result, joints, sep="<br>") + excluded),
                         (f"iteration{'' if it == 1 else 's'}", str(it)), ("time", f"{ms:.2f} ms")])


def reached_mark(result, ignored=()) -> str:
    """Whether a solver reached its effectors, as HTML: ``"✓ reached"``, ``"✗ not reached"``, or with effectors it
    ignored (not given, their kind not honoured) ``"◐ 3 of 5 reached · look-at, rotation ignored"`` — never a
    ✓ then, since an ignored effector is unmet. The views (:func:`status_line`) and the studio's summary say it in these words."""
    if not ignored:
        return "✓ reached" if result.converged else "✗ not reached"
    used = len(result.effector_error)
    mark = f"◐ {used} of {used + len(ignored)} reached" if result.converged else "✗ not reached"
    return mark + f" · <span style='color:#b9770e'>{_kinds_text(e.kind for e in ignored)} ignored</span>"


def ignored_effectors(solver, effectors) -> list:
    """The effectors ``solver`` is not given: those of a kind it does not honour (``solver.kinds``; default
    positions only)."""
    kinds = getattr(solver, "kinds", ("position",))
    return [e for e in effectors if e.kind not in kinds]


def worst_errors(result, joints=None, sep: str = ", ") -> str:
    """A result's worst effector errors as text: mm for positions, degrees for rotation and look-at effectors
    (each when there are any), each followed by its joint when ``joints`` (one name per effector, in the
    result's order) is given, e.g. ``"2.1 mm (Hand_L), 0.7° (Head)"``; ``sep`` joins the two."""
    err = np.asarray(result.effector_error, dtype=float)
    kinds = tuple(getattr(result, "kinds", ()) or ("position",) * len(err))
    angular = np.array([k != "position" for k in kinds], dtype=bool)
    parts = []
    for mask, scale, unit in ((~angular, 1000.0, " mm"), (angular, None, "°")):
        if mask.any():
            k = int(np.flatnonzero(mask)[np.argmax(err[mask])])
            value = err[k] * scale if scale else np.degrees(err[k])
            parts.append(f"{value:.1f}{unit}" + (f" ({html.escape(str(joints[k]))})" if joints is not None else ""))
    return sep.join(parts)


def status_table(title: str, rows) -> str:
    """A title over an HTML table of ``(label, value, ...)`` rows. Two-cell rows: the value right-aligned. Rows of
    more cells (the studio's summary: name, mark, errors, time) keep each column aligned: the second cell left, the
    others right-aligned in monospace; a shorter row's last cell spans the columns it lacks."""
    width = max((len(r) for r in rows), default=2)

    def cells(row):
        out = [f"<td style='padding-right:10px'>{row[0]}</td>"]
        for k, value in enumerate(row[1:], start=1):
            span = width - len(row) + 1 if k == len(row) - 1 else 1
            left = width > 2 and (k == 1 or span > 1)
            style = "padding-right:10px" + ("" if left else ";text-align:right;font-family:monospace")
            out.append(f"<td{f' colspan={span}' if span > 1 else ''} style='{style}'>{value}</td>")
        return "".join(out)

    body = "".join(f"<tr>{cells(row)}</tr>" for row in rows)
    return f"{title}<table style='border-collapse:collapse'>{body}</table>"


def solver_views(skeleton, names, pose, truth=None, width: int = 300, height: int = 330, selectable=None):
    """One viewer per solver name (the first with the joint selector and target sliders, offering the joints
    ``selectable``, default all), a status label under each: ``(viewers, labels, boxes)``, dicts by name and the
    list of titled boxes to lay out."""
    import ipywidgets as w

    viewers, labels, boxes = {}, {}, []
    for k, name in enumerate(names):
        v = SkeletonViewer(skeleton, pose, ghost=truth, width=width, height=height, controls=(k == 0),
                           selectable=selectable if k == 0 else None)
        viewers[name], labels[name] = v, widget(w.HTML)  # as wide as its view: a long message wraps
        labels[name].add_class("posekit-view-label")
        # the views share the row's width, each scaled down from its canvas's width (posekit.viz.screen_fit), never
        # squeezed into a scrolled box; a page narrower than four small views wraps them onto rows
        title = widget(w.HTML, f"<b>{html.escape(str(name))}</b>")
        title.add_class("posekit-view-title")
        boxes.append(widget(w.VBox, [title, v.renderer, labels[name]],
                            layout=view_box_layout(width)))
        boxes[-1].add_class("posekit-view")
    return viewers, labels, boxes


def views_row(boxes):
    """The row of view boxes (:func:`solver_views`), with the page's rules that scale them (a stylesheet that takes
    no room, :func:`~posekit.viz.screen_fit.stylesheet`)."""
    import ipywidgets as w

    return widget(w.HBox, [*boxes, stylesheet()], layout={"flex_flow": "row wrap", "width": "100%"})


def solve_views(skeleton, solvers: dict, viewers: dict, labels: dict, start, effectors, results: dict,
                times: dict) -> None:
    """Solve with every solver and refresh its view and status label — the one loop behind
    :class:`SolverPanel` and :class:`~posekit.viz.EffectorEditor`.

    Each solver gets the effectors of the kinds it honours (``solver.kinds``); its label names the kinds it
    ignored. A solver that raises keeps its last pose and shows why (a ``ValueError`` is a refusal, e.g. a
    joint set a network was not trained for; anything else is shown with its type); the others go on.

    Parameters
    ----------
    skeleton : Skeleton
    solvers, viewers, labels : dict
        Name -> solver, :class:`~posekit.viz.SkeletonViewer` and ipywidgets.HTML.
    start : Pose
        Start pose (passed only to solvers with ``needs_start``).
    effectors : list of Effector
    results, times : dict
        Filled in: name -> IKResult or the exception raised; name -> milliseconds of the solve.
    """
    names = [skeleton.names[skeleton.index(e.joint)] for e in effectors]
    positions = {n: e.target for n, e in zip(names, effectors) if e.kind == "position"}
    looks = {n: e.target for n, e in zip(names, effectors) if e.kind == "look_at"}
    rotations = {n: resolve_effectors(skeleton, [e]).rotation[0] for n, e in zip(names, effectors)
                 if e.kind == "rotation"}
    for name, solver in solvers.items():
        with viewers[name].drawing_once():
            _solve_one(name, solver, viewers[name], labels[name], start, effectors, names, results, times,
                       (positions, looks, rotations))


def _solve_one(name, solver, viewer, label, start, effectors, names, results, times, targets):
    """One solver of :func:`solve_views`: its targets drawn, its effectors solved, its view and label updated."""
    viewer.set_targets(*targets)
    if not effectors:
        label.value = "add an effector"
        return
    kinds = getattr(solver, "kinds", ("position",))
    use = [k for k, e in enumerate(effectors) if e.kind in kinds]
    ignored = ignored_effectors(solver, effectors)
    if not use:
        results.pop(name, None)
        label.value = (f"<b>nothing to solve</b><br>{html.escape(name)} honours "
                       f"{_kinds_text(kinds)} effectors only: {_kinds_text(e.kind for e in ignored)} ignored")
        return
    t = time.perf_counter()
    try:
        res = solver.solve(start if getattr(solver, "needs_start", True) else None, [effectors[k] for k in use])
    except Exception as err:  # noqa: BLE001 - a solver that fails says why in its view; the others go on
        results[name] = err
        what = "" if isinstance(err, ValueError) else f"{type(err).__name__}: "
        label.value = f"<b>✗ cannot solve</b><br>{html.escape(what + str(err))}"
        return
    ms = (time.perf_counter() - t) * 1e3
    results[name], times[name] = res, ms
    viewer.set_pose(res.pose.global_pos)
    label.value = status_line(res, ms, [names[k] for k in use], ignored)


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
        Initial effectors (one per joint: the viewer moves one point per joint); the first view offers their
        joints (``selectable``); moving a look-at target moves the point looked at; :meth:`move_target` on a
        joint without one adds a position effector.
    truth : ndarray, shape (J, 3), optional
        Shown as the ghost in every viewer.
    selectable : sequence of str, optional
        The joints the first view offers; default the joints of ``effectors`` and every joint to which each solver
        accepts one more position effector (:meth:`usable_joints`): a slider never gives a joint a new effector
        that a solver of the panel refuses (lesson 03's network takes only the joint sets it was trained for).
        *remove target* takes the selected joint's effector away again.

    Attributes
    ----------
    widget : ipywidgets.VBox
    results : dict
        Name -> last :class:`~posekit.ik.api.IKResult`, or the exception the solver raised (its view then
        shows the message and keeps its last pose; e.g. a neural solver asked for a joint set it has no
        network for). Each solver gets the effectors of the kinds it honours; its view names the others
        as ignored (:func:`solve_views`).
    times : dict
        Name -> milliseconds of its last solve.
    """

    def __init__(self, skeleton, solvers: dict, start: Pose, effectors, truth=None, width: int = 300,
                 height: int = 330, selectable=None):
        import ipywidgets as w

        self.skeleton = skeleton
        self.solvers = dict(solvers)
        self.start = start
        self.effectors = {skeleton.names[skeleton.index(e.joint)]: e for e in effectors}
        self.results, self.times = {}, {}
        if selectable is None:
            selectable = self.usable_joints()
        self.viewers, self.labels, boxes = solver_views(skeleton, self.solvers, start.global_pos, truth, width, height,
                                                        selectable)
        first = next(iter(self.viewers.values()))
        first.on_target_change(self._on_target)
        first.on_look_target_change(self._on_target)
        self.remove_button = widget(w.Button, description="remove target", icon="times", layout={"width": "130px"},
                                    tooltip="take the selected joint's effector away")
        self.remove_button.on_click(lambda _: self.remove_effector(first.selected))
        self.message = widget(w.HTML)
        self.widget = widget(w.VBox, [views_row(boxes), first.controls,
                                      widget(w.HBox, [self.remove_button, self.message],
                                             layout={"align_items": "center"})])
        self.solve()

    def _ipython_display_(self):
        show_widget(self.widget, f"[live 3D views of {', '.join(self.solvers)}, posing one skeleton side by side. They "
                                 "draw in a running Jupyter kernel; run the notebook to move the targets]")

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

    def usable_joints(self) -> list:
        """The body joints every solver of the panel takes: those of the effectors, and each other joint to which
        every solver accepts one more position effector (each is asked once, on the start pose; a ValueError is a
        refusal)."""
        from ..data.metrics import body_joints

        base, P = list(self.effectors.values()), np.asarray(self.start.global_pos, float)
        usable = []
        for j in body_joints(self.skeleton):
            name = self.skeleton.names[int(j)]
            trial = base + [Effector(name, P[int(j)])]
            if name in self.effectors or all(_accepts(s, self.start, trial) for s in self.solvers.values()):
                usable.append(name)
        return usable

    def remove_effector(self, joint):
        """Take ``joint``'s effector away (its marker goes) and re-solve; the last effector stays (with a message)."""
        if joint is None or self.skeleton.names[self.skeleton.index(joint)] not in self.effectors:
            self.message.value = "select a joint with a target first"
            return
        name = self.skeleton.names[self.skeleton.index(joint)]
        if len(self.effectors) == 1:
            self.message.value = f"<span style='color:#b03a2e'>{html.escape(name)} holds the only effector</span>"
            return
        del self.effectors[name]
        self.message.value = ""
        self.solve()

    def move_target(self, joint, position):
        """Move (or add) the target of a joint and re-solve, as the sliders do."""
        name = self.skeleton.names[self.skeleton.index(joint)]
        next(iter(self.viewers.values())).move_target(name, position)

    def solve(self):
        """Solve with every solver and refresh the views (:func:`solve_views`)."""
        solve_views(self.skeleton, self.solvers, self.viewers, self.labels, self.start,
                    list(self.effectors.values()), self.results, self.times)


def _accepts(solver, start, effectors) -> bool:
    """Whether ``solver`` solves ``effectors`` (those of the kinds it honours) without refusing them."""
    kinds = getattr(solver, "kinds", ("position",))
    use = [e for e in effectors if e.kind in kinds]
    if not use:
        return True
    try:
        solver.solve(start if getattr(solver, "needs_start", True) else None, use)
    except Exception:  # noqa: BLE001 - a refusal (ValueError) or a failure: either way the view could not solve
        return False
    return True
