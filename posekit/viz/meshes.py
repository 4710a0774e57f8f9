"""The viewer's geometry: many spheres or many bone cylinders in one pythreejs mesh each, and a view's whole
figure (bones, joints, target markers, rays, triads) drawn from one shared position array.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb`` (through :class:`~posekit.viz.SkeletonViewer`).
Every shape of a kind lives in one buffer, so moving a pose rewrites position arrays instead of rebuilding the
scene: playback and live solving stay smooth. :class:`Figure` goes further: its parts are separate meshes (each
its own picking and visibility) indexing **one** position array, so a solved pose with its targets costs one
message to the browser (and one acknowledgement back), not one per part. Bones are flat-shaded (three.js derives
each face's normal on the graphics card), so a moved pose sends no normals; every other part is coloured by vertex
colours, so a view compiles three shader programs (bones, spheres, lines) whatever it shows. Every attribute and
geometry is made as the browser's three.js would make it (:mod:`posekit.viz.buffers`), so a page that opens
reports nothing back to the kernel for them. The materials and the buffers nothing changes (triangle indices, normals,
a ghost's colours) are one model for every view of a page (:mod:`posekit.viz.shared`): the studio's four views open
with fewer than half the models they had. Units: metres; axes: :mod:`posekit.conventions`.
"""

from __future__ import annotations

import numpy as np

from .buffers import attribute, geometry
from .shared import constant_attribute, material as shared_material, release

__all__ = ["icosphere", "Spheres", "Bones", "Figure", "SIDE_COLOURS", "PICK_BOUND", "attribute", "geometry"]

PICK_BOUND = 100.0
"""Half-size (metres) of a box two unused vertices of every pickable mesh span. three.js tests a mouse ray
against a mesh's bounding sphere before its triangles and computes that sphere once, at the first render;
spheres that later move outside it (a clip played on, a hand raised, a marker created at the origin and
then placed) could no longer be picked. With the two far corners in the position buffer (no triangle
uses them, so nothing is drawn) the sphere holds every place a joint or marker can go."""

SIDE_COLOURS = {1: "#1a5276", -1: "#922b21", 0: "#4d5656"}
"""Bone colours by side of the body (:meth:`posekit.skeleton.Skeleton.sides`): left dark blue, right dark
red, central grey."""


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


TRIAD_STRANDS = ((0.0, 0.0), (0.16, 0.0), (-0.16, 0.0), (0.0, 0.16), (0.0, -0.16))
"""Each axis of a rotation triad is drawn as these parallel lines (offsets along the triad's other two axes, in
joint radii; the centre line first): WebGL draws every line one pixel wide, so one line per axis was hard to see."""


def _hex(colour: str) -> np.ndarray:
    colour = colour.lstrip("#")
    return np.array([int(colour[k:k + 2], 16) / 255 for k in (0, 2, 4)], dtype=np.float32)


def _sphere_vertices(unit, centres, radius):
    """Vertices (n V, 3) of spheres of the unit mesh ``unit`` (V, 3) at ``centres`` (n, 3) with radii ``radius``
    (scalar or (n,)), metres."""
    r = np.broadcast_to(np.asarray(radius, float), (len(centres),))
    return (centres[:, None, :] + r[:, None, None] * unit[None]).reshape(-1, 3)


