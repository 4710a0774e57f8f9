"""An effector editor: add and remove effectors of every kind, set each one's tolerance, watch solvers re-pose.

Introduced in ``notebooks/05_protores.ipynb`` (ProtoRes beside DLS). Talks to solvers only through the
:class:`~posekit.ik.api.Solver` interface; it knows nothing of a particular model (a model's meaning of
a tolerance comes in as ``tolerance_of``).

* **Add** — a joint, a kind (position, rotation, look-at) and the *add* button. A new position effector
  sits on the joint where the first solver put it; a rotation effector holds that joint's current world
  rotation; a look-at effector points the direction the character faces (in the joint's own frame) at a
  target 1 m ahead.
* **Each effector's row** — its tolerance slider (``Lambda`` in [0, 1]: 0 exact, 1 loose), for a rotation
  effector yaw / pitch / roll sliders (degrees, 1° steps, applied in the world frame on top of the rotation
  it was added with; the target rotation is drawn as an axes triad at the joint), and *remove*.
* **Markers** — position targets are red; a look-at target is orange, with a ray from its joint.
* **Move a target** — pick the effector's joint in the first view (double-click or the joint list) and
  drag the X/Y/Z sliders: a position target moves, or the point a look-at effector faces (a joint with
  both: the *sliders move* choice says which).
* **Ignored kinds** — a solver gets only the effectors of the kinds it honours; its view says which kinds
  it ignored and never calls them reached.

The effectors, results and undo steps are a :class:`~posekit.studio.PosingSession`'s (:attr:`EffectorEditor.session`):
the editor's widgets and views show it and report edits to it; a drag is ``session.move`` → solve → the views show.
"""

from __future__ import annotations

import html

import numpy as np

from ..ik.api import Pose
from ..studio import KIND_CHOICES, PosingSession
from .compare import show_session, solver_views, views_row
from .shared import widget
from .viewer import show_widget

__all__ = ["EffectorEditor"]


