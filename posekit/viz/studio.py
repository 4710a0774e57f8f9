"""The posing studio: 2-4 registered solvers side by side on one shared, editable set of effectors.

Introduced in ``notebooks/06_posing_studio.ipynb`` and served as a browser app by Voila (``make studio``).
It is :class:`~posekit.viz.EffectorEditor` (effectors of every kind with tolerances, target sliders,
dragging in 3D) with what an animator expects around it:

* **solvers** — any 2-4 registered names (:func:`posekit.ik.registry.solver_names`), ticked in a list of
  check boxes: a solver a later lesson or a student registers appears without a change here; a summary
  table gives each one's worst effector error and solve time; while solvers load (or anything slow runs)
  the studio says it is busy;
* **undo / redo** — every change is a step (a drag from press to release, or a slider moved without a second's
  pause, is one); a step brings back the views' cameras with the pose;
* **setups** — save and load the effectors as JSON (:mod:`posekit.viz.setup_file`), from a path on the
  server or uploaded from the browser; a malformed file is reported and nothing is lost;
* **export** — the chosen solver's pose as BVH (read back through :func:`posekit.io.bvh.read_bvh` to check it)
  and all views as a PNG (the views' own pixels, read from the page), each with a download link; a start pose can
  be read from a BVH file;
* **timeline** — key effector setups, in-betweens posed by one solver (:mod:`posekit.ik.keyframes`),
  played back and exported as an animated BVH.

Files are written under ``export_dir`` (default :func:`posekit.paths.exports_dir`: ``studio_exports/`` beside the
notebook, or ``$POSEKIT_EXPORTS_DIR``).
"""

from __future__ import annotations

import html
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..ik.api import Effector, Pose
from ..ik.registry import make_solver, solver_names
from ..paths import exports_dir
from ..studio import PosingSession, solve_honoured
from ..studio.status import status_table
from .canvas_capture import CanvasCapture
from .effector_editor import EffectorEditor
from .studio_export import StudioExport, link
from .studio_messages import BUSY_SIGN, WRAP, StudioMessages
from .studio_timeline import StudioTimeline
from .setup_file import SetupError, parse_setup, save_setup
from .shared import widget
from .viewer import show_widget

__all__ = ["PosingStudio", "MIN_SOLVERS", "MAX_SOLVERS"]

MIN_SOLVERS, MAX_SOLVERS = 2, 4


def _error(text: str) -> str:
    return f"<span style='color:#b03a2e'>{html.escape(text)}</span>"


