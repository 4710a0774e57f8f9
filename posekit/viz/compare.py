"""Several solvers posing the same skeleton side by side, live, in the notebook.

Introduced in ``notebooks/01_fabrik.ipynb`` (FABRIK, CCD and DLS); later lessons add their learned
solvers. Talks to solvers only through the :class:`~posekit.ik.api.Solver` interface.
"""

from __future__ import annotations

import html

import numpy as np

from ..ik.api import DEFAULT_TOLERANCE, Effector, Pose
from ..studio import PosingSession, accepts, honoured
from ..studio.status import reached_mark, status_line, status_table, worst_errors
from .screen_fit import stylesheet, view_box_layout
from .shared import widget
from .viewer import SkeletonViewer, show_widget

__all__ = ["SolverPanel", "ignored_effectors", "reached_mark", "solver_views", "show_session", "status_line",
           "status_table", "views_row", "worst_errors"]


def ignored_effectors(solver, effectors) -> list:
    """The effectors ``solver`` is not given: those of a kind it does not honour (``solver.kinds``;
    :func:`posekit.studio.honoured`)."""
    return honoured(solver, effectors)[1]


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
                            layout=view_box_layout(width, height)))
        boxes[-1].add_class("posekit-view")
    return viewers, labels, boxes


def views_row(boxes):
    """The row of view boxes (:func:`solver_views`), with the page's rules that scale them (a stylesheet that takes
    no room, :func:`~posekit.viz.screen_fit.stylesheet`)."""
    import ipywidgets as w

    return widget(w.HBox, [*boxes, stylesheet()], layout={"flex_flow": "row wrap", "width": "100%"})


def show_session(session, viewers: dict, labels: dict) -> None:
    """Show a :class:`~posekit.studio.PosingSession` in its views: each view draws the session's markers and its
    solver's last pose, and its label says the session's status (:meth:`~posekit.studio.PosingSession.view_status`)
    — the one loop behind :class:`SolverPanel`, :class:`~posekit.viz.EffectorEditor` and the studio. A solver that
    failed or had nothing to solve keeps its last pose on screen."""
    for name, view in viewers.items():
        res = session.results.get(name)
        pose = res.pose.global_pos if res is not None and not isinstance(res, Exception) else None
        with view.drawing_once():
            view.show(pose)
            labels[name].value = session.view_status(name)


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
        # one effector per joint, each with the tolerance it was given (or the kind's default)
        self.session = PosingSession(skeleton, start, self.solvers, effectors,
                                     tolerance_of=lambda lam, kind: DEFAULT_TOLERANCE[kind])
        if selectable is None:
            selectable = self.usable_joints()
        self.viewers, self.labels, boxes = solver_views(skeleton, self.solvers, start.global_pos, truth, width, height,
                                                        selectable)
        first = next(iter(self.viewers.values()))
        self.remove_button = widget(w.Button, description="remove target", icon="times", layout={"width": "130px"},
                                    tooltip="take the selected joint's effector away")
        self.remove_button.on_click(lambda _: self.remove_effector(first.selected))
        self.message = widget(w.HTML)
        self.widget = widget(w.VBox, [views_row(boxes), first.controls,
                                      widget(w.HBox, [self.remove_button, self.message],
                                             layout={"align_items": "center"})])
        self.widget.add_class("posekit-panel")
        for v in self.viewers.values():
            v.attach(self.session)
        first.page_watch.keys_scope = "posekit-panel"  # Ctrl+Z / Ctrl+Shift+Z with the focus in the panel
        first.page_watch.on_key("undo", self.session.undo)
        first.page_watch.on_key("redo", self.session.redo)
        self.session.on_change(self._on_change)
        self.show()

    def _ipython_display_(self):
        show_widget(self.widget, f"[live 3D views of {', '.join(self.solvers)}, posing one skeleton side by side. They "
                                 "draw in a running Jupyter kernel; run the notebook to move the targets]")

    def _on_change(self, what, index):
        if what != "select":
            self.show()

    @property
    def effectors(self) -> dict:
        """Joint name -> :class:`~posekit.ik.api.Effector`, as the solvers get them (read from :attr:`session`)."""
        return {e.joint: e for e in self.session.solver_effectors()}

    @property
    def results(self) -> dict:
        """Name -> last IKResult, or the exception the solver raised (:attr:`session`)."""
        return self.session.results

    @property
    def times(self) -> dict:
        return self.session.times

    def usable_joints(self) -> list:
        """The body joints every solver of the panel takes: those of the effectors, and each other joint to which
        every solver accepts one more position effector (each is asked once, on the start pose; a ValueError is a
        refusal)."""
        from ..data.metrics import body_joints

        base, P = self.session.solver_effectors(), np.asarray(self.start.global_pos, float)
        have = {e.joint for e in base}
        usable = []
        for j in body_joints(self.skeleton):
            name = self.skeleton.names[int(j)]
            trial = base + [Effector(name, P[int(j)])]
            if name in have or all(accepts(s, self.start, trial) for s in self.solvers.values()):
                usable.append(name)
        return usable

    def remove_effector(self, joint):
        """Take ``joint``'s effector away (its marker goes) and re-solve; the last effector stays (with a message)."""
        at = [] if joint is None else [i for i, e in enumerate(self.session.effectors)
                                       if e.joint == self.skeleton.names[self.skeleton.index(joint)]]
        if not at:
            self.message.value = "select a joint with a target first"
            return
        name = self.session.effectors[at[0]].joint
        if len(self.session.effectors) == 1:
            self.message.value = f"<span style='color:#b03a2e'>{html.escape(name)} holds the only effector</span>"
            return
        self.message.value = ""
        self.session.remove(at[0])

    def move_target(self, joint, position):
        """Move (or add) the target of a joint and re-solve, as the sliders do (:meth:`PosingSession.move`: a
        look-at effector's point, else a position target)."""
        name = self.skeleton.names[self.skeleton.index(joint)]
        kind = "look_at" if self.session.find(name, "look_at") is not None else "position"
        self.session.move(name, position, kind)

    def solve(self):
        """Solve with every solver and show the views (:func:`show_session`)."""
        self.session.solve()
        self.show()

    def show(self):
        """Show the session's effectors and poses in every view (:func:`show_session`)."""
        show_session(self.session, self.viewers, self.labels)