class Spheres:
    """``n`` spheres of one radius and colour in one mesh; :meth:`set` moves them (centres (n, 3), metres)."""

    def __init__(self, n, radius, color, opacity=1.0):
        import pythreejs as three

        self.unit, faces = icosphere(1)
        self.radius = radius
        self.n = n
        V = len(self.unit)
        index = (faces[None] + (np.arange(n) * V)[:, None, None]).reshape(-1).astype(np.uint32)
        normals = np.concatenate([np.tile(self.unit, (n, 1)), np.zeros((2, 3))]).astype(np.float32)
        colours = np.repeat(_hex(color)[None], n * V + 2, axis=0)
        self.geometry = geometry(attributes={
            "position": attribute(self._positions(np.zeros((n, 3)))),
            "normal": constant_attribute(normals),
            "color": constant_attribute(colours),
            "index": constant_attribute(index),
        })
        # vertex colours, as the figure's joints and markers: one shader program for every sphere of a view, and one
        # material model for the spheres of every view of this opacity (shared.material)
        material = shared_material(three.MeshLambertMaterial, vertexColors="VertexColors", transparent=opacity < 1,
                                   opacity=opacity)
        self.mesh = three.Mesh(self.geometry, material)

    def _positions(self, centres):
        """Vertex positions (n V + 2, 3): each sphere's, then the two far corners (:data:`PICK_BOUND`)."""
        verts = _sphere_vertices(self.unit, centres, self.radius)
        return np.concatenate([verts, [[-PICK_BOUND] * 3, [PICK_BOUND] * 3]]).astype(np.float32)

    def set(self, centres):
        self.geometry.attributes["position"].array = self._positions(np.asarray(centres, float))


class _Tubes:
    """Every bone (parent -> child) of a skeleton as an open cylinder of ``sides`` faces: the arithmetic of
    :class:`Bones` and :class:`Figure` (vertices, triangles, colours), no widget."""

    def __init__(self, skeleton, radius: float, colour: str | None = None, sides: int = 8):
        self.pairs = np.array([(skeleton.parents[j], j) for j in range(1, skeleton.n_joints)], dtype=int)
        self.radius, self.sides = float(radius), int(sides)
        angle = 2 * np.pi * np.arange(sides) / sides
        self._cos, self._sin = np.cos(angle)[:, None], np.sin(angle)[:, None]
        B, S = len(self.pairs), self.sides
        # per bone: ring at the parent (vertices 0..S-1), ring at the child (S..2S-1); two triangles per side
        k, k1 = np.arange(S), (np.arange(S) + 1) % S
        quad = np.stack([np.stack([k, k1, S + k], -1), np.stack([k1, S + k1, S + k], -1)], 1).reshape(-1, 3)
        self.faces = (quad[None] + (np.arange(B) * 2 * S)[:, None, None]).reshape(-1, 3)
        side = skeleton.sides()[self.pairs[:, 1]]
        rgb = np.array([_hex(colour or SIDE_COLOURS[int(s)]) for s in side], dtype=np.float32)
        self.colours = np.repeat(rgb, 2 * S, axis=0)
        self.n_vertices = 2 * S * B

    def vertices(self, pos):
        """Vertices (2 S B, 3) of the bones on global joint positions ``pos`` (J, 3), metres."""
        a, b = pos[self.pairs[:, 0]], pos[self.pairs[:, 1]]
        d = b - a
        length = np.linalg.norm(d, axis=-1, keepdims=True)
        axis = np.where(length > 1e-9, d / np.maximum(length, 1e-12), np.array([0.0, 1.0, 0.0]))
        # a vector not parallel to the axis, then two unit vectors spanning the cross-section
        helper = np.where(np.abs(axis[:, 1:2]) < 0.9, np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0]))
        u = np.cross(axis, helper)
        u /= np.linalg.norm(u, axis=-1, keepdims=True)
        v = np.cross(axis, u)
        ring = self._cos[None] * u[:, None] + self._sin[None] * v[:, None]  # (B, S, 3) outward
        verts = np.concatenate([a[:, None] + self.radius * ring, b[:, None] + self.radius * ring], axis=1)
        return verts.reshape(-1, 3)


def _bone_material(opacity: float = 1.0):
    """Flat shading: each face's normal comes from its vertices on the graphics card, so moving a pose sends
    positions only (an 8-sided cylinder reads the same faceted or smooth at this size); no shine. One material model
    for the bones of every view of this opacity (:func:`~posekit.viz.shared.material`)."""
    import pythreejs as three

    return shared_material(three.MeshPhongMaterial, vertexColors="VertexColors", flatShading=True, shininess=0,
                           specular="#000000", transparent=opacity < 1, opacity=opacity)


