"""An interactive 3D skeleton viewer for Jupyter (pythreejs + ipywidgets).

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``; every later lesson poses through it, and
``notebooks/06_posing_studio.ipynb`` drags targets in it. World axes: :mod:`posekit.conventions`
(metres, Y up, the character faces +Z).

What it shows: a skeleton (bones as solid cylinders coloured by side — left blue, right red, centre
grey — with a sphere at every joint, so that they read as capsules), an optional translucent *ghost*
pose for comparison, *target* markers (magenta), *look-at* targets (orange, with a ray from the joint) and
*rotation* targets (an axes triad at the joint: x red, y green, z blue, in the orientation asked for).
Updating a pose rewrites the buffers of the existing geometries (:mod:`posekit.viz.meshes`) instead of
rebuilding the scene, so playback and live solving stay smooth. The camera keeps the pose framed: it is
fitted to the pose (or to a whole clip in :meth:`SkeletonViewer.player`), and follows a pose that leaves
the framed region.

Interaction: orbit with the mouse (drag to rotate, wheel to zoom, right-drag to pan; **reset view** frames the
pose from the front again);
**double-click** a joint to select it (a single-click picker would also fire at the end of every
orbit drag); the X/Y/Z sliders then move that joint's target, in 1 mm steps within
:attr:`SkeletonViewer.SLIDER_SPAN` of it (a slider pushed to an end of its range re-centres on the new
value, so any point can be reached). A joint with both a target and a look-at target gets a choice of
which one the sliders move. Selecting never moves anything, and a key press moves the joint selected when it
arrives by exactly its steps, however soon after a selection: the kernel never changes a slider the browser
shows, it replaces it (:mod:`posekit.viz.sliders`), and the page gives the keyboard to the new slider of the axis
whose handle had it (:mod:`posekit.viz.page_watch`). Helper joints that are not part of the body (Bandai's
``joint_Root``, the world point under the feet) cannot be selected, nor joints a view does not offer
(``selectable``: a panel offers the joints its solvers were given). With **drag in 3D** on, orbiting stops and
pressing the mouse on a target marker or a joint and moving it drags that target across the plane through it that faces
the camera (the camera waits for the mouse to be released before it takes a far target in, so the drag
keeps its scale); letting the button go anywhere, on the page or outside the window, ends the drag
(:mod:`posekit.viz.drag`). ``on_target_change`` callbacks (an IK solver, in later lessons) receive
``(joint_name, position)``; targets are always stored under the joint's own name, whatever name, role
or index the caller used.

The viewer knows no solver: lessons connect one through :meth:`SkeletonViewer.on_target_change`.
"""

from __future__ import annotations

import html
import os
from contextlib import contextmanager

import numpy as np

from ..data.metrics import body_joints
from ..skeleton import Skeleton
from .camera import FramedCamera, orthographic_matrix, perspective_matrix, translation_matrix
from .drag import DragTargets
from .meshes import Bones, Figure, Spheres, icosphere
from .page_watch import PageWatch
from .screen_fit import VIEWER_LAYOUT, WRAP_ROW, stylesheet
from .shared import layout, model, widget
from .sliders import TargetSliders

__all__ = ["SkeletonViewer", "antialias_default", "icosphere", "show_widget", "TARGET_COLOUR", "LOOK_COLOUR"]

TARGET_COLOUR = "#d81b9c"
"""Position targets: magenta, apart from the right side's red bones and the look-at orange."""
LOOK_COLOUR = "#e67e22"
"""Look-at targets and their rays: orange."""
SELECTED_COLOUR = "#f1c40f"
"""The selected joint: drawn larger, in yellow."""
TRIAD_LENGTH = 0.2
"""Length (metres) of each axis of a rotation target's triad."""


def show_widget(widget, text: str) -> None:
    """Display an ipywidget whose static rendering (a saved notebook, a page without a live kernel) is ``text``
    — what would be there — instead of ipywidgets' ``VBox(children=...)``."""
    from IPython.display import display

    bundle = widget._repr_mimebundle_()
    bundle["text/plain"] = text
    display(bundle, raw=True)


