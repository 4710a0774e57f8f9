"""The posing studio's state, without a widget: one list of effectors, the solvers, their results, undo and redo.

Introduced in ``notebooks/06_posing_studio.ipynb`` (``studio.session``); lessons 01, 03, 04 and 05's panels pose
through it too. Everything a drag, a slider, a button or a cell decides happens here, and every view only shows it:
a drag is ``session.move(joint, point)``, which edits the one stored target, solves (each solver with the kinds it
honours, :func:`~posekit.studio.solve.solve_honoured`) and tells the listeners, which redraw.

* **Effectors** — :attr:`PosingSession.effectors`, a list of :class:`StudioEffector` (joint, kind, tolerance
  slider value ``lam``, target point, look-at ``axis``, rotation ``base`` and ``euler`` turn). One effector of a
  kind per joint, and no rotation beside a look-at (a rotation fixes where a joint faces).
* **Selecting** a joint (:meth:`PosingSession.select`) never creates an effector: only an edit does
  (:meth:`~PosingSession.move` on a joint without a target adds a position effector there).
* **Undo and redo** — every change is a step; a drag in 3D, from the press to the release
  (:meth:`PosingSession.begin_drag` / :meth:`~PosingSession.end_drag`), is one step however slowly the solves come,
  and moves of one effector less than ``coalesce_s`` apart (a slider held down) are one step. Each step may carry
  a note (the views' cameras): :attr:`PosingSession.notes`.
* **Setups** — :meth:`~PosingSession.to_dict` / :meth:`~PosingSession.from_dict` (the JSON of
  :mod:`posekit.viz.setup_file`); a bad setup is refused with a sentence before anything changes.
* **Timeline keys** — :meth:`~PosingSession.add_key`: the effectors as they are, each key with the same joints and
  kinds as the first.
* **Status** — :meth:`~PosingSession.view_status`, :meth:`~PosingSession.summary_rows` (:mod:`posekit.studio.status`):
  with no effectors they say nothing was solved, and no result is kept.

Units: metres, world frame; ``euler`` in degrees (yaw about Y, pitch about X, roll about Z, world frame, on top of
``base``) — :mod:`posekit.conventions`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..ik.api import Effector, Pose
from ..ik.effectors import resolve_effectors
from ..kinematics import fk
from ..rotations import euler_to_quat, quat_to_matrix
from ..transforms import facing_angle
from .solve import Solved, solve_honoured
from .status import summary_rows, view_status

__all__ = ["PosingSession", "StudioEffector", "KIND_CHOICES", "COALESCE_S", "conflict"]

KIND_CHOICES = ("position", "rotation", "look_at")
COALESCE_S = 1.0
"""Moves of one effector less than this many seconds apart are one undo step (a slider held down; a drag is one step
from press to release, :meth:`PosingSession.begin_drag`)."""


@dataclass
class StudioEffector:
    """One effector as the studio edits it (see the module docstring).

    Attributes
    ----------
    joint : str
        The joint's own name.
    kind : str
        ``"position"``, ``"rotation"`` or ``"look_at"``.
    lam : float
        The tolerance slider's value in [0, 1] (0 exact, 1 loose); ``tolerance_of(lam, kind)`` gives the
        :class:`~posekit.ik.api.Effector`'s tolerance.
    target : ndarray, shape (3,), metres, or None
        The point (position and look-at effectors).
    axis : ndarray, shape (3,), or None
        The look-at direction in the joint's own frame.
    base : ndarray, shape (3, 3), or None
        A rotation effector's world rotation as added.
    euler : ndarray, shape (3,), degrees
        Yaw, pitch, roll on top of ``base`` (rotation effectors).
    tolerance : float or None
        A tolerance of its own (metres or radians; an effector a lesson gave with one), else ``tolerance_of(lam)``.
    weight : float
        The :class:`~posekit.ik.api.Effector`'s weight.
    """

    joint: str
    kind: str
    lam: float = 0.0
    target: np.ndarray | None = None
    axis: np.ndarray | None = None
    base: np.ndarray | None = None
    euler: np.ndarray = field(default_factory=lambda: np.zeros(3))
    tolerance: float | None = None
    weight: float = 1.0

    def __getitem__(self, key):
        """``e["target"]``: the field (the editor's rows were dicts)."""
        return getattr(self, key)

    def effector(self, tolerance_of) -> Effector:
        """The :class:`~posekit.ik.api.Effector` a solver gets."""
        tol = float(tolerance_of(self.lam, self.kind) if self.tolerance is None else self.tolerance)
        if self.kind == "rotation":
            return Effector(self.joint, self.rotation, "rotation", tolerance=tol, weight=self.weight)
        if self.kind == "look_at":
            return Effector(self.joint, self.target, "look_at", tolerance=tol, weight=self.weight, axis=self.axis)
        return Effector(self.joint, self.target, "position", tolerance=tol, weight=self.weight)

    @property
    def rotation(self) -> np.ndarray:
        """The world rotation asked for (3, 3): ``euler`` turned on top of ``base``."""
        return quat_to_matrix(euler_to_quat(self.euler, "YXZ", degrees=True)) @ self.base

    def to_dict(self) -> dict:
        """Plain data (lists and floats): the row of a setup file (:mod:`posekit.viz.setup_file`)."""
        d = {"joint": self.joint, "kind": self.kind, "lam": float(self.lam)}
        for key in ("target", "axis", "base"):
            if getattr(self, key) is not None:
                d[key] = np.asarray(getattr(self, key), float).tolist()
        if self.kind == "rotation":
            d["euler"] = np.asarray(self.euler, float).tolist()
        if self.tolerance is not None:
            d["tolerance"] = float(self.tolerance)
        if self.weight != 1.0:
            d["weight"] = float(self.weight)
        return d


def conflict(effectors, joint: str, kind: str) -> str | None:
    """Why an effector of ``kind`` on ``joint`` cannot join ``effectors`` (anything with ``joint`` and ``kind``),
    or None: one effector of a kind per joint, and no rotation beside a look-at."""
    for e in effectors:
        if e.joint == joint and (e.kind == kind or {e.kind, kind} == {"rotation", "look_at"}):
            return (f"{joint} already has a {e.kind.replace('_', '-')} effector; remove it first "
                    "(one effector of a kind per joint, and a rotation fixes where a joint faces)")
    return None


def _default_tolerance(lam, kind):
    return max(0.1 * lam, 1e-4)


class PosingSession:
    """Effectors, solvers, results, selection, undo/redo and timeline keys of one posing session (see the module
    docstring). No widget: a test, a cell or a page drives it alike.

    Parameters
    ----------
    skeleton : Skeleton
    start : Pose
        Start pose of the solvers that need one.
    solvers : dict, optional
        Name -> solver (:class:`~posekit.ik.api.Solver`).
    effectors : sequence of Effector or of dict, optional
        The first effectors (:class:`~posekit.ik.api.Effector`, or setup rows as :meth:`to_dict` writes them).
    tolerance_of : callable, optional
        ``tolerance_of(lam, kind) -> float`` (metres or radians); default ``max(0.1 lam, 1e-4)``.
    coalesce_s : float
        Moves of one effector closer in time than this are one undo step.
    clock : callable
        Seconds (default :func:`time.monotonic`); a test passes its own.

    Attributes
    ----------
    effectors : list of StudioEffector
        The one copy of every target.
    solvers : dict
    results : dict
        Name -> last IKResult or the exception raised; a solver with nothing to solve has none.
    solved : dict
        Name -> :class:`~posekit.studio.solve.Solved` of the last solve.
    updates : int
        How many times the solvers have solved.
    selected : str or None
    history : list of list of dict
        One setup per undo step; ``history[position]`` is the current one.
    notes : list of dict
        What a front end keeps with each step (the views' cameras).
    keys : list of tuple
        Timeline keys: ``(setup rows, list of Effector)``.
    """

    def __init__(self, skeleton, start: Pose, solvers=None, effectors=(), tolerance_of=None,
                 coalesce_s: float = COALESCE_S, clock=time.monotonic):
        self.skeleton, self.start = skeleton, start
        self.solvers = dict(solvers or {})
        self.tolerance_of = tolerance_of or _default_tolerance
        self.coalesce_s, self.clock = float(coalesce_s), clock
        self.effectors: list[StudioEffector] = []
        self.results, self.times, self.solved = {}, {}, {}
        self.updates, self.selected, self.keys = 0, None, []
        self._listeners, self._before = [], []
        self._last_move = (None, -np.inf)
        self._drag_step = None  # during a drag: the step it made (-1 before its first change), else None
        rows = [e if isinstance(e, dict) else self._row_of(e) for e in effectors]
        self._set_rows(self._checked(rows))
        self.solve()
        self.history, self.notes, self.position = [self.setup()], [{}], 0

    def _row_of(self, e: Effector) -> dict:
        row = {"joint": e.joint, "kind": e.kind, "target": e.target, "weight": e.weight}
        if e.tolerance is not None and tolerance_given(e):
            row["tolerance"] = e.tolerance
        if e.axis is not None:
            row["axis"] = e.axis
        return row

    # ------------------------------------------------------------------ listeners
    def on_change(self, callback):
        """Call ``callback(what, index)`` after every change and its solve: ``what`` is ``"add"``, ``"remove"``,
        ``"tolerance"``, ``"rotation"``, ``"move"`` (effector ``index``), ``"setup"``, ``"undo"``, ``"redo"``,
        ``"solvers"`` (index None) or ``"select"`` (no solve)."""
        self._listeners.append(callback)

    def on_before_change(self, callback):
        """Call ``callback(what, index)`` before a change is made (the studio notes each view's camera)."""
        self._before.append(callback)

    def _tell(self, what, index):
        for cb in list(self._listeners):
            cb(what, index)

    # ------------------------------------------------------------------ reading
    @property
    def names(self) -> list:
        """The solvers' names, in order."""
        return list(self.solvers)

    def solver_effectors(self) -> list:
        """The effectors as solvers get them (:class:`~posekit.ik.api.Effector`, in the list's order)."""
        return [e.effector(self.tolerance_of) for e in self.effectors]

    def find(self, joint, kind: str) -> int | None:
        """The index of ``joint``'s effector of ``kind``, or None."""
        name = self._name(joint)
        return next((i for i, e in enumerate(self.effectors) if e.joint == name and e.kind == kind), None)

    def markers(self) -> tuple:
        """What the views draw: ``(positions, looks, rotations)``, dicts joint -> (3,) point / (3,) point /
        (3, 3) rotation, read from :attr:`effectors` (no copy is kept anywhere else)."""
        pos = {e.joint: e.target for e in self.effectors if e.kind == "position"}
        looks = {e.joint: e.target for e in self.effectors if e.kind == "look_at"}
        rots = {e.joint: e.rotation for e in self.effectors if e.kind == "rotation"}
        return pos, looks, rots

    def current_pose(self) -> Pose:
        """The first solver's last pose with rotations, else the start pose."""
        res = self.results.get(next(iter(self.solvers), None))
        pose = res.pose if res is not None and not isinstance(res, Exception) else self.start
        return self.start if pose.local_rot is None else pose

    def _name(self, joint) -> str:
        return self.skeleton.names[self.skeleton.index(joint)]

    # ------------------------------------------------------------------ editing
    def select(self, joint):
        """Select a joint (name, role or index; None clears): what the sliders move. Never adds an effector."""
        name = None if joint is None else self._name(joint)
        if name != self.selected:
            self.selected = name
            self._tell("select", None)

    def move(self, joint, point, kind: str = "position") -> int:
        """Move ``joint``'s ``kind`` target (``"position"`` or ``"look_at"``) to ``point`` (3,), metres, and solve;
        a joint without a position effector gets one there (an edit adds, a selection never does). Returns the
        effector's index."""
        name = self._name(joint)
        kind = kind.replace("-", "_")
        point = np.asarray(point, float).reshape(3)
        if not np.all(np.isfinite(point)):
            raise ValueError(f"target of {name} contains NaN or inf")
        i = self.find(name, kind)
        if i is None:
            if kind != "position":
                raise ValueError(f"{name} has no {kind.replace('_', '-')} effector to move")
            return self.add(name, "position", target=point)
        self._before_change("move", i)
        self.effectors[i].target = point
        self._changed("move", i)
        return i

    def move_target(self, index: int, point) -> int:
        """Move effector ``index``'s point (position, or the point a look-at faces) and solve."""
        e = self._at(index)
        if e.kind == "rotation":
            raise ValueError(f"effector {index} on {e.joint} is a rotation: turn it with set_rotation")
        return self.move(e.joint, point, e.kind)

    def add(self, joint, kind: str = "position", lam: float = 0.0, target=None, axis=None) -> int:
        """Add an effector and solve; returns its index. Where it starts when no ``target`` is given: a position
        effector on the joint as the first solver put it; a rotation its current world rotation; a look-at the
        direction the character faces, at a point 1 m ahead."""
        row = self._new_row(self._name(joint), kind.replace("-", "_"), lam, target, axis, self.effectors)
        self._before_change("add", len(self.effectors))
        self.effectors.append(row)
        self._changed("add", len(self.effectors) - 1)
        return len(self.effectors) - 1

    def remove(self, index: int):
        """Remove effector ``index`` and solve."""
        self._at(index)
        self._before_change("remove", index)
        self.effectors.pop(index)
        self._changed("remove", index)

    def set_tolerance(self, index: int, lam: float):
        """Set effector ``index``'s tolerance slider value (``lam`` in [0, 1]) and solve."""
        e = self._at(index)
        if not 0.0 <= float(lam) <= 1.0:
            raise ValueError(f"tolerance must lie in [0, 1], got {lam!r}")
        if float(lam) == e.lam:
            return
        self._before_change("tolerance", index)
        e.lam = float(lam)
        self._changed("tolerance", index)

    def set_rotation(self, index: int, yaw: float = 0.0, pitch: float = 0.0, roll: float = 0.0):
        """Turn a rotation effector by yaw (about Y), pitch (X) and roll (Z), degrees, world frame, from the rotation
        it was added with; solve."""
        e = self._at(index)
        if e.kind != "rotation":
            raise ValueError(f"effector {index} on {e.joint} is a {e.kind} effector, not a rotation")
        euler = np.array([yaw, pitch, roll], float)
        if not np.all(np.isfinite(euler)):
            raise ValueError(f"rotation of effector {index} on {e.joint} contains NaN or inf")
        if np.array_equal(euler, e.euler):
            return
        self._before_change("rotation", index)
        e.euler = euler
        self._changed("rotation", index)

    def _at(self, index) -> StudioEffector:
        if not isinstance(index, (int, np.integer)) or not 0 <= index < len(self.effectors):
            raise ValueError(f"no effector {index!r}: there are {len(self.effectors)}")
        return self.effectors[int(index)]

    def _new_row(self, name, kind, lam, target, axis, others) -> StudioEffector:
        if kind not in KIND_CHOICES:
            raise ValueError(f"unknown effector kind {kind!r}; valid kinds: {', '.join(KIND_CHOICES)}")
        if self.skeleton.index(name) not in _body(self.skeleton):
            raise ValueError(f"{name} is a helper joint, not part of the body: it takes no effector")
        clash = conflict(others, name, kind)
        if clash:
            raise ValueError(clash)
        if not 0.0 <= float(lam) <= 1.0:
            raise ValueError(f"tolerance must lie in [0, 1], got {lam!r}")
        j = self.skeleton.index(name)
        row = StudioEffector(name, kind, float(lam))
        if target is not None and kind == "position":
            row.target = _point(target, name)
            return row
        if target is not None and kind == "rotation":
            base = np.asarray(target, float)
            row.base = base.copy() if base.shape == (3, 3) else _rotation_of(self.skeleton, name, target)
            return row
        pose = self.current_pose()
        P, G = fk(self.skeleton, np.asarray(pose.local_rot, float), np.asarray(pose.root_pos, float))
        if kind == "position":
            row.target = P[j].copy()
        elif kind == "rotation":
            row.base = G[j].copy()
        else:
            if axis is None:
                heading = facing_angle(self.skeleton, P)
                axis = G[j].T @ np.array([np.sin(heading), 0.0, np.cos(heading)])
            row.axis = _point(axis, name, "axis")
            if np.linalg.norm(row.axis) < 1e-9:
                raise ValueError(f"{name}: 'axis' must not be zero")
            row.target = P[j] + G[j] @ row.axis if target is None else _point(target, name)
        return row

    # ------------------------------------------------------------------ solving and steps
    def solve(self):
        """Solve with every solver (each given the kinds it honours); with no effectors nothing is solved and no
        result is kept."""
        self.updates += 1
        effectors = self.solver_effectors()
        for name, solver in self.solvers.items():
            s = solve_honoured(solver, self.start, effectors) if effectors else Solved()
            self.solved[name] = s
            if s.result is None:
                self.results.pop(name, None)
                self.times.pop(name, None)
            else:
                self.results[name] = s.result
                if not isinstance(s.result, Exception):
                    self.times[name] = s.ms

    def set_solvers(self, solvers: dict):
        """Pose with these solvers (name -> solver) from now on; solve. Not an undo step."""
        self.solvers = dict(solvers)
        self.results, self.times, self.solved = {}, {}, {}
        self._last_move = (None, -np.inf)  # a move after new solvers is a step of its own
        self.solve()
        self._tell("solvers", None)

    def _before_change(self, what, index):
        for cb in list(self._before):
            cb(what, index)

    def begin_drag(self):
        """A drag in 3D starts (the mouse pressed): every change until :meth:`end_drag` is one undo step, however
        long the solves between its moves take (timing alone split a drag on a slow machine, and undo then went back
        to the middle of it). A drag that creates its target (an add, then moves) is one step too."""
        self._drag_step = -1

    def end_drag(self):
        """The drag ends (the mouse released, or Escape): the next change is a step of its own."""
        self._drag_step = None
        self._last_move = (None, -np.inf)

    def _changed(self, what, index):
        self.solve()
        now = self.clock()
        last = self.position == len(self.history) - 1 and self.position > 0
        same = last and (self._drag_step == self.position if self._drag_step is not None else
                         what == "move" and self._last_move[0] == index and now - self._last_move[1] < self.coalesce_s)
        if same:
            self.history[self.position] = self.setup()
        else:
            del self.history[self.position + 1:]
            del self.notes[self.position + 1:]
            self.history.append(self.setup())
            self.notes.append(dict(self.notes[self.position]))
            self.position += 1
        self._last_move = (index, now) if what == "move" else (None, -np.inf)
        if self._drag_step is not None:
            self._drag_step = self.position
        self._tell(what, index)

    @property
    def can_undo(self) -> bool:
        return self.position > 0

    @property
    def can_redo(self) -> bool:
        return self.position < len(self.history) - 1

    def undo(self) -> bool:
        """Go back one step and solve; False (nothing done) at the first."""
        if not self.can_undo:
            return False
        self._before_change("undo", None)
        self.position -= 1
        self._restore("undo")
        return True

    def redo(self) -> bool:
        """Redo the step undone last and solve; False when there is none."""
        if not self.can_redo:
            return False
        self._before_change("redo", None)
        self.position += 1
        self._restore("redo")
        return True

    def revert_to(self, position: int):
        """Go back to step ``position`` and forget the steps after it (a drag cancelled with Escape: nothing of it is
        left to redo); solve."""
        if not 0 <= position <= self.position:
            raise ValueError(f"no step {position} to go back to (at step {self.position})")
        if position == self.position and self.setup() == self.history[position]:
            return
        self.position = position
        del self.history[position + 1:]
        del self.notes[position + 1:]
        self._restore("cancel")

    def _restore(self, what):
        self._set_rows(self._checked(self.history[self.position]))
        self._last_move = (None, -np.inf)
        self.solve()
        self._tell(what, None)

    # ------------------------------------------------------------------ setups
    def setup(self) -> list:
        """The effectors as plain data, one dict each (:meth:`StudioEffector.to_dict`)."""
        return [e.to_dict() for e in self.effectors]

    def to_dict(self) -> dict:
        """``{"effectors": [...], "solvers": [...]}``: what a setup file holds (:mod:`posekit.viz.setup_file`)."""
        return {"effectors": self.setup(), "solvers": self.names}

    def from_dict(self, doc):
        """Replace every effector by ``doc["effectors"]`` (or ``doc`` itself, a list of rows) as one step, and
        solve. Everything is checked first: on a ValueError nothing changes. Solver names are the caller's."""
        rows = doc["effectors"] if isinstance(doc, dict) else doc
        checked = self._checked(rows)
        self._before_change("setup", None)
        self._set_rows(checked)
        self._changed("setup", None)

    set_setup = from_dict

    def _checked(self, rows) -> list:
        """``rows`` (setup dicts) as StudioEffectors, every one checked; raises ValueError naming the first bad."""
        out = []
        for k, r in enumerate(rows):
            if not isinstance(r, dict):
                raise ValueError(f"effector {k + 1}: expected an object with joint and kind, got {r!r}")
            try:
                j = self._name(r["joint"])
            except (KeyError, ValueError, IndexError, TypeError) as err:
                raise ValueError(f"effector {k + 1}: {err}") from None
            kind = str(r.get("kind", "")).replace("-", "_")
            if kind not in KIND_CHOICES:
                raise ValueError(f"effector {k + 1} on {j}: unknown kind {r.get('kind')!r}; valid: "
                                 f"{', '.join(KIND_CHOICES)}")
            need = {"position": ("target",), "look_at": ("target", "axis"), "rotation": ("base",)}[kind]
            for key in need:
                if r.get(key) is None:
                    raise ValueError(f"effector {k + 1} on {j}: a {kind.replace('_', '-')} effector needs {key!r}")
            for key, shape in {"target": (3,), "axis": (3,), "euler": (3,)}.items():
                if r.get(key) is not None:
                    try:
                        a = np.asarray(r[key], float)
                    except (TypeError, ValueError):
                        a = np.full(1, np.nan)
                    if a.shape != shape or not np.all(np.isfinite(a)):
                        raise ValueError(f"effector {k + 1} on {j}: {key!r} must be {shape} finite numbers, "
                                         f"got {r[key]!r}")
            if kind == "rotation":
                try:
                    R = np.asarray(r["base"], float)
                except (TypeError, ValueError):
                    R = np.full(1, np.nan)
                if R.shape not in ((3, 3), (4,), (6,)) or not np.all(np.isfinite(R)):
                    raise ValueError(f"effector {k + 1} on {j}: 'base' must be (3, 3) finite numbers, got {r['base']!r}")
                if R.shape == (3, 3) and (np.abs(R.T @ R - np.eye(3)).max() > 1e-4 or np.linalg.det(R) < 0):
                    raise ValueError(f"effector {k + 1} on {j}: 'base' is not a rotation matrix")
            try:
                lam = float(r.get("lam", 0.0))
            except (TypeError, ValueError):
                lam = np.nan
            if not 0.0 <= lam <= 1.0:
                raise ValueError(f"effector {k + 1} on {j}: tolerance must lie in [0, 1], got {r.get('lam')!r}")
            if kind == "look_at" and np.linalg.norm(np.asarray(r["axis"], float)) < 1e-9:
                raise ValueError(f"effector {k + 1} on {j}: 'axis' must not be zero")
            try:
                e = self._new_row(j, kind, lam, r.get("base") if kind == "rotation" else r.get("target"),
                                  r.get("axis"), out)
            except ValueError as err:
                raise ValueError(f"effector {k + 1}: {err}") from None
            if kind == "rotation" and r.get("euler") is not None:
                e.euler = np.asarray(r["euler"], float)
            for key in ("tolerance", "weight"):
                if r.get(key) is not None:
                    try:
                        v = float(r[key])
                    except (TypeError, ValueError):
                        v = np.nan
                    if not (np.isfinite(v) and v >= 0):
                        raise ValueError(f"effector {k + 1} on {j}: {key!r} must be a number >= 0, got {r[key]!r}")
                    setattr(e, key, v)
            out.append(e)
        return out

    def _set_rows(self, rows):
        self.effectors = list(rows)

    # ------------------------------------------------------------------ timeline keys
    def add_key(self) -> int:
        """Store the current effectors as the next timeline key; returns how many keys there are."""
        if not self.effectors:
            raise ValueError("add an effector before adding a key")
        if self.keys and [(r["joint"], r["kind"]) for r in self.keys[0][0]] != \
                [(e.joint, e.kind) for e in self.effectors]:
            raise ValueError("every key needs the same effectors as the first (same joints and kinds): "
                             "move them, do not add or remove them, or clear the keys")
        self.keys.append((self.setup(), self.solver_effectors()))
        return len(self.keys)

    def clear_keys(self):
        """Forget every timeline key."""
        self.keys = []

    def key_effectors(self, name: str) -> list:
        """Each key's effectors of the kinds solver ``name`` honours (what its in-betweens are made of)."""
        kinds = self.solvers[name].kinds
        return [[e for e in effs if e.kind in kinds] for _, effs in self.keys]

    # ------------------------------------------------------------------ status
    def view_status(self, name: str) -> str:
        """The text under solver ``name``'s view (:func:`~posekit.studio.status.view_status`)."""
        return view_status(name, self.solvers[name], self.solved.get(name, Solved()), self.effectors,
                           [e.joint for e in self.effectors])

    def summary_rows(self) -> list:
        """The summary table's rows (:func:`~posekit.studio.status.summary_rows`): with no effectors each solver's
        row says nothing was solved."""
        return summary_rows({n: self.solved.get(n, Solved()) for n in self.solvers}, self.effectors)


def tolerance_given(e: Effector) -> bool:
    """Whether ``e`` carries a tolerance of its own, not the kind's default (:data:`~posekit.ik.api.DEFAULT_TOLERANCE`)."""
    from ..ik.api import DEFAULT_TOLERANCE

    return e.tolerance != DEFAULT_TOLERANCE.get(e.kind.replace("-", "_"))


def _body(skeleton) -> list:
    from ..data.metrics import body_joints

    return [int(j) for j in body_joints(skeleton)]


def _point(value, joint, what="target") -> np.ndarray:
    try:
        p = np.asarray(value, float).reshape(3)
    except (TypeError, ValueError):
        raise ValueError(f"{joint}: {what} must be 3 numbers, got {value!r}") from None
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{joint}: {what} contains NaN or inf")
    return p


def _rotation_of(skeleton, joint, target) -> np.ndarray:
    return resolve_effectors(skeleton, [Effector(joint, target, "rotation")]).rotation[0]
