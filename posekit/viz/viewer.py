"""An interactive 3D skeleton viewer for Jupyter (pythreejs + ipywidgets).

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``; every later lesson poses through it.
World axes: :mod:`posekit.conventions` (metres, Y up, the character faces +Z).

What it shows: a skeleton (bones as lines, joints as small spheres), an optional *ghost* pose for
comparison, and *target* markers. Updating a pose rewrites the position buffers of the existing
geometries instead of rebuilding the scene, so playback and live solving stay smooth.

Interaction: orbit with the mouse (drag to rotate, wheel to zoom, right-drag to pan);
**double-click** a joint to select it (a single-click picker would also fire at the end of every
orbit drag); the X/Y/Z sliders then move that joint's target, and ``on_target_change`` callbacks
(an IK solver, in later lessons) receive ``(joint_name, position)``.

The viewer knows no solver: lessons connect one through :meth:`SkeletonViewer.on_target_change`.
"""

from __future__ import annotations

import numpy as np

from ..skeleton import Skeleton

__all__ = ["SkeletonViewer", "icosphere"]


def icosphere(subdivisions: int = 1):
    """Unit sphere mesh: vertices (V, 3) and triangle indices (T, 3), from a subdivided icosahedron."""
    t = (1.0 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5),
         (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(p, float) / np.linalg.norm(p) for p in v]
    faces = f
    for _ in range(subdivisions):
        cache, new = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                cache[key] = len(verts) - 1
            return cache[key]

        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    return np.array(verts), np.array(faces, dtype=np.uint32)


class _Spheres:
    """Many spheres in one mesh: moving them rewrites one position buffer."""

    def __init__(self, n, radius, color, opacity=1.0):
        import pythreejs as three

        self.unit, faces = icosphere(1)
        self.radius = radius
        self.n = n
        V = len(self.unit)
        self.faces_per_sphere = len(faces)
        index = (faces[None] + (np.arange(n) * V)[:, None, None]).reshape(-1).astype(np.uint32)
        normals = np.tile(self.unit, (n, 1)).astype(np.float32)
        self.geometry = three.BufferGeometry(attributes={
            "position": three.BufferAttribute(self._positions(np.zeros((n, 3))), normalized=False),
            "normal": three.BufferAttribute(normals, normalized=False),
            "index": three.BufferAttribute(index, normalized=False),
        })
        material = three.MeshLambertMaterial(color=color, transparent=opacity < 1, opacity=opacity)
        self.mesh = three.Mesh(self.geometry, material)

    def _positions(self, centres):
        return (centres[:, None, :] + self.radius * self.unit[None]).reshape(-1, 3).astype(np.float32)

    def set(self, centres):
        self.geometry.attributes["position"].array = self._positions(np.asarray(centres, float))


class _Bones:
    """Bones as line segments parent -> child in one buffer."""

    def __init__(self, skeleton, color, linewidth=3, opacity=1.0):
        import pythreejs as three

        self.pairs = np.array([(skeleton.parents[j], j) for j in range(1, skeleton.n_joints)], dtype=int)
        self.geometry = three.BufferGeometry(attributes={
            "position": three.BufferAttribute(np.zeros((2 * len(self.pairs), 3), np.float32), normalized=False)})
        material = three.LineBasicMaterial(color=color, linewidth=linewidth, transparent=opacity < 1, opacity=opacity)
        self.lines = three.LineSegments(self.geometry, material)

    def set(self, pos):
        self.geometry.attributes["position"].array = np.asarray(pos, np.float32)[self.pairs.reshape(-1)]