def _sun(target):
    """The view's directional light (white, 0.75, from above, right and in front, towards ``target``: the group of
    the scene content, at the world origin), with its shadow camera made here. Without a target and a shadow camera
    the browser makes both (three.js lights carry them) and opens three new models in the kernel for every view as a
    page opens; the shadow camera's projection is given as three.js computes it
    (:func:`~posekit.viz.camera.orthographic_matrix` of its default box), so the browser has nothing to report. No
    shadow is drawn, so every view's light holds the same shadow model (:func:`~posekit.viz.shared.model`)."""
    import pythreejs as three

    box = dict(zip(("left", "right", "top", "bottom", "near", "far"), (-5.0, 5.0, 5.0, -5.0, 0.5, 500.0)))
    # three.js' DirectionalLightShadow's box
    camera = model(three.OrthographicCamera, **box, projectionMatrix=orthographic_matrix(*box.values()))
    # matrixWorldNeedsUpdate as three.js leaves it for a light it has placed: nothing to report back either
    return three.DirectionalLight(color="#ffffff", position=[3, 5, 4], intensity=0.75, target=target,
                                  shadow=model(three.DirectionalLightShadow, camera=camera),
                                  matrixWorldNeedsUpdate=True)


class OwnMarkers:
    """The points a view shows when no session drives it (a lesson's lone viewer): those :meth:`SkeletonViewer.
    set_targets` gave and the sliders or a drag moved. A :class:`~posekit.studio.PosingSession` has the same
    ``markers()`` and ``move()``: a view attached to one (:meth:`SkeletonViewer.attach`) keeps no points at all."""

    def __init__(self):
        self.positions, self.looks, self.rotations = {}, {}, {}

    def markers(self) -> tuple:
        return self.positions, self.looks, self.rotations

    def move(self, joint, point, kind: str = "position"):
        (self.looks if kind == "look_at" else self.positions)[joint] = point


def antialias_default() -> bool:
    """Whether viewers smooth their edges: yes, unless ``POSEKIT_ANTIALIAS=0`` (``make studio STUDIO_ANTIALIAS=0``).

    For a browser without a GPU (software WebGL, e.g. Chromium's SwiftShader on a server or a virtual desktop):
    multisampling makes every redraw rasterise several samples per pixel, and a compositor without a GPU then reads
    each canvas back. Measured on a 2-core machine with headless Chromium, two 560 x 360 views of the studio: the
    browser's WebGL time per update 20 ms with antialiasing, 8 ms without (``posekit bench studio`` serves the
    studio without it; ``--antialias`` keeps it)."""
    return os.environ.get("POSEKIT_ANTIALIAS", "1").strip() != "0"


