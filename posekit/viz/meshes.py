"""The viewer's geometry: many spheres or many bone cylinders in one pythreejs mesh each.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb`` (through :class:`~posekit.viz.SkeletonViewer`).
Every shape of a kind lives in one buffer, so moving a pose rewrites one position array per mesh instead of
rebuilding the scene: playback and live solving stay smooth. Bones are flat-shaded (three.js derives each
face's normal on the graphics card), so a moved pose sends no normals. Units: metres; axes:
:mod:`posekit.conventions`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["icosphere", "Spheres", "Bones", "SIDE_COLOURS", "PICK_BOUND", "attribute"]

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


_ATTRIBUTE = None


def attribute(array):
    """A pythreejs ``BufferAttribute`` of ``array`` whose ``version`` is not echoed back to the browser.

    Every time the kernel sends a new array, the browser's copy of the attribute counts its ``version`` up and
    reports it to the kernel, and ipywidgets 8 answers each report with an echo of the same number: two
    messages and a busy/idle pair per array per update, for a number the kernel never reads or sets. This
    attribute (the same model in the browser) is not echoed, so a live update costs fewer messages."""
    global _ATTRIBUTE
    if _ATTRIBUTE is None:
        import pythreejs as three
        from traitlets import CInt

        class Attribute(three.BufferAttribute):
            version = CInt(-1, allow_none=False).tag(sync=True, echo_update=False)

        _ATTRIBUTE = Attribute
    return _ATTRIBUTE(array, normalized=False)


def _hex(colour: str) -> np.ndarray:
    colour = colour.lstrip("#")
    return np.array([int(colour[k:k + 2], 16) / 255 for k in (0, 2, 4)], dtype=np.float32)


class Spheres:
    """``n`` spheres of one radius and colour in one mesh; :meth:`set` moves them (centres (n, 3), metres).

    With ``highlight`` (a colour) one sphere at a time can be shown larger in that colour (:meth:`highlight`:
    a selected joint) without a mesh of its own, so moving the pose still sends one array."""

    HIGHLIGHT_SCALE = 1.6
    """Radius of the highlighted sphere, times :attr:`radius`."""

    def __init__(self, n, radius, color, opacity=1.0, highlight: str | None = None):
        import pythreejs as three

        self.unit, faces = icosphere(1)
        self.radius = radius
        self.n = n
        self._scale = np.ones(n)
        self._colour, self._highlight_colour, self.highlighted = _hex(color), highlight, None
        V = len(self.unit)
        index = (faces[None] + (np.arange(n) * V)[:, None, None]).reshape(-1).astype(np.uint32)
        normals = np.concatenate([np.tile(self.unit, (n, 1)), np.zeros((2, 3))]).astype(np.float32)
        attributes = {
            "position": attribute(self._positions(np.zeros((n, 3)))),
            "normal": three.BufferAttribute(normals, normalized=False),
            "index": three.BufferAttribute(index, normalized=False),
        }
        if highlight is not None:
            attributes["color"] = three.BufferAttribute(self._colours(), normalized=False)
            material = three.MeshLambertMaterial(vertexColors="VertexColors", transparent=opacity < 1,
                                                 opacity=opacity)
        else:
            material = three.MeshLambertMaterial(color=color, transparent=opacity < 1, opacity=opacity)
        self.geometry = three.BufferGeometry(attributes=attributes)
        self.mesh = three.Mesh(self.geometry, material)
        self._centres = np.zeros((n, 3))

    def _positions(self, centres):
        """Vertex positions (n V + 2, 3): each sphere's, then the two far corners (:data:`PICK_BOUND`)."""
        verts = (centres[:, None, :] + (self.radius * self._scale)[:, None, None] * self.unit[None]).reshape(-1, 3)
        return np.concatenate([verts, [[-PICK_BOUND] * 3, [PICK_BOUND] * 3]]).astype(np.float32)

    def _colours(self):
        rgb = np.repeat(self._colour[None], self.n, axis=0)
        if self.highlighted is not None:
            rgb[self.highlighted] = _hex(self._highlight_colour)
        return np.concatenate([np.repeat(rgb, len(self.unit), axis=0), np.zeros((2, 3))]).astype(np.float32)

    def set(self, centres):
        self._centres = np.asarray(centres, float)
        self.geometry.attributes["position"].array = self._positions(self._centres)

    def highlight(self, k):
        """Show sphere ``k`` larger in the highlight colour (None: none); needs ``highlight`` at construction."""
        if self._highlight_colour is None:
            raise ValueError("these spheres were made without a highlight colour")
        if k == self.highlighted:
            return
        self.highlighted = None if k is None else int(k)
        self._scale = np.ones(self.n)
        if k is not None:
            self._scale[int(k)] = self.HIGHLIGHT_SCALE
        self.geometry.attributes["color"].array = self._colours()
        self.set(self._centres)


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

        self.pairs = np.array([(skeleton.parents[j], j) for j in range(1, skeleton.n_joints)], dtype=int)
        self.radius, self.sides = float(radius), int(sides)
        angle = 2 * np.pi * np.arange(sides) / sides
        self._cos, self._sin = np.cos(angle)[:, None], np.sin(angle)[:, None]
        B, S = len(self.pairs), self.sides
        # per bone: ring at the parent (vertices 0..S-1), ring at the child (S..2S-1); two triangles per side
        k, k1 = np.arange(S), (np.arange(S) + 1) % S
        quad = np.stack([np.stack([k, k1, S + k], -1), np.stack([k1, S + k1, S + k], -1)], 1).reshape(-1, 3)
        index = (quad[None] + (np.arange(B) * 2 * S)[:, None, None]).reshape(-1).astype(np.uint32)
        side = skeleton.sides()[self.pairs[:, 1]]
        rgb = np.array([_hex(colour or SIDE_COLOURS[int(s)]) for s in side], dtype=np.float32)
        colours = np.repeat(rgb, 2 * S, axis=0)
        self.geometry = three.BufferGeometry(attributes={
            "position": attribute(self._buffers(np.zeros((skeleton.n_joints, 3)))),
            "color": three.BufferAttribute(colours, normalized=False),
            "index": three.BufferAttribute(index, normalized=False),
        })
        # flat shading: each face's normal comes from its vertices on the graphics card, so moving a pose sends
        # positions only (an 8-sided cylinder reads the same faceted or smooth at this size); no shine
        material = three.MeshPhongMaterial(vertexColors="VertexColors", flatShading=True, shininess=0,
                                           specular="#000000", transparent=opacity < 1, opacity=opacity)
        self.mesh = three.Mesh(self.geometry, material)

    def _buffers(self, pos):
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
        return verts.reshape(-1, 3).astype(np.float32)

    def set(self, pos):
        """Place the bones on global joint positions, shape (J, 3), metres."""
        self.geometry.attributes["position"].array = self._buffers(np.asarray(pos, float))
