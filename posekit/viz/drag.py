"""Dragging targets with the mouse in a pythreejs view: a ray from the camera, a plane facing it.

Introduced in ``notebooks/06_posing_studio.ipynb``; a part of :class:`~posekit.viz.SkeletonViewer` (it
inherits :class:`DragTargets`). With the viewer's **drag in 3D** toggle on, orbiting stops and three
pickers report mouse events to the kernel:

* *mouse down* on a joint or a marker (:meth:`DragTargets.grab`): that target is held, and a drag plane is
  fixed through it, facing the camera;
* *mouse move*: the browser reports where the mouse ray meets a large invisible sphere around the scene;
  the kernel draws the line from the camera through that point and moves the target to where it crosses
  the drag plane (:func:`drag_point`, :meth:`DragTargets.drag_to`);
* *mouse up* — wherever it happens: the target is let go (:meth:`DragTargets._let_go`);
* *Escape* while the drag is held: the target goes back to where it started (:meth:`DragTargets.cancel_drag`).

The pickers see the mouse on the canvas only: a button let go over another part of the page, or outside the
window, never reaches the *mouse up* picker, and the drag went on with no button down (hovering moved the target).
So the view's :class:`~posekit.viz.page_watch.PageWatch` listens on the whole page and tells the kernel of the first
``pointerup`` or ``pointercancel`` anywhere, of the window losing focus, and of a mouse moving with no button down,
once a drag may be held (the kernel marks the switch with :data:`DRAG_HELD_CLASS` while it holds one); the canvas'
*mouse up* picker stays, for a page without that script. Letting go twice is harmless.

So the target follows the cursor in the plane of the screen, at the depth it had, and the arithmetic runs
in the kernel: the browser only reports points. Units: metres; positions in the world frame.
"""

from __future__ import annotations

import numpy as np

from .meshes import icosphere
from .shared import constant_attribute, constant_geometry, material, widget

__all__ = ["drag_point", "DragTargets", "DRAG_ON_CLASS", "DRAG_HELD_CLASS"]

DRAG_ON_CLASS = "posekit-drag-on"
"""The CSS class the kernel puts on the *drag in 3D* switch once it has stopped orbiting (and takes off once it
orbits again): a page, or a test driving one, presses in the view after it shows."""

DRAG_HELD_CLASS = "posekit-drag-held"
"""The CSS class the kernel puts on the *drag in 3D* switch while it holds a drag (from the press on a joint until
the release): a test reads the kernel's drag state from the page by it."""

SURFACE_RADIUS = 40.0
"""Radius (metres) of the invisible sphere every mouse ray from inside the scene meets."""


def drag_point(camera, through, plane_point, plane_normal):
    """Where the ray from ``camera`` through ``through`` meets a plane (all (3,) arrays, one frame).

    The browser reports where the mouse ray hits a large sphere around the scene; the ray is the line
    from the camera through that point, and the dragged target goes where it crosses the drag plane.
    Returns None when the ray runs parallel to the plane or meets it behind the camera.
    """
    camera, through = np.asarray(camera, float), np.asarray(through, float)
    n = np.asarray(plane_normal, float)
    d = through - camera
    denom = float(d @ n)
    if abs(denom) < 1e-9 * max(np.linalg.norm(d), 1e-12):
        return None
    t = float((np.asarray(plane_point, float) - camera) @ n) / denom
    return None if t <= 0 else camera + t * d


