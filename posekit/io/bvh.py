"""BVH motion files: a reader that survives real files and a writer.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``. Conventions: :mod:`posekit.conventions`
(BVH channel order is an intrinsic Euler sequence, angles in the file are degrees).

The reader accepts any channel layout (0-6 channels on any joint; position channels give that
joint's translation, replacing its OFFSET), any rotation order, ``End Site`` blocks, CRLF line ends,
tabs, scientific notation, and a unit ``scale`` (0.01 for centimetre files, ``None`` to detect the unit
from the skeleton's height: :func:`posekit.io.rigs.guess_units`). Joint roles are guessed from the
names (:func:`posekit.io.rigs.guess_roles`) unless given. Malformed files raise :class:`BVHError`
naming the file and the line; a ``Frames:`` count one short of the rows that follow (a common exporter
slip) only warns (:class:`BVHWarning`) and all rows are read.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ..kinematics import fk
from ..rotations import quat_to_euler
from ..skeleton import Skeleton
from .rigs import guess_roles, guess_units, rig_report, standing_height, unit_warning

__all__ = ["BVHError", "BVHWarning", "BVHMotion", "read_bvh", "write_bvh"]

_ROT = {"Xrotation": "X", "Yrotation": "Y", "Zrotation": "Z"}
_POS = {"Xposition": 0, "Yposition": 1, "Zposition": 2}


class BVHError(ValueError):
    """A malformed BVH file; the message starts with ``path:line:``."""

    def __init__(self, path, line, message):
        self.path, self.line = str(path), line
        where = f"{path}:{line}" if line else str(path)
        super().__init__(f"{where}: {message}")


class BVHWarning(UserWarning):
    """A BVH file that was read despite a slip (e.g. one more frame row than ``Frames:`` says)."""


@dataclass
class BVHMotion:
    """A motion read from a BVH file.

    Attributes
    ----------
    skeleton : Skeleton
        Joints (End Sites excluded, kept in ``skeleton.end_sites``), offsets in metres.
    local_rot : ndarray, shape (F, J, 4)
        Local rotations, quaternions ``(x, y, z, w)``.
    local_pos : ndarray, shape (F, J, 3), metres
        Local translations: the position channels where a joint has them, else its OFFSET.
    frame_time : float
        Seconds per frame.
    channels : list of tuple of str
        Each joint's channels as written.
    path : str
    units : UnitGuess
        The detected length unit, the scale applied and the standing height
        (:class:`posekit.io.rigs.UnitGuess`).
    rig : RolesReport
        The recognised rig and the roles it lacks (:class:`posekit.io.rigs.RolesReport`).
    """

    skeleton: Skeleton
    local_rot: np.ndarray
    local_pos: np.ndarray
    frame_time: float
    channels: list
    path: str = ""
    units: object = None
    rig: object = None

    @property
    def n_frames(self) -> int:
        return int(self.local_rot.shape[0])

    @property
    def root_pos(self) -> np.ndarray:
        """World position of joint 0 per frame, shape (F, 3)."""
        return self.local_pos[:, 0]

    def global_positions(self) -> np.ndarray:
        """Global joint positions by FK, shape (F, J, 3), metres."""
        return fk(self.skeleton, self.local_rot, local_pos=self.local_pos)[0]


class _Tokens:
    """Whitespace tokens of the HIERARCHY part, with their line numbers."""

    def __init__(self, lines, path):
        self.items = []
        self.path = path
        for lineno, line in lines:
            for tok in line.split():
                self.items.append((tok, lineno))
        self.i = 0
        self.last_line = lines[-1][0] if lines else 1

    def peek(self):
        return self.items[self.i][0] if self.i < len(self.items) else None

    def next(self, what):
        if self.i >= len(self.items):
            raise BVHError(self.path, self.last_line, f"file ends early: expected {what}")
        tok, line = self.items[self.i]
        self.i += 1
        return tok, line

    def expect(self, word):
        tok, line = self.next(repr(word))
        if tok != word:
            raise BVHError(self.path, line, f"expected {word!r}, found {tok!r}")
        return line

    def number(self, what):
        tok, line = self.next(what)
        try:
            value = float(tok)
        except ValueError:
            raise BVHError(self.path, line, f"expected a number for {what}, found {tok!r}") from None
        if not np.isfinite(value):
            raise BVHError(self.path, line, f"{what} is {tok}; expected a finite number")
        return value


def read_bvh(path, scale: float | None = 1.0, drop_tpose: bool = False, roles: dict | None = None,
             name: str = "") -> BVHMotion:
    """Read a BVH file.

    Parameters
    ----------
    path : str or Path
    scale : float or None
        Multiplies every length (OFFSETs, position channels): 0.01 turns centimetres into metres.
        The default 1 keeps the file's numbers. ``None`` detects the unit from the rest pose's
        standing height (:func:`posekit.io.rigs.guess_units`) and warns when it is not metres.
    drop_tpose : bool
        Drop the first frame (many captures start with a T-pose).
    roles : dict, optional
        Canonical roles (see :data:`posekit.skeleton.ROLES`) -> joint names. Default: guessed from
        the joint names and hierarchy (:func:`posekit.io.rigs.guess_roles`); the roles given
        replace the guessed ones of the same name, the others stay guessed.
    name : str
        Label for the skeleton.

    Returns
    -------
    BVHMotion
        With ``units`` (detected unit, applied scale, height) and ``rig`` (rig name, missing roles).

    Raises
    ------
    BVHError
        Malformed file, with its path and line number; also when ``Frames:`` says more frames than
        the file has, or two or more fewer.

    Warns
    -----
    BVHWarning
        ``Frames:`` is exactly one less than the complete rows that follow: all rows are read.
    UserWarning
        ``scale=None`` and the detected unit is not metres (the message says which and how to override).
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as e:
        raise BVHError(path, 0, f"cannot read: {e.strerror or e}") from None
    lines = text.splitlines()
    motion_at = next((i for i, l in enumerate(lines) if l.strip().upper().startswith("MOTION")), None)
    if not lines or lines[0].split()[:1] != ["HIERARCHY"]:
        first = next((i for i, l in enumerate(lines) if l.strip()), 0)
        if not lines or lines[first].strip() != "HIERARCHY":
            raise BVHError(path, first + 1, "expected 'HIERARCHY' at the start of a BVH file")
    if motion_at is None:
        raise BVHError(path, len(lines), "no MOTION section (file truncated?)")
    toks = _Tokens([(i + 1, l) for i, l in enumerate(lines[:motion_at])], path)
    toks.expect("HIERARCHY")

    names, parents, offsets, channels, end_sites = [], [], [], [], {}

    def parse_joint(parent):
        j = len(names)
        name_tok, line = toks.next("a joint name")
        names.append(name_tok)
        parents.append(parent)
        toks.expect("{")
        toks.expect("OFFSET")
        offsets.append([toks.number(f"OFFSET of {name_tok}") for _ in range(3)])
        chans = ()
        if toks.peek() == "CHANNELS":
            toks.next("CHANNELS")
            n = toks.number(f"channel count of {name_tok}")
            if n != int(n) or not 0 <= n <= 6:
                raise BVHError(path, toks.items[toks.i - 1][1], f"channel count must be 0..6, found {n:g}")
            chans = []
            for _ in range(int(n)):
                c, cl = toks.next(f"a channel name of {name_tok}")
                if c not in _ROT and c not in _POS:
                    raise BVHError(path, cl, f"unknown channel {c!r} on joint {name_tok}; expected one of "
                                   f"{', '.join(list(_POS) + list(_ROT))}")
                chans.append(c)
            chans = tuple(chans)
        channels.append(chans)
        while True:
            tok, tl = toks.next(f"'}}' closing joint {name_tok}")
            if tok == "}":
                return
            if tok == "JOINT":
                parse_joint(j)
            elif tok == "End":
                toks.expect("Site")
                toks.expect("{")
                toks.expect("OFFSET")
                end_sites[j] = [toks.number("End Site OFFSET") for _ in range(3)]
                toks.expect("}")
            else:
                raise BVHError(path, tl, f"expected JOINT, End Site or '}}' in joint {name_tok}, found {tok!r}")

    root_tok, root_line = toks.next("ROOT")
    if root_tok != "ROOT":
        raise BVHError(path, root_line, f"expected 'ROOT', found {root_tok!r}")
    parse_joint(-1)
    if toks.peek() is not None:
        tok, tl = toks.next("")
        raise BVHError(path, tl, f"unexpected {tok!r} after the joint hierarchy (a second ROOT is not supported)")

    # ---- MOTION header
    F, frame_time, row_at = None, None, motion_at + 1
    while row_at < len(lines) and (F is None or frame_time is None):
        line = lines[row_at].strip()
        row_at += 1
        if not line:
            continue
        key, _, value = line.partition(":")
        key = key.strip().lower()
        try:
            if key == "frames":
                F = int(value.strip())
            elif key == "frame time":
                frame_time = float(value.strip())
            else:
                raise BVHError(path, row_at, f"expected 'Frames:' and 'Frame Time:' after MOTION, found {line[:40]!r}")
        except ValueError as e:
            if isinstance(e, BVHError):
                raise
            raise BVHError(path, row_at, f"bad number in {line[:40]!r}") from None
    if F is None or frame_time is None:
        raise BVHError(path, row_at, "MOTION section lacks 'Frames:' or 'Frame Time:' (file truncated?)")
    if F < 0 or not np.isfinite(frame_time) or frame_time <= 0:
        raise BVHError(path, row_at, f"Frames must be >= 0 and Frame Time > 0, found {F} and {frame_time}")

    # ---- frame rows
    n_ch = sum(len(c) for c in channels)
    rows = [(i + 1, l) for i, l in enumerate(lines[row_at:], start=row_at) if l.strip()]
    if rows and 0 < len(rows[-1][1].split()) < n_ch and len(rows) in (F, F + 1):
        # the file ends inside a frame row (a cut copy, an interrupted export): that row is no frame
        lineno, cut = rows.pop()
        said = f"Frames: says {F}, " if len(rows) < F else ""
        warnings.warn(f"{path}:{lineno}: the last frame row is cut off ({len(cut.split())} of {n_ch} values); "
                      f"{said}read the {len(rows)} complete frame rows before it", BVHWarning, stacklevel=2)
        F = len(rows)
    if len(rows) < F:
        last = rows[-1][0] if rows else row_at
        raise BVHError(path, last, f"Frames: says {F} frames but the file has {len(rows)} (truncated?)")
    if len(rows) == F + 1 and len(rows[F][1].split()) == n_ch:
        warnings.warn(f"{path}:{rows[F][0]}: Frames: says {F} frames but the file has {F + 1} complete frame "
                      f"rows; reading all {F + 1}", BVHWarning, stacklevel=2)
        F += 1
    if len(rows) > F:
        raise BVHError(path, rows[F][0], f"Frames: says {F} frames but {len(rows)} frame rows follow")
    for lineno, l in rows:
        if len(l.split()) != n_ch:
            raise BVHError(path, lineno, f"expected {n_ch} values in a frame row, found {len(l.split())}")
    try:
        data = np.array(" ".join(l for _, l in rows).split(), dtype=float).reshape(F, n_ch)
    except ValueError:
        for lineno, l in rows:
            for tok in l.split():
                try:
                    float(tok)
                except ValueError:
                    raise BVHError(path, lineno, f"bad number {tok!r} in a frame row") from None
        raise
    if not np.all(np.isfinite(data)):
        bad = int(np.nonzero(~np.all(np.isfinite(data), axis=1))[0][0])
        raise BVHError(path, rows[bad][0], "frame row contains nan or inf")
    if drop_tpose and F > 0:
        data, F = data[1:], F - 1

    guessed = guess_roles(names, parents)
    if roles is not None:
        unknown = {r: j for r, j in roles.items() if j not in names}
        if unknown:
            raise ValueError(f"{path}: roles name joints the file does not have: {unknown}; "
                             f"joints: {', '.join(names)}")
        guessed.update(roles)
    roles = guessed
    height = standing_height(names, parents, offsets, roles)
    if height <= 1e-9 and F:  # every OFFSET zero: measure the animated pose instead
        raw = _decode(names, parents, offsets, channels, data[: min(F, 200)], 1.0)
        height = standing_height(names, parents, offsets, roles,
                                 fk(raw[0], raw[1], local_pos=raw[2])[0])
    units = guess_units(height, scale)
    if scale is None:
        message = unit_warning(units, str(path))
        if message:
            warnings.warn(message, UserWarning, stacklevel=2)
    skeleton, local_rot, local_pos = _decode(names, parents, offsets, channels, data, units.scale, roles,
                                             name or path.stem, end_sites)
    return BVHMotion(skeleton, local_rot, local_pos, float(frame_time), channels, str(path), units,
                     rig_report(names, roles))


