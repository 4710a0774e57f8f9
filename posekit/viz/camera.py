"""The skeleton viewer's camera: it keeps the pose, and the targets set on it, framed.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb`` with :class:`posekit.viz.viewer.SkeletonViewer`, whose
mixin this is. The scene content sits in a group shifted by minus the framed centre, so the orbit pivot (the
origin, where pythreejs' OrbitControls starts) is the middle of what is shown; framing moves that group and
steps the camera along its current direction until a sphere around the points fits the narrower field of
view. Units: metres (:mod:`posekit.conventions`).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["FramedCamera", "orthographic_matrix", "perspective_matrix", "translation_matrix"]


def perspective_matrix(fov: float, aspect: float, near: float, far: float) -> list:
    """The projection matrix three.js gives a perspective camera (``PerspectiveCamera.updateProjectionMatrix``, zoom
    1, no view offset), 16 floats in its column-major order, with its arithmetic step for step: a camera model that
    holds it has nothing to report back when a page opens. ``fov``: vertical field of view, degrees."""
    top = near * math.tan(math.pi / 180 * 0.5 * fov)
    height = 2 * top
    width = aspect * height
    left = -0.5 * width
    right, bottom = left + width, top - height
    x, y = 2 * near / (right - left), 2 * near / (top - bottom)
    a, b = (right + left) / (right - left), (top + bottom) / (top - bottom)
    c, d = -(far + near) / (far - near), -2 * far * near / (far - near)
    return [x, 0, 0, 0, 0, y, 0, 0, a, b, c, -1, 0, 0, d, 0]


def orthographic_matrix(left: float, right: float, top: float, bottom: float, near: float, far: float) -> list:
    """The projection matrix three.js gives an orthographic camera of this box (``Matrix4.makeOrthographic``, zoom
    1), 16 floats in its column-major order, with its arithmetic step for step (as :func:`perspective_matrix`)."""
    w, h, p = 1.0 / (right - left), 1.0 / (top - bottom), 1.0 / (far - near)
    x, y, z = (right + left) * w, (top + bottom) * h, (far + near) * p
    return [2 * w, 0, 0, 0, 0, 2 * h, 0, 0, 0, 0, -2 * p, 0, -x, -y, -z, 1]


def translation_matrix(position) -> list:
    """The matrix three.js composes for an object at ``position`` (3,) that is neither turned nor scaled
    (column-major)."""
    return [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, *(float(c) for c in position), 1]


class FramedCamera:
    """Camera framing for :class:`~posekit.viz.viewer.SkeletonViewer` (a mixin: the viewer holds ``camera``,
    ``orbit``, ``_world``, ``aspect``, ``pose``, ``targets``, ``look_targets``, ``follow``, ``_held``,
    ``_offset`` and ``_radius``)."""

    VIEW_DIRECTION = np.array([0.35, 0.2, 1.0]) / np.linalg.norm([0.35, 0.2, 1.0])
    """From the pose towards the camera: in front of the character, a little right and above."""
    FOV = 40.0
    """Vertical field of view, degrees."""

    def _camera_position(self, radius):
        """Camera position (scene frame) that fits a sphere of ``radius`` metres around the pivot in the view."""
        half = np.radians(self.FOV) / 2
        half = min(half, np.arctan(np.tan(half) * self.aspect))  # the narrower of the two fields of view
        return [float(c) for c in self.VIEW_DIRECTION * (1.08 * radius / np.sin(half))]

    @staticmethod
    def _frame(pos):
        """Centre and radius (metres) of the box around joint positions ``(..., J, 3)`` and the floor below them."""
        pts = np.asarray(pos, float).reshape(-1, 3)
        lo, hi = pts.min(0), pts.max(0)
        lo[1] = min(lo[1], 0.0)  # keep the floor under the feet in view
        return 0.5 * (lo + hi), float(max(0.5 * np.linalg.norm(hi - lo), 0.6))

    def _shown_points(self):
        """Everything the view should keep in frame: the pose, the targets and the look-at targets, (N, 3)."""
        return np.concatenate([self.pose.reshape(-1, 3), *[np.array(list(d.values())).reshape(-1, 3)
                                                          for d in (self.targets, self.look_targets) if d]])

    def _follow(self):
        """Step the camera back (and re-centre it) when the pose or a target leaves the framed region; never while a
        drag holds a target (the mouse would then move it further per pixel: the drag keeps its scale until the
        mouse is released)."""
        if self._held or getattr(self, "dragging", None) is not None:
            return
        pts = self._shown_points()
        if self.follow and np.linalg.norm(pts - self._offset, axis=1).max() > 1.05 * self._radius:
            self.frame_camera(pts, keep_distance=True)

    def frame_camera(self, poses=None, keep_distance: bool = False):
        """Frame the view on ``poses`` (shape (..., J, 3) or (N, 3) points; default the current pose): the orbit pivot moves
        to their middle and the camera steps back along its current direction until they fit (with
        ``keep_distance``, only further back, never closer)."""
        centre, radius = self._frame(self.pose if poses is None else poses)
        self._offset = centre.copy()
        with self._world.hold_sync():  # one message, with the matrix the browser computes (it reports none back)
            self._world.position = [float(-c) for c in centre]
            self._world.matrix = translation_matrix(self._world.position)
        current = np.asarray(self.camera.position, float) - np.asarray(self.orbit.target, float)
        dist = float(np.linalg.norm(self._camera_position(radius)))
        if keep_distance:
            dist = max(dist, float(np.linalg.norm(current)))
        direction = current / np.linalg.norm(current) if np.linalg.norm(current) > 1e-9 else self.VIEW_DIRECTION
        self.camera.position = [float(c) for c in np.asarray(self.orbit.target, float) + direction * dist]
        self._radius = max(radius, self._radius) if keep_distance else radius

    def reset_view(self):
        """Frame the pose and its targets from the starting direction (in front of the character, a little right
        and above; :attr:`VIEW_DIRECTION`), as the *reset view* button does: the camera looks at the pivot again."""
        centre, radius = self._frame(self._shown_points())
        self.set_camera_state({"offset": centre, "radius": radius,
                               "position": self._camera_position(radius)})

    def camera_state(self) -> dict:
        """Where the camera is: ``position`` (3,) in the scene frame, the framed ``offset`` (3,, world) and
        ``radius`` (metres) — what :meth:`set_camera_state` restores (undo in the studio).

        The orientation is not part of it: OrbitControls always looks at the pivot with Y up, so the position
        determines it, and the kernel's copy of ``camera.quaternion`` is not the browser's (it stays at its
        default until the kernel sets it; restoring that default turned the camera away from the pose)."""
        return {"position": [float(c) for c in self.camera.position],
                "offset": [float(c) for c in self._offset], "radius": float(self._radius)}

    def set_camera_state(self, state: dict):
        """Put the camera where :meth:`camera_state` said, looking at the pivot with Y up."""
        self._offset = np.asarray(state["offset"], float).copy()
        self._radius = float(state["radius"])
        with self._world.hold_sync():
            self._world.position = [float(-c) for c in self._offset]
            self._world.matrix = translation_matrix(self._world.position)
        position = [float(c) for c in state["position"]]
        quaternion = _look_at_origin(np.asarray(position, float))
        with self.camera.hold_sync():
            self.camera.position = position
            self.camera.quaternion = [float(c) for c in quaternion]


def _look_at_origin(eye) -> list:
    """The quaternion (x, y, z, w) three.js' ``Object3D.lookAt`` gives a camera at ``eye`` (3,) looking at the
    origin with Y up."""
    z = eye / np.linalg.norm(eye)
    x = np.cross([0.0, 1.0, 0.0], z)
    x = x / np.linalg.norm(x) if np.linalg.norm(x) > 1e-9 else np.array([1.0, 0.0, 0.0])
    y = np.cross(z, x)
    R = np.stack([x, y, z], axis=1)
    w = np.sqrt(max(1.0 + R[0, 0] + R[1, 1] + R[2, 2], 1e-12)) / 2
    return [float((R[2, 1] - R[1, 2]) / (4 * w)), float((R[0, 2] - R[2, 0]) / (4 * w)),
            float((R[1, 0] - R[0, 1]) / (4 * w)), float(w)]