class DragTargets:
    """The dragging half of :class:`~posekit.viz.SkeletonViewer` (see the module docstring).

    Expects of the viewer: ``camera``, ``orbit``, ``_offset`` (world position of the scene origin),
    ``_grabbable`` (the group of joints and markers), ``pose``, ``targets``, ``look_targets``,
    ``_joint_radius``, ``select``, ``move_target``, ``move_look_target``, ``_look_callbacks``, ``page_watch`` (a
    :class:`~posekit.viz.page_watch.PageWatch`, made with the controls, which calls :meth:`_let_go` on a release).

    Attributes
    ----------
    drag_mode : ipywidgets.ToggleButton
    dragging : str or None
        The joint whose target the mouse holds.
    dragging_look : bool
        Whether it holds the joint's look-at marker (orange) rather than its target.
    """

    def _init_drag(self):
        self.dragging, self.dragging_look = None, False
        self._drag_plane = None
        self._drag_start = None  # (joint, kind, point or None, the source's undo position or None) at the grab

    def _drag_surface(self):
        """The invisible sphere (seen from inside) that every mouse ray meets."""
        import pythreejs as three

        unit, faces = icosphere(2)
        # one geometry and one material model for the sphere of every view (posekit.viz.shared)
        self._drag_sphere = three.Mesh(
            constant_geometry({"position": constant_attribute((SURFACE_RADIUS * unit).astype(np.float32)),
                               "index": constant_attribute(faces.reshape(-1).astype(np.uint32))}),
            # never drawn (a material that is not visible) but still hit by the pickers' rays: three.js tests only
            # the object's own visibility when it casts a ray, the material's when it draws
            material(three.MeshBasicMaterial, color="#ffffff", side="BackSide", visible=False))
        return self._drag_sphere

    def _drag_pickers(self):
        """Mouse down on the joints and markers, mouse move and mouse up on the sphere."""
        import pythreejs as three

        self._drag_made = True
        self._grab = three.Picker(controlling=self._grabbable, event="mousedown")
        self._grab.observe(self._on_grab, names=["point"])
        self._move = three.Picker(controlling=self._drag_sphere, event="mousemove")
        self._move.observe(self._on_drag, names=["point"])
        self._release = three.Picker(controlling=self._drag_sphere, event="mouseup")
        self._release.observe(self._on_release, names=["point"])
        return [self._grab, self._move, self._release]

    def _drag_toggle(self):
        import ipywidgets as w

        toggle = widget(w.ToggleButton, value=False, description="drag in 3D", icon="hand-pointer-o",
                        tooltip="on: press on a joint or a target and move the mouse to drag the target "
                                "(orbiting stops); off: the mouse orbits")
        toggle.observe(self._on_drag_mode, names="value")
        return toggle

    def _on_drag_mode(self, change):
        if change["new"] and not getattr(self, "_drag_made", False):  # a view without controls: made when needed
            self.renderer.controls = [*self.renderer.controls, *self._drag_pickers()]
        self.orbit.enabled = not change["new"]
        self.page_watch.armed = bool(change["new"])  # a press on the canvas may start a drag: the page watches
        # the page learns that the kernel has switched orbiting (a class on the switch, sent after ``enabled``): a
        # press before it orbits the camera instead of grabbing a joint
        (self.drag_mode.add_class if change["new"] else self.drag_mode.remove_class)(DRAG_ON_CLASS)
        self._let_go()

    def _let_go(self):
        """End a drag (the page's release, the canvas' *mouse up*, the switch turned off; again: nothing): the
        sliders show where the target went (they wait while the mouse is down)."""
        held, self.dragging = self.dragging, None
        if held is not None:
            self._show_held(False)
            if hasattr(self.source, "end_drag"):
                self.source.end_drag()  # a session's next change is a step of its own
        if self._sliders_due:
            self._sync_sliders()
        if held is not None:
            self._follow()  # the camera waited for the mouse to be released

    def grab(self, point):
        """Start dragging at ``point`` (world frame, metres): the target marker it is on (within two
        marker radii), else the nearest joint's target (created on the first move)."""
        p = np.asarray(point, float).reshape(3)
        looks = self.look_targets
        red = [(float(np.linalg.norm(q - p)), n, False) for n, q in self.targets.items()]
        orange = [(float(np.linalg.norm(q - p)), n, True) for n, q in looks.items()]
        near = [c for c in red + orange if c[0] <= 2.6 * self._joint_radius]
        # on a marker: that target (an orange one: the point the joint looks at); else the nearest joint's
        _, name, self.dragging_look = min(near) if near else (0.0, self._nearest_joint(p), False)
        if self.skeleton.index(name) not in self.selectable:  # a joint this view does not offer: nothing to drag
            self._refuse(name)
            return
        self.dragging = name
        self._show_held(True)
        if hasattr(self.source, "begin_drag"):
            self.source.begin_drag()  # a session makes the whole drag one undo step, however slow its solves
        if self.selected != name:
            self.select(name)
        had = self.look_targets.get(name) if self.dragging_look else self.targets.get(name)
        anchor = np.array(had if had is not None else self.pose[self.skeleton.index(name)], float)
        if self.dragging_look and not self._moves_look():
            # a lone view's orange marker: the drag moves the joint's position target, from the marker's plane
            self.dragging_look, had = False, self.targets.get(name)
        self._drag_start = ("look_at" if self.dragging_look else "position",
                            None if had is None else np.array(had, float), getattr(self.source, "position", None))
        camera = np.asarray(self.camera.position, float) + self._offset  # world frame
        self._drag_plane = (anchor.copy(), (camera - anchor) / max(np.linalg.norm(camera - anchor), 1e-9))

    def _moves_look(self) -> bool:
        """Whether a drag on an orange marker moves the point the joint looks at: when a session holds the markers
        (:meth:`~posekit.viz.SkeletonViewer.attach`) or someone listens to look-at moves
        (``on_look_target_change``). A lone view's (lesson 00's) drags the joint's position target, as its
        :meth:`~posekit.viz.SkeletonViewer.move_look_target` tells its target listeners."""
        return bool(self._look_callbacks) or hasattr(self.source, "revert_to")

    def _show_held(self, held: bool):
        """Tell the page whether a drag is held: its watcher then ends it on any release, and the switch carries
        :data:`DRAG_HELD_CLASS` meanwhile."""
        if not self._controls_made:
            return
        self.page_watch.holding = held
        (self.drag_mode.add_class if held else self.drag_mode.remove_class)(DRAG_HELD_CLASS)

    def drag_to(self, through):
        """Move the dragged target to where the mouse ray (camera -> ``through``, world frame) meets the
        drag plane (through the grabbed point, facing the camera); notifies ``on_target_change``."""
        if self.dragging is None:
            return
        camera = np.asarray(self.camera.position, float) + self._offset
        p = drag_point(camera, through, *self._drag_plane)
        if p is not None and np.linalg.norm(p - self._drag_plane[0]) < 10.0:  # not off towards the horizon
            if self.dragging_look:
                self.move_look_target(self.dragging, p)
            else:
                self.move_target(self.dragging, p)

    def cancel_drag(self):
        """Escape during a drag: the target goes back to where it was at the grab (a session steps back to where it
        was, :meth:`~posekit.studio.PosingSession.revert_to`: a target the drag created goes again), and the drag
        ends."""
        if self.dragging is None:
            return
        name, (kind, point, position) = self.dragging, self._drag_start
        if position is not None:
            self.source.revert_to(position)
            self.show()
        elif point is not None:
            (self.move_look_target if kind == "look_at" else self.move_target)(name, point)
        else:  # a lone view's target made by this drag
            self.source.positions.pop(name, None)
            self.show()
        self._let_go()

    def _on_grab(self, change):
        if self.drag_mode.value and self._grab.distance is not None:
            self.grab(np.asarray(change["new"], float) + self._offset)

    def _on_drag(self, change):
        if self.drag_mode.value and self.dragging is not None and self._move.distance is not None:
            self.drag_to(np.asarray(change["new"], float) + self._offset)

    def _on_release(self, change):
        self._let_go()