class SkeletonViewer:
    """A pythreejs scene of one skeleton with a ghost, targets, picking and sliders.

    Parameters
    ----------
    skeleton : Skeleton
    pose : ndarray, shape (J, 3), metres, optional
        Global joint positions; default the rest pose.
    ghost : ndarray, shape (J, 3), optional
        A second pose drawn translucent (e.g. the ground truth, or another solver).
    targets : dict, optional
        Joint name -> (3,) target position, drawn as red spheres.
    width, height : int
        Canvas size in pixels.
    joint_radius : float
        Sphere radius in metres.
    controls : bool
        Show the joint selector, X/Y/Z target sliders and the status line.

    Attributes
    ----------
    widget : ipywidgets.VBox
        What to display (the viewer also displays itself when it is a cell's last value).
    selected : str or None
        Name of the selected joint.
    pose : ndarray, shape (J, 3)
    targets : dict
    """

    SLIDER_STEP = 0.005
    """Target slider resolution, metres."""

    def __init__(self, skeleton: Skeleton, pose=None, ghost=None, targets=None, width: int = 560,
                 height: int = 420, joint_radius: float = 0.025, controls: bool = True,
                 background: str = "#f7f7f2", floor: bool = True):
        import ipywidgets as w
        import pythreejs as three

        from ..kinematics import rest_pose

        self.skeleton = skeleton
        J = skeleton.n_joints
        self.pose = np.array(rest_pose(skeleton) if pose is None else pose, dtype=float)
        self._check(self.pose, "pose")
        self.targets, self.look_targets = {}, {}
        self.selected = None
        self._select_callbacks, self._target_callbacks = [], []
        self._syncing = False

        self._bones = _Bones(skeleton, "#1f4e79", linewidth=3)
        self._joints = _Spheres(J, joint_radius, "#2e86c1")
        self._ghost_bones = _Bones(skeleton, "#999999", linewidth=2, opacity=0.6)
        self._ghost_joints = _Spheres(J, joint_radius * 0.8, "#aaaaaa", opacity=0.5)
        self._selected_marker = _Spheres(1, joint_radius * 1.6, "#f1c40f", opacity=0.6)
        self._ghost_group = three.Group(children=[self._ghost_bones.lines, self._ghost_joints.mesh])
        self._target_group = three.Group()
        self._targets_mesh, self._target_key = None, None
        self._selected_marker.mesh.visible = False

        # The scene content sits in a group shifted by -centre, so the orbit pivot (the origin,
        # where OrbitControls starts) is the middle of the pose.
        centre, extent = self._frame(self.pose)
        self._offset = centre.copy()
        self.camera = three.PerspectiveCamera(position=self._camera_position(extent), fov=40,
                                              aspect=width / height, near=0.01, far=100)
        content = [self._bones.lines, self._joints.mesh, self._ghost_group, self._target_group,
                   self._selected_marker.mesh]
        if floor:
            content.append(three.GridHelper(size=6, divisions=24, colorCenterLine="#888888", colorGrid="#cccccc"))
        self._world = three.Group(children=content, position=[float(-c) for c in centre])
        self.scene = three.Scene(children=[self._world, self.camera,
                                           three.AmbientLight(color="#ffffff", intensity=0.6),
                                           three.DirectionalLight(color="#ffffff", position=[3, 5, 4], intensity=0.7)],
                                 background=background)
        self.orbit = three.OrbitControls(controlling=self.camera)
        self.picker = three.Picker(controlling=self._joints.mesh, event="dblclick")
        self.picker.observe(self._on_pick, names=["point"])
        self.renderer = three.Renderer(camera=self.camera, scene=self.scene, controls=[self.orbit, self.picker],
                                       width=width, height=height, antialias=True)

        self.status = w.HTML(value="double-click a joint to select it")
        # "" stands for no selection: a Dropdown whose value is None shows a blank box
        self.joint_select = w.Dropdown(options=[("(none)", "")] + [(n, n) for n in skeleton.names],
                                       value="", description="joint", layout=w.Layout(width="220px"))
        self.joint_select.observe(lambda ch: self.select(ch["new"] or None), names="value")
        span = max(extent, 1.0)
        step = self.SLIDER_STEP
        # limits on the step grid, so that the browser's snapping to it does not move a value
        lo = np.floor((self.pose.min(0) - span) / step) * step
        hi = np.ceil((self.pose.max(0) + span) / step) * step
        self.sliders = [w.FloatSlider(value=float(lo[k]), min=float(lo[k]), max=float(hi[k]), step=step,
                                      description=f"target {a}", continuous_update=True, readout_format=".3f",
                                      disabled=True, readout=False, layout=w.Layout(width="320px"))
                        for k, a in enumerate("xyz")]
        self._synced = None
        for s in self.sliders:
            s.observe(self._on_slider, names="value")
        self.controls = w.VBox([w.HBox([self.joint_select, self.status]), *self.sliders])
        self.controls.layout.display = None if controls else "none"
        self._extra = w.VBox([])
        self.widget = w.VBox([self.renderer, self.controls, self._extra])

        self.set_pose(self.pose)
        self.set_ghost(ghost)
        self.set_targets(targets or {})

    # ------------------------------------------------------------------ helpers
    def _check(self, pos, what):
        pos = np.asarray(pos, dtype=float)
        if pos.shape != (self.skeleton.n_joints, 3):
            raise ValueError(f"{what}: expected shape ({self.skeleton.n_joints}, 3), got {pos.shape}")
        if not np.all(np.isfinite(pos)):
            raise ValueError(f"{what} contains NaN or inf")
        return pos

    @staticmethod
    def _camera_position(extent):
        return [0.7 * extent, 0.3 * extent, 1.9 * extent]

    @staticmethod
    def _frame(pos):
        lo, hi = pos.min(0), pos.max(0)
        centre = 0.5 * (lo + hi)
        centre[1] = 0.5 * hi[1]  # look at half the height above the floor
        return centre, float(max(np.ptp(pos, axis=0).max(), 1.0))

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)

    # ------------------------------------------------------------------ drawing
    def set_pose(self, global_pos):
        """Show a new pose: global joint positions, shape (J, 3), metres."""
        self.pose = self._check(global_pos, "pose").copy()
        self._bones.set(self.pose)
        self._joints.set(self.pose)
        self._draw_rays()
        if self.selected is not None:
            self._selected_marker.set(self.pose[[self.skeleton.index(self.selected)]])
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

    def set_targets(self, targets: dict, look_at: dict | None = None):
        """Replace the target markers: joint name -> (3,) position in metres (red spheres; the sliders
        move these). ``look_at``: joint name -> (3,) point the joint should face, drawn as an orange
        sphere with a ray from the joint (a joint may appear in both)."""
        new = self._points(targets, "target")
        looks = self._points(look_at or {}, "look-at target")
        red = {n: p for n, p in new.items() if not (n in looks and np.array_equal(looks[n], p))}
        key = (tuple(red), tuple(looks))
        rebuild = key != self._target_key or self._targets_mesh is None
        self.targets, self.look_targets, self._target_key = new, looks, key
        if rebuild:
            import pythreejs as three

            self._targets_mesh = _Spheres(max(len(red), 1), self._joints.radius * 1.3, "#e74c3c")
            self._targets_mesh.mesh.visible = bool(red)
            self._look_mesh = _Spheres(max(len(looks), 1), self._joints.radius * 1.3, "#e67e22")
            self._look_mesh.mesh.visible = bool(looks)
            self._rays = three.LineSegments(
                three.BufferGeometry(attributes={"position": three.BufferAttribute(
                    np.zeros((2 * max(len(looks), 1), 3), np.float32), normalized=False)}),
                three.LineBasicMaterial(color="#e67e22", linewidth=1))
            self._rays.visible = bool(looks)
            self._target_group.children = [self._targets_mesh.mesh, self._look_mesh.mesh, self._rays]
        if red:
            self._targets_mesh.set(np.array(list(red.values())))
        if looks:
            self._look_mesh.set(np.array(list(looks.values())))
        self._draw_rays()
        self._sync_sliders()

    def _draw_rays(self):
        looks = self.look_targets
        if looks:
            joints = self.pose[[self.skeleton.index(n) for n in looks]]
            seg = np.stack([joints, np.array(list(looks.values()))], axis=1).reshape(-1, 3)
            self._rays.geometry.attributes["position"].array = seg.astype(np.float32)

    def frame_camera(self):
        """Re-centre the view on the current pose."""
        centre, extent = self._frame(self.pose)
        self._offset = centre.copy()
        self._world.position = [float(-c) for c in centre]
        self.camera.position = self._camera_position(extent)

    # ------------------------------------------------------------------ selection and targets
    def select(self, joint):
        """Select a joint by name, role or index (None clears the selection)."""
        name = None if joint is None else self.skeleton.names[self.skeleton.index(joint)]
        self.selected = name
        if self.joint_select.value != (name or ""):
            self.joint_select.value = name or ""
        self._selected_marker.mesh.visible = name is not None
        if name is not None:
            self._selected_marker.set(self.pose[[self.skeleton.index(name)]])
        self._sync_sliders()
        self._update_status()
        for cb in self._select_callbacks:
            cb(name)

    def _on_pick(self, change):
        p = np.asarray(change["new"], dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            return
        p = p + self._offset  # picked point is in scene coordinates
        j = int(np.argmin(np.linalg.norm(self.pose - p, axis=1)))
        self.select(self.skeleton.names[j])

    def _sync_sliders(self):
        """Show the selected joint's target (or, without one, the joint) on the sliders; with no
        selection the sliders are disabled and show no number."""
        active = self.selected is not None
        for s in self.sliders:
            s.disabled, s.readout = not active, active
        if not active:
            self._synced = None
            return
        p = self.targets.get(self.selected, self.pose[self.skeleton.index(self.selected)])
        self._syncing = True
        try:
            for s, v in zip(self.sliders, p):
                s.value = float(np.clip(v, s.min, s.max))
        finally:
            self._syncing = False
        self._synced = np.array([s.value for s in self.sliders])

    def _on_slider(self, change):
        if self._syncing or self.selected is None:
            return
        values = np.array([s.value for s in self.sliders])
        # the browser snaps a synced value to the slider's step grid and sends it back: that is
        # not a move, and must not create a target a fraction of a step from the joint
        if self._synced is not None and np.all(np.abs(values - self._synced) <= 0.5 * self.SLIDER_STEP + 1e-9):
            return
        self.move_target(self.selected, values)

    def move_target(self, joint, position):
        """Set one joint's target (creating it if needed) and notify ``on_target_change`` callbacks."""
        name = self.skeleton.names[self.skeleton.index(joint)]
        targets = dict(self.targets)
        targets[name] = np.asarray(position, dtype=float).reshape(3)
        self.set_targets(targets, self.look_targets)
        self._update_status()
        for cb in self._target_callbacks:
            cb(name, self.targets[name].copy())

    def on_select(self, callback):
        """Call ``callback(joint_name or None)`` whenever the selection changes."""
        self._select_callbacks.append(callback)

    def on_target_change(self, callback):
        """Call ``callback(joint_name, position)`` whenever a target moves (sliders or code)."""
        self._target_callbacks.append(callback)

    def _update_status(self):
        if self.selected is None:
            self.status.value = "double-click a joint to select it"
            return
        p = self.pose[self.skeleton.index(self.selected)]
        text = f"<b>{self.selected}</b> at ({p[0]:+.3f}, {p[1]:+.3f}, {p[2]:+.3f}) m"
        if self.selected in self.targets:
            t = self.targets[self.selected]
            text += f", target {np.linalg.norm(t - p) * 100:.1f} cm away"
        self.status.value = text

    # ------------------------------------------------------------------ playback
    def add_controls(self, *widgets):
        """Append widgets (sliders of a lesson, a player) under the viewer."""
        self._extra.children = tuple(self._extra.children) + tuple(widgets)

    def player(self, frames, frame_time: float = 1 / 30, description: str = "frame"):
        """A Play button and a frame slider that show ``frames`` (F, J, 3) in turn; added under the view.

        Returns
        -------
        ipywidgets.HBox
            The player; its ``children[1]`` is the frame slider.
        """
        import ipywidgets as w

        frames = np.asarray(frames, dtype=float)
        if frames.ndim != 3 or frames.shape[1:] != (self.skeleton.n_joints, 3):
            raise ValueError(f"frames: expected shape (F, {self.skeleton.n_joints}, 3), got {frames.shape}")
        play = w.Play(value=0, min=0, max=len(frames) - 1, step=1, interval=max(int(frame_time * 1000), 15),
                      description="play")
        slider = w.IntSlider(value=0, min=0, max=len(frames) - 1, description=description)
        w.jslink((play, "value"), (slider, "value"))
        slider.observe(lambda ch: self.set_pose(frames[ch["new"]]), names="value")
        box = w.HBox([play, slider])
        self.set_pose(frames[0])
        self.add_controls(box)
        return box