class PosingStudio(StudioExport, StudioTimeline):
    """Registered solvers side by side on shared effectors, with undo, setups, export and a timeline.

    Parameters
    ----------
    skeleton : Skeleton
    start : Pose
        Start pose of the solvers that need one; it must carry rotations (BVH export of positions-only
        solvers turns its rotations onto their positions).
    solvers : sequence of str
        2-4 registered solver names to compare first.
    effectors : list of Effector, optional
    available : sequence of str, optional
        The names offered (default every registered solver).
    tolerance_of : callable, optional
        Passed to :class:`EffectorEditor` (slider value -> tolerance).
    export_dir : str or Path, optional
        Where the studio writes its files (default :func:`posekit.paths.exports_dir`: ``studio_exports/`` in the
        working folder, or ``$POSEKIT_EXPORTS_DIR``).
    own_folder : bool
        The page's files stay in ``export_dir`` (the app a class shares, :func:`~posekit.viz.studio_app.app_studio`):
        the *setup file* box takes a file name there, and a path that leaves the folder is refused with a message, so
        a page neither reads nor writes any other file of the server. Default ``False``: any path (a notebook's own
        kernel).
    width, height : int
        Each view's canvas, pixels (default width: the views share about 1,250 px, 300-560 px each). The page scales
        a canvas down to the width it has (:mod:`posekit.viz.screen_fit`), never up.

    selected : str, optional
        The joint the first view's sliders move at the start.

    Attributes
    ----------
    session : PosingSession
        The one owner of the effectors, the results, the undo steps and the timeline keys
        (:class:`~posekit.studio.PosingSession`): a cell can drive the studio through it
        (``studio.session.move("Hand_L", [0.3, 1.2, 0.2])``) and the views follow.
    editor : EffectorEditor
        The current views and effector rows (rebuilt when the solvers change), showing :attr:`session`.
    history : list of list of dict
        Setups, one per undo step (the session's); ``history[position]`` is the current one.
    cameras : list of dict
        Each step's cameras (solver name -> :meth:`~posekit.viz.SkeletonViewer.camera_state`): undo and redo put
        the views back with the pose.
    keys : list of tuple
        The timeline's keys (the session's).
    frames : list of IKResult
        The last built animation.
    widget : ipywidgets.VBox
    """

    def __init__(self, skeleton, start: Pose, solvers=("fabrik", "dls"), effectors=(), available=None,
                 tolerance_of=None, export_dir=None, own_folder: bool = False, width: int | None = None,
                 height: int = 360, selected=None):
        import ipywidgets as w

        if start.local_rot is None:
            raise ValueError("the studio's start pose needs rotations (Pose.from_rotations)")
        self.skeleton, self.start, self.tolerance_of = skeleton, start, tolerance_of
        self.available = list(available or solver_names())
        self.export_dir = exports_dir() if export_dir is None else Path(export_dir)
        self.own_folder = bool(own_folder)
        self.size = (width, height)
        self.frames, self.timeline_viewer = [], None
        self.session = None

        # every widget's layout and style shared with the widgets that have the same (posekit.viz.shared)
        self.checks = {n: widget(w.Checkbox, value=False, description=n, indent=False, layout={"width": "175px"})
                       for n in self.available}
        self.choose = widget(w.GridBox, list(self.checks.values()),
                             layout={"grid_template_columns": "repeat(auto-fill, 175px)", "width": "min(900px, 100%)"})
        self.compare_button = widget(w.Button, description="compare", button_style="info",
                                     tooltip=f"pose with the ticked {MIN_SOLVERS}-{MAX_SOLVERS} solvers")
        self.compare_button.on_click(lambda _: self._safely(lambda: self.set_solvers(self.chosen), "solvers"))
        self.busy = widget(w.HTML)
        self.summary = widget(w.HTML)
        self.message = StudioMessages()
        lines = self.message.lines
        self.undo_button = widget(w.Button, description="undo", icon="undo", disabled=True, layout={"width": "90px"})
        self.redo_button = widget(w.Button, description="redo", icon="repeat", disabled=True, layout={"width": "90px"})
        self.undo_button.on_click(lambda _: self.undo())
        self.redo_button.on_click(lambda _: self.redo())
        self.setup_path = widget(w.Text, value="setup.json" if self.own_folder else str(self.export_dir / "setup.json"),
                                 description="setup file", layout={"width": "380px"})
        self.save_button = widget(w.Button, description="save setup")
        self.save_button.on_click(lambda _: self._safely(lambda: self.save(self.setup_file()), "setup"))
        self.load_button = widget(w.Button, description="load setup")
        self.load_button.on_click(lambda _: self._safely(lambda: self.load(self.setup_file()), "setup"))
        self.upload = widget(w.FileUpload, accept=".json,.bvh", multiple=False, description="upload setup / BVH",
                             tooltip="a setup (.json) or a BVH pose (.bvh) from your computer",
                             layout={"width": "auto"})
        self.upload.observe(self._on_upload, names="value")
        self.export_solver = widget(w.Dropdown, description="export", layout={"width": "260px"})
        bvh = widget(w.Button, description="pose as BVH")
        bvh.on_click(lambda _: self._safely(lambda: self.export_bvh(), "export"))
        png = widget(w.Button, description="views as PNG")
        png.on_click(lambda _: self._safely(lambda: self.export_png(from_page=True), "export"))
        self.views_capture = CanvasCapture(scope=".posekit-studio", views=".posekit-view")  # reads the views' pixels
        self.inbetweens = widget(w.BoundedIntText, value=10, min=0, max=120, description="in-betweens",
                                 layout={"width": "180px"})
        self.ease = widget(w.Dropdown, options=["smooth", "linear"], value="smooth", description="ease",
                           layout={"width": "180px"})
        add_key = widget(w.Button, description="add key", icon="key")
        add_key.on_click(lambda _: self._safely(self.add_key, "timeline"))
        clear = widget(w.Button, description="clear keys")
        clear.on_click(lambda _: self._safely(self.clear_keys, "timeline"))
        build = widget(w.Button, description="build animation", button_style="info")
        build.on_click(lambda _: self._safely(self.build_animation, "timeline"))
        anim = widget(w.Button, description="animation as BVH")
        anim.on_click(lambda _: self._safely(lambda: self.export_animation(), "timeline"))
        self.keys_label = widget(w.HTML, "no keys yet")
        self.timeline_box = widget(w.VBox, [])
        self.views_box = widget(w.VBox, [])
        row = lambda *ws: widget(w.HBox, list(ws), layout=WRAP)  # noqa: E731
        # the views and the selected joint's controls first: with the studio's top at the screen's top, every view,
        # the selection and its X/Y/Z sliders lie on one 1280 x 800 screen (posekit.viz.screen_fit); the choice of
        # solvers under them
        self.widget = widget(w.VBox, [
            self.views_box,
            widget(w.HTML, f"<b>Solvers</b> — tick {MIN_SOLVERS} to {MAX_SOLVERS}, then compare"),
            row(self.choose, widget(w.VBox, [self.compare_button, self.busy, lines["solvers"]])),
            widget(w.HTML, "<b>All solvers</b>"), self.summary,
            row(self.undo_button, self.redo_button, self.setup_path, self.save_button, self.load_button, self.upload,
                lines["setup"]),
            row(self.export_solver, bvh, png, lines["export"], self.views_capture),
            widget(w.HTML, "<b>Timeline</b> — key setups; in-betweens posed by the export solver"),
            row(add_key, clear, self.inbetweens, self.ease, build, anim, lines["timeline"]), self.keys_label,
            self.timeline_box], layout={"max_width": "100%"})
        for part, name in ((self.widget, "studio"), (self.summary, "summary"), (self.choose, "solver-choice"), (self.busy, "busy"),
                             (self.compare_button, "compare"), (self.views_box, "views")):
            part.add_class(f"posekit-{name}")  # for a browser test (and a stylesheet)
        self.editor = None
        self.set_solvers(solvers, effectors=effectors, selected=selected)
        self.session.notes[self.session.position]["cameras"] = self._cameras()

    def _ipython_display_(self):
        show_widget(self.widget, f"[posing studio: {', '.join(self.solvers)} side by side on {len(self.editor.rows)} "
                                 "effectors, with undo, setups, export and a timeline. It runs in a live Jupyter "
                                 "kernel: run the notebook, or serve it with make studio]")

    def _safely(self, action, row: str):
        """Run a button's action with the studio marked busy; what it says, or a ValueError (bad input) as an
        error, goes on the line of its ``row`` of controls (:class:`StudioMessages`), never a traceback; an earlier
        message, anywhere, is cleared."""
        self.message.row = row
        self.message.value = ""
        try:
            with self.working():
                action()
        except (ValueError, OSError) as err:
            self.message.row = row
            self.message.value = _error(str(err))

    @property
    def chosen(self) -> tuple:
        """The ticked solver names, in the list's order."""
        return tuple(n for n, c in self.checks.items() if c.value)

    @contextmanager
    def working(self, what: str = "working"):
        """Mark the studio busy (a note beside *compare*, the button disabled) while the block runs."""
        self.busy.value = f"<span style='color:#b9770e'>{BUSY_SIGN}{html.escape(what)}…</span>"
        self.compare_button.disabled = True
        try:
            yield
        finally:
            self.busy.value = ""
            self.compare_button.disabled = False

    # ------------------------------------------------------------------ solvers and views
    @property
    def solvers(self) -> list:
        """The names being compared."""
        return list(self.editor.solvers)

    # the session's steps and keys, read where they are kept
    history = property(lambda self: self.session.history)
    position = property(lambda self: self.session.position)
    keys = property(lambda self: self.session.keys)

    @property
    def cameras(self) -> list:
        """Each step's cameras (solver name -> camera state), kept with the session's steps."""
        return [n.get("cameras", {}) for n in self.session.notes]

    def set_solvers(self, names, effectors=(), selected=None):
        """Compare these 2-4 registered solvers on the current effectors (or ``effectors`` at the start)."""
        names = list(dict.fromkeys(names))
        if not MIN_SOLVERS <= len(names) <= MAX_SOLVERS:
            raise ValueError(f"choose {MIN_SOLVERS} to {MAX_SOLVERS} solvers to compare, got {len(names)}")
        unknown = [n for n in names if n not in self.available]
        if unknown:
            raise ValueError(f"unknown solver(s) {', '.join(map(repr, unknown))}; registered: {', '.join(self.available)}")
        built = {}
        for n in names:
            try:
                built[n] = make_solver(n, self.skeleton)
            except ValueError as err:
                raise ValueError(f"{n} cannot pose this skeleton: {err}") from None
        for solver in built.values():  # a first solve compiles or loads what it needs: not part of its time
            self._warm_up(solver, effectors)
        w, h = self.size
        w = w or int(np.clip(1250 // len(names), 300, 560))
        if self.session is None:
            self.session = PosingSession(self.skeleton, self.start, built, effectors, tolerance_of=self.tolerance_of)
            self.session.on_before_change(self._before_change)
        replacing = self.editor is not None
        if replacing:
            selected = self.editor.first.selected  # keep the joint the sliders move
            self.editor.close()
        editor = EffectorEditor(self.skeleton, built, self.start, session=self.session, width=w, height=h,
                                selected=selected)
        editor.first.page_watch.reveal = replacing  # after compare: the new views scrolled into sight
        editor.on_change(self._on_change)
        editor.keys_undo, editor.keys_redo = self.undo, self.redo  # Ctrl+Z anywhere in the studio: its undo
        editor.first.page_watch.keys_scope = "posekit-studio"
        self.editor = editor
        self.views_box.children = (editor.widget,)
        for n, c in self.checks.items():
            c.value = n in names
        self.export_solver.options = names
        self.export_solver.value = names[0]
        self._refresh()

    def _warm_up(self, solver, effectors=()):
        """Solve once so that the first real solve is not the one that compiles kernels or loads weights: with
        ``effectors`` when given, else with the first of a few effector sets (both hands; hands, feet and head;
        the pelvis) that this solver accepts (a learned solver only takes the joint sets it was trained on)."""
        s, P = self.skeleton, self.start.global_pos
        roles = [r for r in ("left_wrist", "right_wrist", "left_ankle", "right_ankle", "head") if r in s.roles]
        candidates = [list(effectors)] if effectors else []
        candidates += [[Effector(r, P[s.index(r)]) for r in roles[:2]], [Effector(r, P[s.index(r)]) for r in roles],
                       [Effector(s.pelvis(), P[s.pelvis()])]]
        for effs in candidates:
            done = solve_honoured(solver, self.start, effs) if effs else None
            if done is not None and done.result is not None and not isinstance(done.result, Exception):
                return True  # else the next set; the real solve says what is wrong
        return False

    def _refresh(self):
        self.undo_button.disabled = not self.session.can_undo
        self.redo_button.disabled = not self.session.can_redo
        # the update counter last: when the browser shows it, every view and button of this update is there
        self.summary.value = status_table(f"update {self.session.updates}", self.session.summary_rows())

    # ------------------------------------------------------------------ undo and redo
    def _on_change(self, what, index):
        """After a change, its solve and its drawing: the step's cameras as the views show them now (undo and redo put
        the step's cameras back instead), then the summary."""
        note = self.session.notes[self.session.position]
        if what in ("undo", "redo", "cancel"):
            for name, state in note.get("cameras", {}).items():  # each view as it was at that step
                if name in self.editor.viewers:
                    self.editor.viewers[name].set_camera_state(state)
        elif what != "solvers":
            note["cameras"] = self._cameras()
        self._refresh()

    def _before_change(self, what, index):
        """The current step's cameras as the views show them just before a change (an orbit since is kept)."""
        if self.editor is not None:
            self.session.notes[self.session.position]["cameras"] = self._cameras()

    def _cameras(self) -> dict:
        """Each view's camera (:meth:`~posekit.viz.SkeletonViewer.camera_state`), by solver name."""
        return {n: v.camera_state() for n, v in self.editor.viewers.items()}

    def undo(self):
        """Go back one step (no-op at the first): the effectors and the views' cameras of that step."""
        self.session.undo()

    def redo(self):
        """Redo the step undone last (no-op when there is none)."""
        self.session.redo()

    # ------------------------------------------------------------------ setups
    def setup_file(self) -> Path:
        """The file the *setup file* box names: the path as typed, or with :attr:`own_folder` a file name inside
        ``export_dir`` (a path that leaves it, absolute or through ``..``, raises ValueError)."""
        text = self.setup_path.value.strip()
        if not self.own_folder:
            return Path(text)
        name = Path(text)
        if not name.parts or name.is_absolute() or ".." in name.parts:
            raise ValueError(f"setup file {text!r}: give a file name in this page's folder, {self.export_dir} "
                             "(e.g. setup.json)")
        return self.export_dir / name

    def save(self, path) -> Path:
        """Write the effectors and the solvers as a setup JSON file; the message links a download."""
        path = save_setup(path, self.skeleton, self.editor.setup(), self.solvers)
        self.message.row = "setup"
        self.message.value = f"saved {html.escape(str(path))} ({len(self.session.effectors)} effectors) — {link(path, 'application/json')}"
        return path

    def load(self, path):
        """Load a setup JSON file (its solvers too, when they are registered). A bad file changes nothing."""
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as err:
            raise SetupError(f"{path}: cannot read the setup file ({err})") from None
        self.load_text(text, source=str(path))

    def load_text(self, text: str, source: str = "setup"):
        """Apply setup JSON text (see :meth:`load`)."""
        doc = parse_setup(text, self.skeleton, source)
        try:
            self.session.from_dict(doc)  # checks every effector before changing anything
        except ValueError as err:
            raise SetupError(f"{source}: {err}") from None
        names = [n for n in doc["solvers"] if n in self.available]
        if MIN_SOLVERS <= len(names) <= MAX_SOLVERS and names != self.solvers:
            try:
                self.set_solvers(names)
            except ValueError:
                self.session.revert_to(self.session.position - 1)
                raise
        self.message.row = "setup"
        self.message.value = f"loaded {html.escape(source)}: {len(doc['effectors'])} effectors"

    def _on_upload(self, change):
        files = change["new"]
        if not files:
            return
        self.message.row = "setup"
        self.message.value = ""
        f = files[0]
        name, content = f["name"], bytes(f["content"])
        try:
            if name.lower().endswith(".bvh"):
                self.export_dir.mkdir(parents=True, exist_ok=True)
                target = self.export_dir / Path(name).name
                target.write_bytes(content)
                self.load_start_bvh(target)
            else:
                try:
                    text = content.decode("utf-8")
                except UnicodeDecodeError:
                    raise SetupError(f"{name}: not a text file (expected setup JSON)") from None
                self.load_text(text, source=name)
        except ValueError as err:
            self.message.row = "setup"
            self.message.value = _error(str(err))
