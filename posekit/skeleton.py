"""The skeleton: a tree of joints stored as a ``parents`` index array with rest offsets.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``. Units and axes:
:mod:`posekit.conventions` (metres, Y up, facing +Z).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Skeleton", "ROLES", "roles_hint", "joint_set_difference", "joint_sides"]

ROLES = (
    "pelvis", "chest", "neck", "head",
    "left_hip", "left_knee", "left_foot", "left_toe",
    "right_hip", "right_knee", "right_foot", "right_toe",
    "left_shoulder", "left_elbow", "left_hand",
    "right_shoulder", "right_elbow", "right_hand",
)
"""Canonical joint roles. A preset maps each role it has to one of its joint names, so that code
(effector sets, facing normalisation, mirroring) works on any dataset's naming."""

_SIDE_SWAPS = [
    (re.compile(r"Left"), "Right"), (re.compile(r"Right"), "Left"),
    (re.compile(r"left"), "right"), (re.compile(r"right"), "left"),
    (re.compile(r"LEFT"), "RIGHT"), (re.compile(r"RIGHT"), "LEFT"),
    (re.compile(r"_L$"), "_R"), (re.compile(r"_R$"), "_L"),
    (re.compile(r"^L(?=[A-Z_])"), "R"), (re.compile(r"^R(?=[A-Z_])"), "L"),
]


def roles_hint(missing) -> str:
    """How to supply roles that are missing: a ``roles=`` dict, shown with the first few."""
    missing = list(missing)
    example = ", ".join(f"'{r}': '<joint name>'" for r in missing[:3])
    more = ", ..." if len(missing) > 3 else ""
    return (f"pass roles={{{example}{more}}} to read_bvh / load_bvh_files / open_dataset, or use "
            "skeleton.with_roles({...})")


def joint_sides(names) -> np.ndarray:
    """Which side of the body each named joint is on: +1 left, -1 right, 0 central, shape (J,).

    The side markers are the ones mirroring swaps (:meth:`Skeleton.mirror_indices`): ``"left_hip"``,
    ``"Hand_L"``, ``"LeftArm"`` are left; a name without one is central. A character's left is +X in its
    root frame (:mod:`posekit.conventions`).

    Parameters
    ----------
    names : sequence of str, length J
        Joint names (a recorded still carries them without the rest of its skeleton).

    Returns
    -------
    ndarray of int, shape (J,)
    """
    out = np.zeros(len(names), dtype=int)
    for j, n in enumerate(names):
        for pattern, other in _SIDE_SWAPS:
            if pattern.search(str(n)):
                out[j] = 1 if other.strip("_").upper().startswith("R") else -1
                break
    return out


def _swap_side(name: str) -> str:
    """``"left_hip"`` -> ``"right_hip"``, ``"Hand_L"`` -> ``"Hand_R"``; central names unchanged."""
    for pattern, other in _SIDE_SWAPS:
        if pattern.search(name):
            return pattern.sub(other, name, count=1)
    return name