def _decode(names, parents, offsets, channels, data, scale, roles=None, name="", end_sites=None):
    """Skeleton, local quaternions (F, J, 4) and local translations (F, J, 3) from frame rows."""
    F, J = len(data), len(names)
    offsets = np.asarray(offsets, dtype=float) * scale
    local_pos = np.broadcast_to(offsets, (F, J, 3)).copy()
    local_rot = np.zeros((F, J, 4))
    local_rot[..., 3] = 1.0
    col = 0
    for j, chans in enumerate(channels):
        axes = "".join(_ROT[c] for c in chans if c in _ROT)
        rot_cols = [col + k for k, c in enumerate(chans) if c in _ROT]
        for k, c in enumerate(chans):
            if c in _POS:
                local_pos[:, j, _POS[c]] = data[:, col + k] * scale
        if axes and F:
            local_rot[:, j] = Rotation.from_euler(axes, data[:, rot_cols], degrees=True).as_quat()
        col += len(chans)
    skeleton = Skeleton(names, parents, offsets, roles=roles or {}, name=name,
                        end_sites={k: np.asarray(v) * scale for k, v in (end_sites or {}).items()})
    return skeleton, local_rot, local_pos


def write_bvh(path, skeleton: Skeleton, local_rot, frame_time: float, local_pos=None, root_pos=None,
              channels=None, order: str = "ZXY", scale: float = 1.0, precision: int = 9):
    """Write a motion as BVH.

    Parameters
    ----------
    path : str or Path
    skeleton : Skeleton
        Offsets in metres; ``skeleton.end_sites`` are written as End Site blocks.
    local_rot : ndarray, shape (F, J, 4)
        Local quaternions ``(x, y, z, w)``.
    frame_time : float
        Seconds per frame.
    local_pos : ndarray, shape (F, J, 3), optional
        Local translations; joints with position channels write theirs from here.
    root_pos : ndarray, shape (F, 3), optional
        Root translation (used when ``local_pos`` is not given).
    channels : list of tuple of str, optional
        Channels per joint (e.g. ``BVHMotion.channels`` to keep a file's layout). Default: the root
        has ``X/Y/Zposition`` + rotations, other joints rotations only, in ``order``.
    order : str
        Rotation channel order for the default layout, e.g. ``"ZXY"``.
    scale : float
        File units per metre (100 writes centimetres).
    """
    local_rot = np.asarray(local_rot, dtype=float)
    F, J = local_rot.shape[0], skeleton.n_joints
    if local_rot.shape != (F, J, 4):
        raise ValueError(f"local_rot: expected shape (F, {J}, 4), got {local_rot.shape}")
    if local_pos is None:
        local_pos = np.broadcast_to(skeleton.offsets, (F, J, 3)).copy()
        if root_pos is not None:
            local_pos[:, 0] = np.asarray(root_pos, dtype=float)
    local_pos = np.asarray(local_pos, dtype=float)
    if channels is None:
        rot = tuple(f"{a}rotation" for a in order.upper())
        channels = [("Xposition", "Yposition", "Zposition") + rot] + [rot] * (J - 1)
    fmt = f"{{:.{precision}g}}"
    out = ["HIERARCHY"]

    def emit(j, depth):
        pad = "  " * depth
        out.append(f"{pad}{'ROOT' if j == 0 else 'JOINT'} {skeleton.names[j]}")
        out.append(f"{pad}{{")
        off = " ".join(fmt.format(v * scale) for v in skeleton.offsets[j])
        out.append(f"{pad}  OFFSET {off}")
        if channels[j]:
            out.append(f"{pad}  CHANNELS {len(channels[j])} {' '.join(channels[j])}")
        for c in skeleton.children(j):
            emit(c, depth + 1)
        if j in skeleton.end_sites:
            es = " ".join(fmt.format(v * scale) for v in skeleton.end_sites[j])
            out.extend([f"{pad}  End Site", f"{pad}  {{", f"{pad}    OFFSET {es}", f"{pad}  }}"])
        out.append(f"{pad}}}")

    emit(0, 0)
    cols = []
    for j, chans in enumerate(channels):
        axes = "".join(_ROT[c] for c in chans if c in _ROT)
        if len(axes) not in (0, 3):
            raise ValueError(f"writing needs 0 or 3 rotation channels per joint; {skeleton.names[j]} has {chans}")
        eul = quat_to_euler(local_rot[:, j], axes, degrees=True) if axes else None
        k = 0
        for c in chans:
            if c in _POS:
                cols.append(local_pos[:, j, _POS[c]] * scale)
            else:
                cols.append(eul[:, k])
                k += 1
    data = np.stack(cols, axis=1) if cols else np.zeros((F, 0))
    out += ["MOTION", f"Frames: {F}", f"Frame Time: {frame_time:.8g}"]
    out += [" ".join(fmt.format(v) for v in row) for row in data]
    Path(path).write_text("\n".join(out) + "\n", encoding="utf-8")
    return os.fspath(path)