class Bones:
    """Every bone (parent -> child) as an open cylinder of ``sides`` faces, coloured by the child's side of
    the body (:data:`SIDE_COLOURS`), in one mesh. With joint spheres of at least the same radius at both
    ends the bones read as capsules.

    Parameters
    ----------
    skeleton : Skeleton
    radius : float, metres
    opacity : float
    colour : str, optional
        One colour for every bone (e.g. a grey ghost) instead of the side colours.
    sides : int
    """

    def __init__(self, skeleton, radius: float = 0.018, opacity: float = 1.0, colour: str | None = None,
                 sides: int = 8):
        import pythreejs as three

        self._tubes = _Tubes(skeleton, radius, colour, sides)
        self.pairs, self.radius, self.sides = self._tubes.pairs, self._tubes.radius, self._tubes.sides
        self.geometry = geometry(attributes={
            "position": attribute(self._buffers(np.zeros((skeleton.n_joints, 3)))),
            "color": constant_attribute(self._tubes.colours),
            "index": constant_attribute(self._tubes.faces.reshape(-1).astype(np.uint32)),
        })
        self.mesh = three.Mesh(self.geometry, _bone_material(opacity))

    def _buffers(self, pos):
        return self._tubes.vertices(pos).astype(np.float32)

    def set(self, pos):
        """Place the bones on global joint positions, shape (J, 3), metres."""
        self.geometry.attributes["position"].array = self._buffers(np.asarray(pos, float))