@dataclass(frozen=True, eq=False)
class Skeleton:
    """A kinematic tree.

    Parameters
    ----------
    names : sequence of str, length J
        Unique joint names.
    parents : array of int, shape (J,)
        ``parents[j] < j`` for every joint but the root, whose parent is ``-1``.
    offsets : array, shape (J, 3), metres
        Rest translation of each joint in its parent's frame (the root's is its rest position).
    roles : dict, optional
        Canonical role (see :data:`ROLES`) -> joint name.
    name : str
        A label such as ``"deepmimic"``.
    end_sites : dict, optional
        Joint index -> (3,) offset of a BVH ``End Site`` under it, kept so files can be written back.
    """

    names: tuple
    parents: np.ndarray
    offsets: np.ndarray
    roles: dict = field(default_factory=dict)
    name: str = ""
    end_sites: dict = field(default_factory=dict)

    def __post_init__(self):
        names = tuple(str(n) for n in self.names)
        parents = np.asarray(self.parents, dtype=np.int64).reshape(-1)
        offsets = np.asarray(self.offsets, dtype=float)
        J = len(names)
        if J == 0:
            raise ValueError("a skeleton needs at least one joint")
        if len(set(names)) != J:
            dup = sorted({n for n in names if names.count(n) > 1})
            raise ValueError(f"joint names must be unique; repeated: {dup}")
        if parents.shape != (J,):
            raise ValueError(f"parents: expected shape ({J},) for {J} names, got {parents.shape}")
        if offsets.shape != (J, 3):
            raise ValueError(f"offsets: expected shape ({J}, 3), got {offsets.shape}")
        if parents[0] != -1 or np.any(parents[1:] < 0):
            raise ValueError("parents: joint 0 must be the only root (parent -1)")
        if np.any(parents[1:] >= np.arange(1, J)):
            bad = int(np.nonzero(parents[1:] >= np.arange(1, J))[0][0]) + 1
            raise ValueError(f"parents: every parent must come before its child; joint {bad} "
                             f"({names[bad]}) has parent {parents[bad]}")
        if not np.all(np.isfinite(offsets)):
            raise ValueError("offsets contain NaN or inf")
        for role, joint in self.roles.items():
            if joint not in names:
                raise ValueError(f"role {role!r} maps to unknown joint {joint!r}")
        parents.setflags(write=False)
        offsets.setflags(write=False)
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "parents", parents)
        object.__setattr__(self, "offsets", offsets)
        object.__setattr__(self, "roles", dict(self.roles))
        object.__setattr__(self, "end_sites", {int(k): np.asarray(v, float) for k, v in self.end_sites.items()})

    # ------------------------------------------------------------------ lookup
    @property
    def n_joints(self) -> int:
        """Number of joints J."""
        return len(self.names)

    def __len__(self) -> int:
        return len(self.names)

    def index(self, joint: str | int) -> int:
        """Index of a joint given its name, its role (``"left_hand"``) or its index.

        Raises
        ------
        ValueError
            For an unknown name, listing the valid names and roles.
        """
        if isinstance(joint, (int, np.integer)):
            if not 0 <= joint < self.n_joints:
                raise ValueError(f"joint index {joint} out of range 0..{self.n_joints - 1}")
            return int(joint)
        if joint in self.names:
            return self.names.index(joint)
        if joint in self.roles:
            return self.names.index(self.roles[joint])
        if joint in ROLES:
            self.require_roles([joint])
        raise ValueError(
            f"unknown joint {joint!r} in skeleton {self.name or '(unnamed)'}; valid names: "
            f"{', '.join(self.names)}; valid roles: {', '.join(self.roles) or 'none'}"
        )

    def missing_roles(self, roles=ROLES) -> list[str]:
        """The roles of ``roles`` (default every canonical role) this skeleton has no joint for."""
        return [r for r in roles if r not in self.roles]

    def require_roles(self, roles, what: str = "") -> None:
        """Raise a ``ValueError`` naming the missing roles (and how to supply them) unless the
        skeleton has all of ``roles``; ``what`` says what needs them (e.g. ``"effector set '5'"``)."""
        missing = self.missing_roles(roles)
        if missing:
            need = f"{what} needs" if what else "this needs"
            raise ValueError(
                f"skeleton {self.name or '(unnamed)'} has no joint for the role(s) {', '.join(missing)} "
                f"({need} {', '.join(roles)}); roles it has: {', '.join(self.roles) or 'none'}. "
                f"{roles_hint(missing)}; joint names: {', '.join(self.names)}")

    def with_roles(self, roles: dict) -> "Skeleton":
        """A copy whose roles are updated with ``roles`` (role -> joint name); a value of None drops a role."""
        merged = {**self.roles, **roles}
        merged = {k: v for k, v in merged.items() if v is not None}
        return Skeleton(self.names, self.parents, self.offsets, merged, self.name, self.end_sites)

    def indices(self, joints) -> np.ndarray:
        """Indices of several joints (names, roles or indices), shape (K,)."""
        return np.array([self.index(j) for j in joints], dtype=np.int64)

    def pelvis(self) -> int:
        """Index of the pelvis role, or of the root when the skeleton has no such role."""
        return self.index("pelvis") if "pelvis" in self.roles else 0

    def children(self, joint) -> list[int]:
        """Indices of the direct children of a joint."""
        j = self.index(joint)
        return [int(c) for c in np.nonzero(self.parents == j)[0]]

    def chain(self, joint, base=0) -> list[int]:
        """Joint indices from ``base`` down to ``joint`` (both included)."""
        j, b = self.index(joint), self.index(base)
        out = [j]
        while out[-1] != b:
            p = int(self.parents[out[-1]])
            if p < 0:
                raise ValueError(f"{self.names[b]} is not an ancestor of {self.names[j]}")
            out.append(p)
        return out[::-1]

    # ------------------------------------------------------------------ geometry
    def bone_lengths(self) -> np.ndarray:
        """Rest length of the bone from each joint's parent to the joint, shape (J,), metres (0 for the root)."""
        lengths = np.linalg.norm(self.offsets, axis=-1)
        lengths[0] = 0.0
        return lengths

    def mirror_indices(self) -> np.ndarray:
        """For each joint the index of its left/right counterpart (itself when central), shape (J,)."""
        out = np.arange(self.n_joints)
        for j, n in enumerate(self.names):
            other = _swap_side(n)
            if other != n and other in self.names:
                out[j] = self.names.index(other)
        return out

    def sides(self) -> np.ndarray:
        """Which side of the body each joint is on, from its name: +1 left, -1 right, 0 central, shape (J,)
        (``"left_hip"``, ``"Hand_L"``, ``"LeftArm"`` are left; a name without a side marker is central).
        :func:`joint_sides` of :attr:`names`."""
        return joint_sides(self.names)

    def is_symmetric(self, atol: float = 1e-4) -> bool:
        """True when mirrored rest offsets (x -> -x, sides swapped) equal the offsets within ``atol`` metres."""
        m = self.mirror_indices()
        mirrored = self.offsets[m] * np.array([-1.0, 1.0, 1.0])
        return bool(np.allclose(mirrored[1:], self.offsets[1:], atol=atol))

    # ------------------------------------------------------------------ display / io
    def tree(self) -> str:
        """The hierarchy as indented text, one joint a line with its bone length in cm."""
        lengths = self.bone_lengths()
        depth = np.zeros(self.n_joints, dtype=int)
        for j in range(1, self.n_joints):
            depth[j] = depth[self.parents[j]] + 1
        lines = []

        def visit(j):
            role = [r for r, n in self.roles.items() if n == self.names[j]]
            tag = f"  [{', '.join(role)}]" if role else ""
            lines.append(f"{'  ' * depth[j]}{j:2d} {self.names[j]}  ({lengths[j] * 100:.1f} cm){tag}")
            for c in self.children(j):
                visit(c)

        visit(0)
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"Skeleton({self.name or 'unnamed'}: {self.n_joints} joints)"

    def to_arrays(self, prefix: str = "skeleton_") -> dict:
        """Arrays for ``np.savez`` (see :meth:`from_arrays`)."""
        roles = np.array([[k, v] for k, v in self.roles.items()], dtype=str).reshape(-1, 2)
        return {
            prefix + "names": np.array(self.names, dtype=str),
            prefix + "parents": self.parents,
            prefix + "offsets": self.offsets,
            prefix + "roles": roles,
            prefix + "name": np.array(self.name),
        }

    @classmethod
    def from_arrays(cls, arrays, prefix: str = "skeleton_") -> "Skeleton":
        """Rebuild a skeleton saved by :meth:`to_arrays`."""
        roles = {str(k): str(v) for k, v in np.asarray(arrays[prefix + "roles"]).reshape(-1, 2)}
        return cls(
            names=[str(n) for n in arrays[prefix + "names"]],
            parents=arrays[prefix + "parents"],
            offsets=arrays[prefix + "offsets"],
            roles=roles,
            name=str(arrays[prefix + "name"]),
        )

    def same_as(self, other: "Skeleton", atol: float = 1e-6) -> bool:
        """True when names, parents and offsets agree (used to check weights fit a skeleton)."""
        return (
            self.names == other.names
            and np.array_equal(self.parents, other.parents)
            and np.allclose(self.offsets, other.offsets, atol=atol)
        )


def joint_set_difference(reference, other, *, show: int = 3, words=("extra", "lacks")) -> list[str]:
    """The joints ``other`` has and ``reference`` lacks, and those it lacks, as at most two short phrases for a
    message — the first ``show`` names of each, never whole lists: ``["extra: a, b, ...", "lacks: c"]``.

    Parameters
    ----------
    reference, other : sequence of str
        Joint names.
    words : (str, str)
        How the two phrases begin.
    """
    extra = [n for n in other if n not in reference]
    lacking = [n for n in reference if n not in other]
    return [f"{word}: {', '.join(names[:show])}{', ...' if len(names) > show else ''}"
            for word, names in zip(words, (extra, lacking)) if names]