class EffectorEditor:
    """Side-by-side solvers driven by an editable list of effectors (see the module docstring).

    Parameters
    ----------
    skeleton : Skeleton
    solvers : dict
        Name -> solver; each solves from ``start`` (a solver with ``needs_start = False`` ignores it).
    start : Pose
        Start pose of the solvers that need one (rotation solvers need its rotations).
    effectors : list of Effector, optional
        Initial effectors (ignored when ``session`` is given).
    tolerance_of : callable, optional
        ``tolerance_of(lam, kind) -> float``: the Effector tolerance (metres or radians) of slider value
        ``lam``; default ``max(0.1 lam, 1e-4)``.
    truth : ndarray, shape (J, 3), optional
        Drawn as the ghost.
    session : PosingSession, optional
        The session to show and edit (the studio keeps one across solver changes); default a new one.
    selected : str, optional
        The joint the first view's sliders move at the start.

    Attributes
    ----------
    session : PosingSession
        The effectors (the one copy of every target), the results and the undo steps.
    effectors : list of Effector
        What the solvers get (read from the session).
    results, times : dict
        The session's: name -> last IKResult (or the exception raised), name -> milliseconds.
    updates : int
        How many times the solvers have solved.
    widget : ipywidgets.VBox
    """

    def __init__(self, skeleton, solvers: dict, start: Pose, effectors=(), tolerance_of=None, truth=None,
                 width: int = 300, height: int = 330, session=None, selected=None):
        import ipywidgets as w

        self.skeleton, self.start = skeleton, start
        if session is None:
            session = PosingSession(skeleton, start, solvers, effectors, tolerance_of=tolerance_of)
        elif list(session.solvers) != list(solvers):
            session.set_solvers(solvers)
        self.session = session
        self._change_callbacks = []
        self.viewers, self.labels, boxes = solver_views(skeleton, self.solvers, start.global_pos, truth, width, height)
        self.first = next(iter(self.viewers.values()))
        self.add_joint = widget(w.Dropdown, options=[skeleton.names[j] for j in self.first.body],
                                value=skeleton.names[skeleton.pelvis()], description="joint", layout={"width": "220px"})
        self.add_kind = widget(w.Dropdown, options=[(k.replace("_", "-"), k) for k in KIND_CHOICES], value="position",
                               description="kind", layout={"width": "200px"})
        self.add_button = widget(w.Button, description="add effector", button_style="info")
        self.add_button.on_click(lambda _: self._add_clicked())
        self.message = widget(w.HTML)
        self.rows_box = widget(w.VBox, [])
        self.row_widgets = []
        wrap = {"flex_flow": "row wrap", "align_items": "center"}  # a narrow page: views and controls wrap
        self.widget = widget(w.VBox, [views_row(boxes), self.first.controls,
                                      widget(w.HBox, [self.add_joint, self.add_kind, self.add_button, self.message],
                                             layout=wrap),
                                      self.rows_box])
        self.widget.add_class("posekit-editor")
        self.keys_undo, self.keys_redo = self.session.undo, self.session.redo
        watch = self.first.page_watch
        watch.keys_scope = "posekit-editor"  # Ctrl+Z / Ctrl+Shift+Z with the focus in the editor
        watch.on_key("undo", lambda: self.keys_undo())
        watch.on_key("redo", lambda: self.keys_redo())
        for v in self.viewers.values():
            v.attach(self.session)
        if selected is not None:
            self.first.select(selected)
        self._make_rows()
        self.session.on_change(self._on_session)
        show_session(self.session, self.viewers, self.labels)
        for v in self.viewers.values():  # not shown yet: no press can come from the sliders replaced while building
            v.settle()

    def _ipython_display_(self):
        show_widget(self.widget, f"[effector editor: live 3D views of {', '.join(self.solvers)} on {len(self.rows)} "
                                 "effectors. They draw in a running Jupyter kernel; run the notebook to edit them]")

    def close(self):
        """Stop showing the session (its views are being replaced)."""
        if self._on_session in self.session._listeners:
            self.session._listeners.remove(self._on_session)

    # ------------------------------------------------------------------ the session's parts
    @property
    def solvers(self) -> dict:
        return self.session.solvers

    @property
    def rows(self) -> list:
        """The session's effectors (:class:`~posekit.studio.StudioEffector`; ``rows[i]["target"]`` reads a field)."""
        return self.session.effectors

    @property
    def effectors(self) -> list:
        return self.session.solver_effectors()

    @property
    def results(self) -> dict:
        return self.session.results

    @property
    def times(self) -> dict:
        return self.session.times

    @property
    def updates(self) -> int:
        return self.session.updates

    @property
    def tolerance_of(self):
        return self.session.tolerance_of

    # ------------------------------------------------------------------ rows of widgets
    def _make_rows(self):
        """One row of widgets per effector, showing the session's values (made again after a change of the list)."""
        import ipywidgets as w

        rows = []
        for i, e in enumerate(self.session.effectors):
            tol = widget(w.FloatSlider, value=float(e.lam), min=0.0, max=1.0, step=0.01, description="tolerance",
                         continuous_update=False, layout={"width": "260px"})
            remove = widget(w.Button, description="remove", layout={"width": "80px"})
            parts = [widget(w.HTML, f"<b>{e.joint}</b> {e.kind.replace('_', '-')}", layout={"width": "180px"}), tol]
            box = widget(w.HBox, parts + [remove])
            tol.observe(lambda ch, i=i: self._safely(lambda: self.session.set_tolerance(i, ch["new"])), names="value")
            remove.on_click(lambda _, i=i: self._safely(lambda: self.session.remove(i)))
            if e.kind == "rotation":  # 360 px for 360 degrees: a pixel a degree, and the readout takes typed values
                angles = [widget(w.FloatSlider, value=float(v), min=-180, max=180, step=1, description=f"{a} °",
                                 continuous_update=False, readout_format=".0f", layout={"width": "460px"})
                          for a, v in zip(("yaw", "pitch", "roll"), e.euler)]
                for s in angles:
                    s.observe(lambda ch, i=i, a=angles: self._safely(
                        lambda: self.session.set_rotation(i, *[s.value for s in a])), names="value")
                box = widget(w.VBox, [box, widget(w.HBox, angles[:2]), angles[2]])
            rows.append(box)
        self.row_widgets = rows
        self.rows_box.children = tuple(rows)

    def _safely(self, action):
        try:
            action()
            self.message.value = ""
        except ValueError as err:
            self.message.value = f"<span style='color:#b03a2e'>{html.escape(str(err))}</span>"

    def _on_session(self, what, index):
        if what == "select":
            return
        if what in ("add", "remove", "setup", "undo", "redo", "cancel", "solvers"):
            self._make_rows()
        show_session(self.session, self.viewers, self.labels)
        self.first.flush()  # a target moved in the first view is drawn there before any listener hears of the change
        for cb in self._change_callbacks:
            cb(what, index)

    # ------------------------------------------------------------------ edits (the session's)
    def add(self, joint, kind: str = "position", lam: float = 0.0, target=None, axis=None) -> int:
        """Add an effector (see the module docstring for where it starts) and re-solve; returns its index."""
        return self.session.add(joint, kind, lam, target, axis)

    def _add_clicked(self):
        self._safely(lambda: self.add(self.add_joint.value, self.add_kind.value))

    def remove(self, index: int):
        """Remove effector ``index`` and re-solve."""
        self.session.remove(index)

    def set_tolerance(self, index: int, lam: float):
        """Set effector ``index``'s tolerance slider value (``Lambda`` in [0, 1]) and re-solve."""
        self.session.set_tolerance(index, lam)
        self._make_rows()  # the row's slider shows the value set here

    def set_rotation(self, index: int, yaw: float = 0.0, pitch: float = 0.0, roll: float = 0.0):
        """Turn a rotation effector by yaw (about Y), pitch (X) and roll (Z), degrees, world frame, from the
        rotation it was added with; re-solve."""
        self.session.set_rotation(index, yaw, pitch, roll)
        self._make_rows()

    def move_target(self, index: int, position):
        """Move effector ``index``'s target point (position, or the point a look-at faces) and re-solve."""
        self.session.move_target(index, position)

    def on_change(self, callback):
        """Call ``callback(what, index)`` after every change, its solve and its drawing (:meth:`PosingSession.on_change`)."""
        self._change_callbacks.append(callback)

    def on_before_change(self, callback):
        """Call ``callback(what, index)`` before a change (:meth:`PosingSession.on_before_change`)."""
        self.session.on_before_change(callback)

    def setup(self) -> list:
        """The effectors as plain data (:meth:`PosingSession.setup`)."""
        return self.session.setup()

    def set_setup(self, rows):
        """Replace every effector by ``rows`` (the form :meth:`setup` returns) as one step, and solve; on a ValueError
        nothing changes (:meth:`PosingSession.from_dict`)."""
        self.session.from_dict(list(rows))

    def solve(self):
        """Solve with every solver and show the views."""
        self.session.solve()
        show_session(self.session, self.viewers, self.labels)