class Figure:
    """One view's skeleton and target markers, every part drawn from one position array.

    Parts, in the order of the array's rows: the bones (:class:`Bones`' cylinders, side colours), the joints
    (spheres; one at a time can be highlighted: larger, in ``highlight``), the position targets and the look-at
    targets (spheres of ``marker_radius``), the look-at rays (joint -> point), the rotation triads (three axes of
    ``triad_length`` per target: x red, y green, z blue), then the two :data:`PICK_BOUND` corners. Each part is
    a mesh (or line segments) of its own, with its own index into the shared rows, so picking and visibility stay
    per part; the normal and colour arrays are shared as well (every part is coloured by its rows of the colour
    array, so the spheres share one material and the lines another, with every other view's) and sent again only
    when the number of targets of a kind changes (:meth:`layout`) or the highlight moves. The normals and each part's
    triangle indices depend only on the skeleton and the counts: views that show as many markers hold the same
    models (:func:`~posekit.viz.shared.constant_attribute`); the positions and colours are the view's own.
    :meth:`draw` writes every part and sends the positions once.

    Attributes
    ----------
    bones, joints, targets, looks : pythreejs.Mesh
    rays, triads : pythreejs.LineSegments
    counts : tuple of int
        Position targets, look-at targets and rotation targets the layout holds.
    """

    HIGHLIGHT_SCALE = 1.6
    """Radius of the highlighted joint, times :attr:`joint_radius`."""

    def __init__(self, skeleton, joint_radius: float, bone_radius: float, joint_colour: str, highlight: str,
                 target_colour: str, look_colour: str, marker_radius: float, triad_length: float):
        import pythreejs as three

        self.n_joints = skeleton.n_joints
        self.joint_radius, self.marker_radius, self.triad_length = joint_radius, marker_radius, triad_length
        self._tubes = _Tubes(skeleton, bone_radius)
        self.unit, self._sphere_faces = icosphere(1)
        self._joint_rgb, self._highlight_rgb = _hex(joint_colour), _hex(highlight)
        self.highlighted = None
        self._marker_rgb = {"targets": _hex(target_colour), "looks": _hex(look_colour), "rays": _hex(look_colour)}
        # every part takes its colours from the shared colour array: the view's meshes and lines need only three
        # shader programs (flat-shaded bones, lit spheres, lines), each compiled once per view when it first draws;
        # and every view holds the same three material models (shared.material): joints and markers, selected or
        # not, one sphere material; the selected joint is coloured by its rows of the colour array (highlight)
        spheres = shared_material(three.MeshLambertMaterial, vertexColors="VertexColors")
        lines = shared_material(three.LineBasicMaterial, vertexColors="VertexColors", linewidth=2)
        self._materials = [_bone_material(), spheres, spheres, spheres, lines, lines]
        self.bones = self.joints = self.targets = self.looks = self.rays = self.triads = None
        self.counts = None
        self._shared = {}
        self.layout(0, 0, 0)

    # ---------------------------------------------------------------- layout
    def _spheres(self, n, first):
        """Triangle indices (n F, 3) of ``n`` spheres whose vertices start at row ``first``."""
        V = len(self.unit)
        return (self._sphere_faces[None] + (first + np.arange(n) * V)[:, None, None]).reshape(-1, 3)

    def layout(self, n_targets: int, n_looks: int, n_rotations: int):
        """Make room for that many position, look-at and rotation targets: new shared arrays and an index per
        part (done only when a count changes: a new marker, not a moved one)."""
        import pythreejs as three

        counts = (int(n_targets), int(n_looks), int(n_rotations))
        if counts == self.counts:
            return
        T, L, R = counts
        V, J = len(self.unit), self.n_joints
        sizes = {"bones": self._tubes.n_vertices, "joints": J * V, "targets": T * V, "looks": L * V,
                 "rays": 2 * L, "triads": 6 * R * len(TRIAD_STRANDS), "corners": 2}
        rows, start = {}, 0
        for name, n in sizes.items():
            rows[name], start = slice(start, start + n), start + n
        self._rows, self.counts = rows, counts
        n = start
        before = getattr(self, "_positions", None)
        self._positions = np.zeros((n, 3))
        if before is not None:  # bones and joints keep their rows: the figure does not blink to the origin
            self._positions[:rows["targets"].start] = before[:rows["targets"].start]
        self._positions[rows["corners"]] = [[-PICK_BOUND] * 3, [PICK_BOUND] * 3]
        normals = np.zeros((n, 3), np.float32)
        for part, k in (("joints", J), ("targets", T), ("looks", L)):
            normals[rows[part]] = np.tile(self.unit, (k, 1))
        self._colours = np.zeros((n, 3), np.float32)
        self._colours[rows["bones"]] = self._tubes.colours
        axes = np.eye(3, dtype=np.float32)  # each triad: x red, y green, z blue, both ends of each axis, per strand
        self._colours[rows["triads"]] = np.tile(np.repeat(np.tile(axes, (R, 1)), 2, axis=0), (len(TRIAD_STRANDS), 1))
        for part, rgb in self._marker_rgb.items():
            self._colours[rows[part]] = rgb
        self._colour_joints()
        old = [self._shared[k] for k in ("position", "color") if k in self._shared]  # this view's own arrays
        old_normal = self._shared.get("normal")
        # the normals and every part's triangle indices depend only on the skeleton and the counts: one model for
        # every view that shows as many markers (constant_attribute: released with the geometry that held it)
        self._shared = {"position": attribute(self._positions.astype(np.float32)),
                        "normal": constant_attribute(normals),
                        "color": attribute(self._colours.copy())}  # a copy: highlight() changes _colours
        corner = rows["corners"].start  # an empty part draws one degenerate triangle (or line) on a corner
        first = {p: rows[p].start for p in rows}
        indices = {"bones": self._tubes.faces + first["bones"],
                   "joints": self._spheres(J, first["joints"]),
                   "targets": self._spheres(T, first["targets"]) if T else np.full((1, 3), corner),
                   "looks": self._spheres(L, first["looks"]) if L else np.full((1, 3), corner),
                   "rays": np.arange(2 * L) + first["rays"] if L else np.full(2, corner),
                   "triads": np.arange(6 * R * len(TRIAD_STRANDS)) + first["triads"] if R else np.full(2, corner)}
        kinds = [three.Mesh] * 4 + [three.LineSegments] * 2
        for name, kind, material in zip(indices, kinds, self._materials):
            index = constant_attribute(np.asarray(indices[name], np.uint32).reshape(-1))
            shape = geometry(attributes={**self._shared, "index": index})
            mesh = getattr(self, name)
            if mesh is None:
                setattr(self, name, kind(shape, material))
            else:  # the same mesh (what pickers and groups hold), a new geometry; the old one closed
                previous, mesh.geometry = mesh.geometry, shape
                release(previous.attributes["index"])
                previous.close()
        for a in old:
            a.close()
        if old_normal is not None:
            release(old_normal)
        for mesh, shown in ((self.targets, T), (self.looks, L), (self.rays, L), (self.triads, R)):
            mesh.visible = bool(shown)

    def _colour_joints(self):
        rgb = np.repeat(self._joint_rgb[None], self.n_joints, axis=0)
        if self.highlighted is not None:
            rgb[self.highlighted] = self._highlight_rgb
        self._colours[self._rows["joints"]] = np.repeat(rgb, len(self.unit), axis=0)

    def highlight(self, k):
        """Draw joint ``k`` larger in the highlight colour (None: no joint); the size shows at the next
        :meth:`draw`."""
        k = None if k is None else int(k)
        if k == self.highlighted:
            return
        self.highlighted = k
        self._colour_joints()
        self._shared["color"].array = self._colours.copy()

    # ---------------------------------------------------------------- drawing
    def draw(self, pose, targets=None, looks=None, look_joints=(), rotations=None, rotation_joints=()):
        """Place every part and send the positions once.

        Parameters
        ----------
        pose : ndarray, shape (J, 3), metres
        targets : ndarray, shape (T, 3), optional
        looks : ndarray, shape (L, 3), optional
            Look-at points; ``look_joints`` (L,) the joints that look at them (the rays' other ends).
        rotations : ndarray, shape (R, 3, 3), optional
            World rotations asked for; ``rotation_joints`` (R,) the joints their triads sit on.
        """
        rows, P = self._rows, self._positions
        pose = np.asarray(pose, float)
        T, L, R = self.counts
        P[rows["bones"]] = self._tubes.vertices(pose)
        radius = np.full(self.n_joints, self.joint_radius)
        if self.highlighted is not None:
            radius[self.highlighted] *= self.HIGHLIGHT_SCALE
        P[rows["joints"]] = _sphere_vertices(self.unit, pose, radius)
        if T:
            targets = np.asarray(targets, float).reshape(T, 3)
            P[rows["targets"]] = _sphere_vertices(self.unit, targets, self.marker_radius)
        if L:
            looks = np.asarray(looks, float).reshape(L, 3)
            P[rows["looks"]] = _sphere_vertices(self.unit, looks, self.marker_radius)
            P[rows["rays"]] = np.stack([pose[list(look_joints)], looks], axis=1).reshape(-1, 3)
        if R:
            at = pose[list(rotation_joints)]  # (R, 3); a triad's axes are the columns of its rotation
            axes = np.asarray(rotations, float).reshape(R, 3, 3).transpose(0, 2, 1)  # (R, axis, xyz)
            tips = at[:, None, :] + self.triad_length * axes
            centre = np.stack([np.repeat(at[:, None, :], 3, axis=1), tips], axis=2)  # (R, axis, end, xyz)
            strands = []
            for a, b in TRIAD_STRANDS:  # each axis again beside itself, along the triad's other two axes
                shift = self.joint_radius * (a * np.roll(axes, -1, axis=1) + b * np.roll(axes, -2, axis=1))
                strands.append(centre + shift[:, :, None, :])
            P[rows["triads"]] = np.stack(strands).reshape(-1, 3)
        self._shared["position"].array = P.astype(np.float32)

    def part(self, name: str) -> np.ndarray:
        """The last drawn rows of one part (``"bones"``, ``"joints"``, ``"targets"``, ``"looks"``, ``"rays"``,
        ``"triads"``, ``"corners"``), float32, metres."""
        return np.asarray(self._shared["position"].array)[self._rows[name]]
