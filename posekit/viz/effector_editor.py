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
"""

from __future__ import annotations

import html

import numpy as np

from ..ik.api import Effector, Pose
from ..kinematics import fk
from ..rotations import euler_to_quat, quat_to_matrix
from ..transforms import facing_angle
from .compare import solve_views, solver_views, views_row
from .shared import widget
from .viewer import show_widget

__all__ = ["EffectorEditor"]

KIND_CHOICES = ("position", "rotation", "look_at")


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
        Initial effectors.
    tolerance_of : callable, optional
        ``tolerance_of(lam, kind) -> float``: the Effector tolerance (metres or radians) of slider value
        ``lam``; default ``max(0.1 lam, 1e-4)``.
    truth : ndarray, shape (J, 3), optional
        Drawn as the ghost.

    Attributes
    ----------
    effectors : list of Effector
        What the solvers get (rebuilt from the rows on every change).
    results : dict
        Name -> last IKResult, or the exception a solver raised (its view shows the message; the others
        go on).
    times : dict
        Name -> milliseconds of its last solve.
    updates : int
        How many times the solvers have solved.
    widget : ipywidgets.VBox
    """

    def __init__(self, skeleton, solvers: dict, start: Pose, effectors=(), tolerance_of=None, truth=None,
                 width: int = 300, height: int = 330):
        import ipywidgets as w

        self.skeleton, self.solvers, self.start = skeleton, dict(solvers), start
        self.tolerance_of = tolerance_of or (lambda lam, kind: max(0.1 * lam, 1e-4))
        self.rows = []  # dicts: effector fields + lam + euler + base rotation + widgets
        self.results, self.times = {}, {}
        self.updates = 0  # solves so far (every change solves once)
        self._change_callbacks, self._before_callbacks = [], []
        self.viewers, self.labels, boxes = solver_views(skeleton, self.solvers, start.global_pos, truth, width, height)
        self.first = next(iter(self.viewers.values()))
        self.first.on_target_change(self._on_target)
        self.first.on_look_target_change(self._on_look)
        self.add_joint = widget(w.Dropdown, options=[skeleton.names[j] for j in self.first.body],
                                value=skeleton.names[skeleton.pelvis()], description="joint", layout={"width": "220px"})
        self.add_kind = widget(w.Dropdown, options=[(k.replace("_", "-"), k) for k in KIND_CHOICES], value="position",
                               description="kind", layout={"width": "200px"})
        self.add_button = widget(w.Button, description="add effector", button_style="info")
        self.add_button.on_click(lambda _: self._add_clicked())
        self.message = widget(w.HTML)
        self.rows_box = widget(w.VBox, [])
        wrap = {"flex_flow": "row wrap", "align_items": "center"}  # a narrow page: views and controls wrap
        self.widget = widget(w.VBox, [views_row(boxes), self.first.controls,
                                      widget(w.HBox, [self.add_joint, self.add_kind, self.add_button, self.message],
                                             layout=wrap),
                                      self.rows_box])
        self._quiet = True
        for e in effectors:
            self.add(e.joint, e.kind, target=e.target, axis=e.axis)
        self._quiet = False
        self.solve()
        for v in self.viewers.values():  # not shown yet: no press can come from the sliders replaced while building
            v._forget_replaced_sliders()

    def _ipython_display_(self):
        show_widget(self.widget, f"[effector editor: live 3D views of {', '.join(self.solvers)} on {len(self.rows)} "
                                 "effectors. They draw in a running Jupyter kernel; run the notebook to edit them]")

    # ------------------------------------------------------------------ effectors
    def _current(self):
        """World positions (J, 3) and rotations (J, 3, 3) of the first solver's last pose (else the start)."""
        res = self.results.get(next(iter(self.solvers)))
        pose = res.pose if res is not None and not isinstance(res, Exception) else self.start
        if pose.local_rot is None:
            pose = self.start
        return fk(self.skeleton, np.asarray(pose.local_rot, float), np.asarray(pose.root_pos, float))

    def add(self, joint, kind: str = "position", lam: float = 0.0, target=None, axis=None):
        """Add an effector (see the module docstring for where it starts) and re-solve; returns its row index."""
        import ipywidgets as w

        j = self.skeleton.index(joint)
        name = self.skeleton.names[j]
        kind = kind.replace("-", "_")
        if kind not in KIND_CHOICES:
            raise ValueError(f"unknown effector kind {kind!r}; valid kinds: {', '.join(KIND_CHOICES)}")
        clash = _conflict(self.rows, name, kind)  # the Solver API's rule, said before any solver sees it
        if clash:
            raise ValueError(clash)
        P, G = self._current()
        row = {"joint": name, "kind": kind, "lam": float(lam), "euler": np.zeros(3)}
        if kind == "position":
            row["target"] = P[j].copy() if target is None else np.asarray(target, float)
        elif kind == "rotation":
            row["base"] = G[j].copy() if target is None else _rotation_of(self.skeleton, name, target)
        else:
            if axis is None:
                heading = facing_angle(self.skeleton, P)
                world = np.array([np.sin(heading), 0.0, np.cos(heading)])
                axis = G[j].T @ world
            row["axis"] = np.asarray(axis, float)
            row["target"] = P[j] + G[j] @ row["axis"] if target is None else np.asarray(target, float)
        tol = widget(w.FloatSlider, value=float(lam), min=0.0, max=1.0, step=0.01, description="tolerance",
                     continuous_update=False, layout={"width": "260px"})
        remove = widget(w.Button, description="remove", layout={"width": "80px"})
        parts = [widget(w.HTML, f"<b>{name}</b> {kind.replace('_', '-')}", layout={"width": "180px"}), tol]
        row["tol"] = tol
        row["widgets"] = widget(w.HBox, parts + [remove])
        if kind == "rotation":  # 360 px for 360 degrees: a pixel a degree, and the readout takes typed values
            row["angle_sliders"] = [widget(w.FloatSlider, value=0.0, min=-180, max=180, step=1, description=f"{a} °",
                                           continuous_update=False, readout_format=".0f", layout={"width": "460px"})
                                    for a in ("yaw", "pitch", "roll")]
            for s in row["angle_sliders"]:
                s.observe(lambda ch, r=row: self._on_angles(r), names="value")
            row["widgets"] = widget(w.VBox, [row["widgets"], widget(w.HBox, row["angle_sliders"][:2]),
                                             row["angle_sliders"][2]])
        tol.observe(lambda ch, r=row: self.set_tolerance(self.rows.index(r), ch["new"]), names="value")
        remove.on_click(lambda _, r=row: self.remove(self.rows.index(r)))
        self.rows.append(row)
        self.rows_box.children = tuple(r["widgets"] for r in self.rows)
        self._changed("add", len(self.rows) - 1)
        return len(self.rows) - 1

    def _add_clicked(self):
        try:
            self.add(self.add_joint.value, self.add_kind.value)
            self.message.value = ""
        except ValueError as err:
            self.message.value = f"<span style='color:#b03a2e'>{html.escape(str(err))}</span>"

    def remove(self, index: int):
        """Remove effector row ``index`` and re-solve."""
        self.rows.pop(index)
        self.rows_box.children = tuple(r["widgets"] for r in self.rows)
        self._changed("remove", index)

    def set_tolerance(self, index: int, lam: float):
        """Set row ``index``'s tolerance slider value (``Lambda`` in [0, 1]) and re-solve."""
        if not 0.0 <= float(lam) <= 1.0:
            raise ValueError(f"tolerance must lie in [0, 1], got {lam!r}")
        self.rows[index]["lam"] = float(lam)
        self._changed("tolerance", index)

    def set_rotation(self, index: int, yaw: float = 0.0, pitch: float = 0.0, roll: float = 0.0):
        """Turn a rotation effector by yaw (about Y), pitch (X) and roll (Z), degrees, world frame, from the
        rotation it was added with; re-solve."""
        row = self.rows[index]
        if row["kind"] != "rotation":
            raise ValueError(f"effector {index} on {row['joint']} is a {row['kind']} effector, not a rotation")
        row["euler"] = np.array([yaw, pitch, roll], float)
        self._changed("rotation", index)

    def _on_angles(self, row):
        self.set_rotation(self.rows.index(row), *[s.value for s in row["angle_sliders"]])

    def move_target(self, index: int, position):
        """Move row ``index``'s target point (position, or the point a look-at faces) and re-solve."""
        row = self.rows[index]
        if row["kind"] == "rotation":
            raise ValueError(f"effector {index} on {row['joint']} is a rotation: turn it with set_rotation")
        position = np.asarray(position, float).reshape(3)
        if not np.all(np.isfinite(position)):
            raise ValueError(f"target of effector {index} on {row['joint']} contains NaN or inf")
        row["target"] = position
        self._changed("move", index)

    def _on_target(self, joint, position):
        # a red target moved in the first view (sliders or dragging): the joint's position effector, or a new one
        for i, r in enumerate(self.rows):
            if r["joint"] == joint and r["kind"] == "position":
                self.move_target(i, position)
                return
        self.add(joint, "position", target=position)

    def on_change(self, callback):
        """Call ``callback(what, index)`` after every change and its solve: ``what`` is ``"add"``, ``"remove"``,
        ``"tolerance"``, ``"rotation"``, ``"move"`` (row ``index``) or ``"setup"`` (a whole setup, index None)."""
        self._change_callbacks.append(callback)

    def on_before_change(self, callback):
        """Call ``callback(what, index)`` after a change to the effectors and before its solve re-poses the views
        (the studio notes each view's camera as it was)."""
        self._before_callbacks.append(callback)

    def _changed(self, what, index):
        if self._quiet:
            return
        for cb in self._before_callbacks:
            cb(what, index)
        self.solve()
        self.first.flush()  # a target moved in the first view is drawn there before any listener hears of the change
        for cb in self._change_callbacks:
            cb(what, index)

    def setup(self) -> list:
        """The effector rows as plain data (lists and floats; :func:`posekit.viz.setup_file.save_setup` writes
        them as JSON): joint, kind, ``lam`` and ``target`` (position, look-at), ``axis`` (look-at), ``base``
        rotation matrix and ``euler`` yaw/pitch/roll degrees (rotation)."""
        out = []
        for r in self.rows:
            d = {"joint": r["joint"], "kind": r["kind"], "lam": float(r["lam"])}
            for key in ("target", "axis", "base", "euler"):
                if key in r and not (key == "euler" and r["kind"] != "rotation"):
                    d[key] = np.asarray(r[key], float).tolist()
            out.append(d)
        return out

    def set_setup(self, rows):
        """Replace every effector by ``rows`` (the form :meth:`setup` returns) and solve once. Everything is
        checked before anything changes: on a ValueError the editor keeps its effectors."""
        rows = [dict(r) for r in rows]
        seen = []
        for k, r in enumerate(rows):
            try:
                j = self.skeleton.names[self.skeleton.index(r["joint"])]
            except (KeyError, ValueError, IndexError) as err:
                raise ValueError(f"effector {k + 1}: {err}") from None
            kind = str(r.get("kind", "")).replace("-", "_")
            if kind not in KIND_CHOICES:
                raise ValueError(f"effector {k + 1} on {j}: unknown kind {r.get('kind')!r}; valid: {', '.join(KIND_CHOICES)}")
            clash = _conflict(seen, j, kind)
            if clash:
                raise ValueError(f"effector {k + 1}: {clash}")
            seen.append({"joint": j, "kind": kind})
            if not 0.0 <= float(r.get("lam", 0.0)) <= 1.0:
                raise ValueError(f"effector {k + 1} on {j}: tolerance must lie in [0, 1], got {r.get('lam')!r}")
            need = {"position": ("target",), "look_at": ("target", "axis"), "rotation": ("base",)}[kind]
            for key in need:
                if key not in r:
                    raise ValueError(f"effector {k + 1} on {j}: a {kind.replace('_', '-')} effector needs {key!r}")
            shapes = {"target": (3,), "axis": (3,), "base": (3, 3), "euler": (3,)}
            for key, shape in shapes.items():
                if key in r:
                    a = np.asarray(r[key], float)
                    if a.shape != shape or not np.all(np.isfinite(a)):
                        raise ValueError(f"effector {k + 1} on {j}: {key!r} must be {shape} finite numbers, "
                                         f"got {r[key]!r}")
            if kind == "rotation":
                R = np.asarray(r["base"], float)
                if np.abs(R.T @ R - np.eye(3)).max() > 1e-4 or np.linalg.det(R) < 0:
                    raise ValueError(f"effector {k + 1} on {j}: 'base' is not a rotation matrix")
            if kind == "look_at" and np.linalg.norm(np.asarray(r["axis"], float)) < 1e-9:
                raise ValueError(f"effector {k + 1} on {j}: 'axis' must not be zero")
        self._quiet = True
        try:
            self.rows = []
            for r in rows:
                kind = r["kind"].replace("-", "_")
                i = self.add(r["joint"], kind, lam=float(r.get("lam", 0.0)),
                             target=r.get("base") if kind == "rotation" else r.get("target"), axis=r.get("axis"))
                row = self.rows[i]
                row["tol"].value = float(row["lam"])
                if kind == "rotation":
                    row["base"] = np.array(r["base"], dtype=float)  # as saved (a rotation, checked above)
                if kind == "rotation" and "euler" in r:
                    row["euler"] = np.asarray(r["euler"], float)
                    for sl, v in zip(row["angle_sliders"], row["euler"]):
                        sl.value = float(v)
        finally:
            self._quiet = False
        self.rows_box.children = tuple(r["widgets"] for r in self.rows)
        self._changed("setup", None)

    def _on_look(self, joint, position):
        # an orange marker moved in the first view (sliders or dragging): that joint's look-at target
        for i, r in enumerate(self.rows):
            if r["joint"] == joint and r["kind"] == "look_at":
                self.move_target(i, position)
                return

    @property
    def effectors(self) -> list:
        out = []
        for r in self.rows:
            tol = float(self.tolerance_of(r["lam"], r["kind"]))
            if r["kind"] == "rotation":
                turn = quat_to_matrix(euler_to_quat(r["euler"], "YXZ", degrees=True))
                out.append(Effector(r["joint"], turn @ r["base"], "rotation", tolerance=tol))
            elif r["kind"] == "look_at":
                out.append(Effector(r["joint"], r["target"], "look_at", tolerance=tol, axis=r["axis"]))
            else:
                out.append(Effector(r["joint"], r["target"], "position", tolerance=tol))
        return out

    # ------------------------------------------------------------------ solving
    def solve(self):
        """Solve with every solver and refresh the views (:func:`~posekit.viz.compare.solve_views`: a solver gets
        the effectors of the kinds it honours, names the others as ignored, and says why when it refuses)."""
        self.updates += 1
        solve_views(self.skeleton, self.solvers, self.viewers, self.labels, self.start, self.effectors,
                    self.results, self.times)


def _conflict(rows, joint: str, kind: str) -> str | None:
    """Why an effector of ``kind`` on ``joint`` cannot join ``rows`` (dicts with ``joint`` and ``kind``), or None:
    one effector of a kind per joint, and no rotation beside a look-at (a rotation fixes where a joint faces)."""
    for r in rows:
        if r["joint"] == joint and (r["kind"] == kind or {r["kind"], kind} == {"rotation", "look_at"}):
            return (f"{joint} already has a {r['kind'].replace('_', '-')} effector; remove it first "
                    "(one effector of a kind per joint, and a rotation fixes where a joint faces)")
    return None


def _rotation_of(skeleton, joint, target) -> np.ndarray:
    from ..ik.effectors import resolve_effectors

    return resolve_effectors(skeleton, [Effector(joint, target, "rotation")]).rotation[0]