class SkeletonViewer(FramedCamera, DragTargets, TargetSliders):
    """A pythreejs scene of one skeleton with a ghost, targets, picking, dragging and sliders.

    Parameters
    ----------
    skeleton : Skeleton
    pose : ndarray, shape (J, 3), metres, optional
        Global joint positions; default the rest pose.
    ghost : ndarray, shape (J, 3), optional
        A second pose drawn translucent (e.g. the ground truth, or another solver).
    targets : dict, optional
        Joint name (or role, or index) -> (3,) target position, drawn as magenta spheres.
    width, height : int
        Canvas size in pixels.
    joint_radius : float
        Joint sphere radius in metres (bones are 0.7 of it).
    controls : bool
        Show the joint selector, the drag toggle, the X/Y/Z target sliders and the status table. Without them
        (``False``) they are made only when first asked for (:attr:`controls`, :attr:`widget` ...), hidden: the
        second to fourth views of a panel or of the studio, shown by their canvases alone, cost no widget models for
        controls another view holds.
    follow : bool
        Re-centre the view when a pose leaves the framed region.
    antialias : bool, optional
        Smooth the edges (multisampling). Default: on, unless the environment variable ``POSEKIT_ANTIALIAS`` is
        ``0`` (:func:`antialias_default`) — for browsers that draw WebGL in software (no GPU), where it costs the
        most.
    selectable : sequence of str or int, optional
        The joints offered (the *selected* list, double-click, drag in 3D): names, roles or indices; default every
        body joint. A panel whose solvers take only some joints offers only those (lesson 02: the rig's handles).

    Attributes
    ----------
    widget : ipywidgets.VBox
        What to display (the viewer also displays itself when it is a cell's last value).
    selected : str or None
        Name of the selected joint.
    pose : ndarray, shape (J, 3)
    targets, look_targets : dict
        Joint name -> (3,) point, metres.
    dragging : str or None
        The joint whose target the mouse is dragging (:class:`~posekit.viz.drag.DragTargets`).
    """

    def __init__(self, skeleton: Skeleton, pose=None, ghost=None, targets=None, width: int = 560,
                 height: int = 420, joint_radius: float = 0.025, controls: bool = True,
                 background: str = "#f7f7f2", floor: bool = True, follow: bool = True, antialias: bool | None = None,
                 selectable=None):
        import pythreejs as three

        from ..kinematics import rest_pose

        self.skeleton = skeleton
        J = skeleton.n_joints
        self.pose = np.array(rest_pose(skeleton) if pose is None else pose, dtype=float)
        self._check(self.pose, "pose")
        self.source = OwnMarkers()  # what the markers show: a session (attach), or the points set_targets gave
        self.selected = None
        self.follow = follow
        self.aspect = width / height
        self._select_callbacks, self._target_callbacks, self._look_callbacks = [], [], []
        self._init_drag()
        self._held, self._status_due = False, False
        self.body = [int(j) for j in body_joints(skeleton)]  # the body (not a helper root)
        self.selectable = self.body if selectable is None else self._selectable(selectable)  # what can be selected

        # bones, joints (the selected one larger and yellow), targets, rays and triads: one position array
        self._figure = Figure(skeleton, joint_radius, 0.7 * joint_radius, "#2e86c1", SELECTED_COLOUR, TARGET_COLOUR,
                              LOOK_COLOUR, 1.3 * joint_radius, TRIAD_LENGTH)
        self._joint_radius = joint_radius
        self._draw_due = False
        self._ghost_bones = Bones(skeleton, radius=0.45 * joint_radius, opacity=0.35, colour="#8c8c8c")
        self._ghost_joints = Spheres(J, joint_radius * 0.6, "#aaaaaa", opacity=0.4)
        self._ghost_group = three.Group(children=[self._ghost_bones.mesh, self._ghost_joints.mesh])
        self._target_key = None
        f = self._figure
        self._grabbable = three.Group(children=[f.joints, f.targets, f.looks])  # what a drag can grab

        # The scene content sits in a group shifted by -centre, so the orbit pivot (the origin,
        # where OrbitControls starts) is the middle of the pose.
        centre, radius = self._frame(self.pose)
        self._offset, self._radius = centre.copy(), radius
        # each matrix as the browser computes it (and the grid's three.js type), so an opening page reports none back
        at = self._camera_position(radius)
        self.camera = three.PerspectiveCamera(position=at, fov=self.FOV, aspect=self.aspect, near=0.01, far=200,
                                              matrix=translation_matrix(at),
                                              projectionMatrix=perspective_matrix(self.FOV, self.aspect, 0.01, 200))
        content = [f.bones, self._grabbable, f.rays, f.triads, self._ghost_group]
        if floor:
            content.append(three.GridHelper(size=6, divisions=24, colorCenterLine="#888888", colorGrid="#cccccc",
                                            type="LineSegments"))
        shift = [float(-c) for c in centre]
        self._world = three.Group(children=content, position=shift, matrix=translation_matrix(shift))
        self.scene = three.Scene(children=[self._world, self._drag_surface(), self.camera,
                                           three.AmbientLight(color="#ffffff", intensity=0.55),
                                           _sun(self._world)],
                                 background=background)
        self.orbit = three.OrbitControls(controlling=self.camera)
        self.picker = three.Picker(controlling=f.joints, event="dblclick")
        self.picker.observe(self._on_pick, names=["point"])
        # a view without controls shows no drag switch: its drag pickers are made if code ever turns dragging on
        self.renderer = three.Renderer(camera=self.camera, scene=self.scene,
                                       controls=[self.orbit, self.picker, *(self._drag_pickers() if controls else [])],
                                       width=width, height=height, layout=layout(),
                                       shadowMap=model(three.WebGLShadowMap),  # no shadow drawn: one for every view
                                       antialias=antialias_default() if antialias is None else bool(antialias))
        self.renderer.add_class("posekit-canvas")  # scaled to its box's width (posekit.viz.screen_fit)

        self._show_controls, self._controls_made, self._sliders_due = bool(controls), False, False
        if controls:
            self._make_controls()
            self._make_widget()

        self.set_pose(self.pose)
        self.set_ghost(ghost)
        self.set_targets(targets or {})

    _LAZY = {**dict.fromkeys(("controls", "status", "joint_select", "drag_mode", "reset_button", "handle_choice",
                              "slider_box", "sliders", "slider_generation", "page_watch"), "_make_controls"),
             "widget": "_make_widget", "_extra": "_make_widget"}
    """The parts a view without controls makes when first asked for, and the method that makes them."""

    @property
    def targets(self) -> dict:
        """Joint name -> (3,) position target, read from :attr:`source` (the view keeps none of its own)."""
        return self.source.markers()[0]

    @property
    def look_targets(self) -> dict:
        """Joint name -> (3,) point the joint looks at, read from :attr:`source`."""
        return self.source.markers()[1]

    @property
    def rotation_targets(self) -> dict:
        """Joint name -> (3, 3) world rotation asked for, read from :attr:`source`."""
        return self.source.markers()[2]

    def attach(self, source):
        """Show the markers of ``source`` (a :class:`~posekit.studio.PosingSession`: ``markers()``, ``move(joint,
        point, kind)`` and ``select(joint)``) from now on: a drag or a slider moves its targets, and :meth:`show`
        redraws what it holds."""
        self.source = source
        self.show()

    def __getattr__(self, name):
        make = SkeletonViewer._LAZY.get(name)
        made = self.__dict__.get("_controls_made")
        if make is None or made is None or (made and make == "_make_controls"):  # not lazy, in __init__, or made
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        getattr(self, make)()
        return self.__dict__[name]

    def _make_controls(self):
        """The joint selector, the drag toggle, *reset view*, the target sliders and the status table, showing the
        view as it is now (made in ``__init__`` with ``controls``, else when first asked for)."""
        import ipywidgets as w

        self._controls_made = True
        skeleton = self.skeleton
        self.status = widget(w.HTML, value="double-click a joint to select it")
        # "" stands for no selection: a Dropdown whose value is None shows a blank box
        self.joint_select = widget(w.Dropdown,
                                   options=[("(none)", "")] + [(skeleton.names[j],) * 2 for j in self.selectable],
                                   value=self.selected or "", description="selected", layout={"width": "230px"})
        self.joint_select.observe(lambda ch: self.select(ch["new"] or None), names="value")
        self.drag_mode = self._drag_toggle()
        self.reset_button = widget(w.Button, description="reset view", icon="home", layout={"width": "110px"},
                                   tooltip="frame the pose again, seen from the front")
        self.reset_button.on_click(lambda _: self.reset_view())
        self._init_sliders()
        # what only the page sees (a release anywhere, the focused slider handle) for the canvas and the controls,
        # which carry its CSS class: shows nothing
        scope = f"posekit-view-{self.renderer.model_id}"
        self.page_watch = widget(PageWatch, scope=scope, layout={"display": "none"})
        self.page_watch.on_release(self._let_go)
        self.page_watch.on_key("cancel", self.cancel_drag)
        self.renderer.add_class(scope)
        # a layout of its own: showing or hiding the controls changes it
        # the selection's row and the sliders beside the readout, each wrapping on a narrow page (screen_fit)
        self.controls = widget(w.VBox, [widget(w.HBox, [self.joint_select, self.drag_mode, self.reset_button],
                                               layout=WRAP_ROW),
                                        self.handle_choice,
                                        widget(w.HBox, [self.slider_box, self.status],
                                               layout={**WRAP_ROW, "align_items": "flex-start"}),
                                        self.page_watch],
                               layout=w.Layout(display=None if self._show_controls else "none"))
        self.controls.add_class("posekit-viewer")
        self.controls.add_class(scope)
        if self.selected is not None:  # made after a selection: the sliders and the readout show it
            self._sync_sliders(recentre=True)
            self._update_status()

    def _make_widget(self):
        """What to display: the canvas, the controls (shown or not) and room for a lesson's own controls."""
        import ipywidgets as w

        self._extra = widget(w.VBox, [])
        # the page's rules last: the first text of the widget stays the selection's readout
        self.widget = widget(w.VBox, [self.renderer, self.controls, self._extra, stylesheet()], layout=VIEWER_LAYOUT)
        self.widget.add_class("posekit-viewer")

    # ------------------------------------------------------------------ helpers
    def _check(self, pos, what):
        pos = np.asarray(pos, dtype=float)
        if pos.shape != (self.skeleton.n_joints, 3):
            raise ValueError(f"{what}: expected shape ({self.skeleton.n_joints}, 3), got {pos.shape}")
        if not np.all(np.isfinite(pos)):
            raise ValueError(f"{what} contains NaN or inf")
        return pos

    def _ipython_display_(self):
        show_widget(self.widget, f"[3D skeleton viewer: {self.skeleton.n_joints} joints. It draws in a running Jupyter "
                                 "kernel; run the cell to see it and pose the skeleton]")

    # ------------------------------------------------------------------ drawing
    def set_pose(self, global_pos):
        """Show a new pose: global joint positions, shape (J, 3), metres (the view follows a pose that
        leaves the framed region, when ``follow``)."""
        self.pose = self._check(global_pos, "pose").copy()
        self._draw()
        self._follow()
        if self.selected is not None:
            self._update_status()

    def set_ghost(self, global_pos=None):
        """Show (shape (J, 3)) or hide (None) the ghost pose."""
        if global_pos is None:
            self._ghost_group.visible = False
            return
        g = self._check(global_pos, "ghost")
        self._ghost_bones.set(g)
        self._ghost_joints.set(g)
        self._ghost_group.visible = True

    def _points(self, targets: dict, what: str) -> dict:
        new = {}
        for name, p in targets.items():
            name = self.skeleton.names[self.skeleton.index(name)]
            p = np.asarray(p, dtype=float).reshape(3)
            if not np.all(np.isfinite(p)):
                raise ValueError(f"{what} for {name} contains NaN or inf")
            new[name] = p
        return new

    def set_targets(self, targets: dict, look_at: dict | None = None, rotations: dict | None = None):
        """Replace the target markers: joint name -> (3,) position in metres (magenta spheres). ``look_at``: joint
        name -> (3,) point the joint should face, drawn as an orange sphere with a ray from the joint (a joint
        may appear in both; the sliders then move the one :attr:`handle_choice` says). ``rotations``: joint name
        -> (3, 3) world rotation the joint should take, drawn as an axes triad at the joint (x red, y green,
        z blue; :data:`TRIAD_LENGTH`), so turning a rotation target shows on screen."""
        new = self._points(targets, "target")
        looks = self._points(look_at or {}, "look-at target")
        rots = {}
        for name, R in (rotations or {}).items():
            name = self.skeleton.names[self.skeleton.index(name)]
            R = np.asarray(R, dtype=float)
            if R.shape != (3, 3) or not np.all(np.isfinite(R)):
                raise ValueError(f"rotation target for {name}: expected a finite (3, 3) matrix, got shape {R.shape}")
            rots[name] = R
        if not isinstance(self.source, OwnMarkers):
            raise ValueError("this view shows a session's effectors: change them through the session (move, add, "
                             "remove), and the view follows")
        self.source.positions, self.source.looks, self.source.rotations = new, looks, rots
        self.show()

    def show(self, pose=None):
        """Draw the markers :attr:`source` holds now (and ``pose``, (J, 3), when given), once: the figure is laid
        out again only when the set of markers changed; the sliders show the selected joint's handle."""
        if pose is not None:
            self.pose = self._check(pose, "pose").copy()
            self._draw_due = True
        new, looks, rots = self.source.markers()
        key = (tuple(new), tuple(looks), tuple(rots))
        if key != self._target_key:
            self._target_key = key
            self._figure.layout(len(new), len(looks), len(rots))
        self._draw()
        self._follow()
        self._sync_sliders()
        self._show_handle_choice()
        if self.selected is not None:
            self._update_status()

    @contextmanager
    def drawing_once(self):
        """Within the block, changes of pose, targets and selection are drawn (one position array), the camera
        moved and the selected joint's readout written once, at the end (a moved target solves, then sets the
        pose: one message each instead of two)."""
        if self._held:
            yield
            return
        self._held = True
        try:
            yield
        finally:
            self._held = False
            self._send_due()

    def _send_due(self):
        """Send the pose, the camera and the readout that a :meth:`drawing_once` block held back."""
        if self._draw_due:
            self._draw()
        self._follow()
        if self._status_due:
            self._update_status()

    def flush(self):
        """Within :meth:`drawing_once`, send what is due now (the pose, the camera, the readout) rather than at the
        block's end: a listener whose news must reach the browser after this view's (the studio's update counter,
        which says every view is drawn) calls it first. Outside the block it does nothing."""
        if not self._held:
            return
        self._held = False
        try:
            self._send_due()
        finally:
            self._held = True

    def _draw(self):
        """Send the pose, its targets, look-at rays and rotation triads (:class:`~posekit.viz.meshes.Figure`: one
        array); within :meth:`drawing_once`, once at its end."""
        if self._held:
            self._draw_due = True
            return
        self._draw_due = False
        index = self.skeleton.index
        self._figure.draw(self.pose, list(self.targets.values()), list(self.look_targets.values()),
                          [index(n) for n in self.look_targets], list(self.rotation_targets.values()),
                          [index(n) for n in self.rotation_targets])

    # ------------------------------------------------------------------ selection and targets
    def select(self, joint):
        """Select a joint by name, role or index (None clears the selection)."""
        name = None if joint is None else self.skeleton.names[self.skeleton.index(joint)]
        if name is not None and self.skeleton.index(name) not in self.body:
            raise ValueError(f"{name} is a helper joint, not part of the body: it cannot be selected")
        if name is not None and self.skeleton.index(name) not in self.selectable:
            raise ValueError(f"{name} is not offered in this view: choose one of {self._offered()}")
        self.selected = name
        if hasattr(self.source, "select"):
            self.source.select(name)  # the session knows what the sliders move; it adds nothing
        self._show_handle_choice()
        if self._controls_made and self.joint_select.value != (name or ""):
            self.joint_select.value = name or ""
        self._figure.highlight(None if name is None else self.skeleton.index(name))
        self._draw()  # the selected joint drawn larger
        self._sync_sliders(recentre=True)
        self._update_status()
        for cb in self._select_callbacks:
            cb(name)

    def _selectable(self, joints) -> list:
        """Body joint indices of ``joints`` (names, roles or indices), in skeleton order."""
        wanted = {int(self.skeleton.index(j)) for j in joints}
        helpers = [self.skeleton.names[j] for j in wanted if j not in self.body]
        if helpers:
            raise ValueError(f"selectable: {', '.join(helpers)} not part of the body (helper joints)")
        return [j for j in self.body if j in wanted]

    def _offered(self) -> str:
        return ", ".join(self.skeleton.names[j] for j in self.selectable)

    def _refuse(self, name):
        """Say in the status line that ``name`` (clicked or pressed on) is not offered here."""
        if not self._controls_made:
            return
        self.status.value = (f"<span style='color:#b03a2e'>{html.escape(name)} is not offered here (no solver of this "
                             f"view takes it): choose {html.escape(self._offered())}</span>")

    def _nearest_joint(self, p):
        """The body joint nearest to point ``p`` (3,), world frame, metres."""
        body = self.pose[self.body]
        return self.skeleton.names[self.body[int(np.argmin(np.linalg.norm(body - p, axis=1)))]]

    PICK_RESET = [0.0, -1000.0, 0.0]
    """Where the kernel puts the picker's point after each double-click (never a point of the scene): the browser
    reports a point only when it changes, so a second double-click on the same pixel, after the dropdown chose
    another joint, would otherwise say nothing."""

    def _on_pick(self, change):
        p = np.asarray(change["new"], dtype=float)
        if list(change["new"]) == self.PICK_RESET:
            return  # the kernel's own reset
        try:
            if p.shape != (3,) or not np.all(np.isfinite(p)) or self.picker.distance is None:
                return  # the double-click hit nothing
            name = self._nearest_joint(p + self._offset)  # picked point is in scene coordinates
            if self.skeleton.index(name) not in self.selectable:
                self._refuse(name)
                return
            self.select(name)
        finally:
            self.picker.point = list(self.PICK_RESET)

    def move_target(self, joint, position):
        """Set one joint's target (creating it if needed) and notify ``on_target_change`` callbacks."""
        name = self.skeleton.names[self.skeleton.index(joint)]
        position = np.asarray(position, dtype=float).reshape(3)
        if not np.all(np.isfinite(position)):
            raise ValueError(f"target for {name} contains NaN or inf")
        with self.drawing_once():  # the source's solve sets the pose: the readout is written once, after it
            self.source.move(name, position, "position")
            self.show()
            for cb in self._target_callbacks:
                cb(name, self.targets[name].copy())

    def move_look_target(self, joint, position):
        """Move the point a joint looks at (its orange marker) and notify ``on_look_target_change`` callbacks."""
        name = self.skeleton.names[self.skeleton.index(joint)]
        position = np.asarray(position, dtype=float).reshape(3)
        if name not in self.look_targets:
            raise ValueError(f"{name} has no look-at target to move")
        if not np.all(np.isfinite(position)):
            raise ValueError(f"look-at target for {name} contains NaN or inf")
        with self.drawing_once():
            self.source.move(name, position, "look_at")
            self.show()
            if not self._look_callbacks:  # nobody listens to look-at moves: the joint's target it is
                for cb in self._target_callbacks:
                    cb(name, position.copy())
            for cb in self._look_callbacks:
                cb(name, position.copy())

    def on_look_target_change(self, callback):
        """Call ``callback(joint_name, position)`` whenever an orange look-at marker is dragged (without such a
        callback, dragging one moves the joint's target through ``on_target_change``)."""
        self._look_callbacks.append(callback)

    def on_select(self, callback):
        """Call ``callback(joint_name or None)`` whenever the selection changes."""
        self._select_callbacks.append(callback)

    def on_target_change(self, callback):
        """Call ``callback(joint_name, position)`` whenever a target moves (sliders, dragging or code)."""
        self._target_callbacks.append(callback)

    def _update_status(self):
        if not self._controls_made:  # written when the controls are made
            return
        if self._held:  # written once, when the drawing_once block ends
            self._status_due = True
            return
        self._status_due = False
        if self.selected is None:
            self.status.value = "double-click a joint to select it"
            return
        p = self.pose[self.skeleton.index(self.selected)]
        rows = [(html.escape(self.selected), p, "")]
        if self.selected in self.targets:
            t = self.targets[self.selected]
            rows.append(("target", t, f"{np.linalg.norm(t - p) * 100:.1f} cm away"))
        if self.selected in self.look_targets:
            t = self.look_targets[self.selected]
            rows.append(("looks at", t, f"{np.linalg.norm(t - p) * 100:.1f} cm away"))
        cell = "<td style='padding:0 8px;text-align:right;font-family:monospace'>{}</td>"
        body = "".join(f"<tr><th style='text-align:left;padding-right:8px'>{n}</th>"
                       + "".join(cell.format(f"{c:+.3f}") for c in q) + f"<td style='padding-left:8px'>{extra}</td></tr>"
                       for n, q, extra in rows)
        self.status.value = ("<table style='border-collapse:collapse'><tr><th></th>"
                             + "".join(f"<th style='text-align:right;padding:0 8px'>{a} m</th>" for a in "xyz")
                             + f"<th></th></tr>{body}</table>")

    # ------------------------------------------------------------------ playback
    def add_controls(self, *widgets):
        """Append widgets (sliders of a lesson, a player) under the viewer."""
        self._extra.children = tuple(self._extra.children) + tuple(widgets)

    def player(self, frames, frame_time: float = 1 / 30, description: str = "frame"):
        """A Play button and a frame slider that show ``frames`` (F, J, 3) in turn; added under the view.
        The camera is framed on the whole clip, so the character stays in view while it plays.

        Returns
        -------
        ipywidgets.HBox
            The player; its ``children[1]`` is the frame slider.
        """
        import ipywidgets as w

        frames = np.asarray(frames, dtype=float)
        if frames.ndim != 3 or frames.shape[1:] != (self.skeleton.n_joints, 3):
            raise ValueError(f"frames: expected shape (F, {self.skeleton.n_joints}, 3), got {frames.shape}")
        if not np.all(np.isfinite(frames)):
            raise ValueError("frames contain NaN or inf")
        play = widget(w.Play, value=0, min=0, max=len(frames) - 1, step=1,
                      interval=max(int(frame_time * 1000), 15), description="play")
        slider = widget(w.IntSlider, value=0, min=0, max=len(frames) - 1, description=description)
        w.jslink((play, "value"), (slider, "value"))
        slider.observe(lambda ch: self.set_pose(frames[ch["new"]]), names="value")
        box = widget(w.HBox, [play, slider])
        self.frame_camera(frames)
        self.set_pose(frames[0])
        self.add_controls(box)
        return box
