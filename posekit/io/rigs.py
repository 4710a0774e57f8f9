"""Recognising someone else's rig: which joint plays which role, and which length unit the file uses.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb`` (section "your own mocap files"). Roles:
:data:`posekit.skeleton.ROLES`; units and axes: :mod:`posekit.conventions` (metres, Y up).

Roles are guessed from joint *names* first and the *hierarchy* second, so one set of rules covers
the common naming schemes:

=============  ==========================================================================
rig            what it looks like
=============  ==========================================================================
``cmu``        the cgspeed BVH conversion of the CMU database: 31 joints, ``LHipJoint``,
               ``LowerBack``, ``Spine1``, ``Neck1``, ``LeftFingerBase``, ``LThumb``
``holden21``   the 21 joints of CMU that Holden et al. 2016 keep (no zero-length joints)
``mixamo``     Adobe Mixamo exports: ``mixamorig:Hips`` ... ``Spine2`` ... ``LeftToeBase``
               (any ``mixamorig1:``-style prefix, or none)
``lafan1``     Ubisoft LAFAN1: Mixamo-like names with ``LeftToe``
``smpl``       SMPL's 24 joints: ``pelvis``, ``spine3``, ``left_collar``, ``left_ankle``
``bandai``     Bandai Namco Research Motion Dataset: ``UpperLeg_L``, ``Chest``, ``Toes_L``
``deepmimic``  the shipped sample: ``root``, ``chest``, ``left_wrist``, ``left_toe``
=============  ==========================================================================

Traps the rules handle: the *shoulder* role is the upper-arm joint (CMU/Mixamo ``LeftArm``,
SMPL ``left_shoulder``), never the clavicle (CMU/Mixamo ``LeftShoulder``, SMPL ``left_collar``);
SMPL's ``left_ankle`` is our ``left_foot`` and its ``left_foot`` our ``left_toe``; SMPL's
``left_wrist`` is our ``left_hand``; the *chest* is the joint both upper arms hang from (CMU
``Spine1``, Mixamo ``Spine2``, SMPL ``spine3``).

Units: a BVH file does not say its unit. :func:`guess_units` measures the rest pose's head height
above the feet and picks the unit that makes it closest to a person's (see :data:`UNITS`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from ..skeleton import ROLES, roles_hint

__all__ = ["guess_roles", "missing_roles", "detect_rig", "RolesReport", "rig_report", "UNITS",
           "UnitGuess", "standing_height", "guess_units", "unit_warning", "roles_hint", "RIG_NAMES", "CMU_SCALE"]

_PREFIX = re.compile(r"^(?:.*:|mixamorig\d*_|bip0*1[ _])", re.IGNORECASE)
_SIDES = [  # (pattern, side); the group "rest" is the name without the side marker
    (re.compile(r"^(?:left)[_.\s]?(?P<rest>.+)$", re.IGNORECASE), "left"),
    (re.compile(r"^(?:right)[_.\s]?(?P<rest>.+)$", re.IGNORECASE), "right"),
    (re.compile(r"^(?P<rest>.+?)[_.\s]?left$", re.IGNORECASE), "left"),
    (re.compile(r"^(?P<rest>.+?)[_.\s]?right$", re.IGNORECASE), "right"),
    (re.compile(r"^[Ll][_.\s](?P<rest>.+)$"), "left"),
    (re.compile(r"^[Rr][_.\s](?P<rest>.+)$"), "right"),
    (re.compile(r"^(?P<rest>.+)[_.\s][Ll]$"), "left"),
    (re.compile(r"^(?P<rest>.+)[_.\s][Rr]$"), "right"),
    (re.compile(r"^L(?P<rest>[A-Z].*)$"), "left"),  # CMU: LHipJoint, LThumb
    (re.compile(r"^R(?P<rest>[A-Z].*)$"), "right"),
]

# synonyms per limb role, most specific first; compared with the lower-case name stripped of
# its side marker, namespace and punctuation
_LIMB = {
    "hand": ("wrist", "hand"),
    "elbow": ("forearm", "lowerarm", "elbow"),
    "shoulder": ("upperarm", "arm", "humerus"),
    "foot": ("ankle", "foot"),
    "toe": ("toebase", "toe", "toes", "ball", "toe0"),
    "knee": ("leg", "lowerleg", "knee", "shin", "calf"),
    "hip": ("upleg", "upperleg", "thigh", "hip", "femur"),
}
_PELVIS = ("hips", "pelvis", "hip", "root")
_CHEST_BY_NAME = ("upperchest", "chest", "spine3", "spine2", "spine1", "spine")


def _split(name: str):
    """``"mixamorig:LeftUpLeg"`` -> ``("left", "upleg")``; central joints have side None."""
    stem = _PREFIX.sub("", name.strip())
    side, rest = None, stem
    for pattern, s in _SIDES:
        m = pattern.match(stem)
        if m:
            side, rest = s, m.group("rest")
            break
    if side is None:  # 3ds Max biped: "Bip01 L Thigh" (prefix already gone: "L Thigh")
        m = re.match(r"^(?P<a>.*?)\s(?P<s>[LR])\s(?P<b>.*)$", stem)
        if m:
            side, rest = ("left" if m.group("s") == "L" else "right"), m.group("a") + m.group("b")
    return side, re.sub(r"[^a-z0-9]", "", rest.lower())


def _ancestors(parents, j):
    out = []
    while j >= 0:
        out.append(j)
        j = int(parents[j])
    return out


def guess_roles(names, parents=None) -> dict:
    """Guess which joint plays each canonical role.

    Parameters
    ----------
    names : sequence of str, length J
        Joint names as written in the file (namespaces such as ``mixamorig:`` are fine).
    parents : array of int, shape (J,), optional
        Parent index of each joint (``-1`` for the root). With it the guess is better: the chest is
        the joint both upper arms hang from, and a limb joint with an unusual name is found from
        its child (the elbow is the hand's parent, the shoulder the elbow's).

    Returns
    -------
    dict
        Role (see :data:`posekit.skeleton.ROLES`) -> joint name, for every role found. Roles not
        found are absent: see :func:`missing_roles`.

    Examples
    --------
    >>> guess_roles(["Hips", "LeftUpLeg", "LeftLeg", "LeftFoot"], [-1, 0, 1, 2])["left_knee"]
    'LeftLeg'
    """
    names = [str(n) for n in names]
    par = None if parents is None else [int(p) for p in np.asarray(parents).reshape(-1)]
    central, sided = {}, {"left": {}, "right": {}}
    for j, n in enumerate(names):
        side, base = _split(n)
        (central if side is None else sided[side]).setdefault(base, j)
    roles = {}

    def pick(table, candidates):
        return next((table[c] for c in candidates if c in table), None)

    def parent_of(j):
        return None if par is None or j is None or par[j] < 0 else par[j]

    pelvis = pick(central, _PELVIS)
    roles["pelvis"] = 0 if pelvis is None else pelvis
    for side, table in sided.items():
        found = {k: pick(table, v) for k, v in _LIMB.items()}
        ankle_is_foot = found["foot"] is not None and table.get("ankle") == found["foot"]
        if found["toe"] is None and ankle_is_foot and "foot" in table:  # SMPL: ankle = foot, foot = toe
            found["toe"] = table["foot"]
        if found["elbow"] is None:
            found["elbow"] = parent_of(found["hand"])
        if found["shoulder"] is None:
            p = parent_of(found["elbow"])
            found["shoulder"] = p if p is not None and _split(names[p])[0] == side else table.get("shoulder")
        if found["knee"] is None:
            found["knee"] = parent_of(found["foot"])
        if found["hip"] is None:
            found["hip"] = parent_of(found["knee"])
        for k, j in found.items():
            if j is not None:
                roles[f"{side}_{k}"] = j
    necks = sorted(j for b, j in central.items() if re.fullmatch(r"neck\d*", b))
    if necks:
        roles["neck"] = necks[0]
    if "head" in central:
        roles["head"] = central["head"]
    chest = None
    if par is not None and "left_shoulder" in roles and "right_shoulder" in roles:
        right = set(_ancestors(par, roles["right_shoulder"]))
        chest = next((j for j in _ancestors(par, roles["left_shoulder"])[1:] if j in right), None)
    if chest is None:
        chest = pick(central, _CHEST_BY_NAME)
    if chest is not None:
        roles["chest"] = chest
    return {r: names[roles[r]] for r in ROLES if r in roles}


def missing_roles(roles, required=ROLES) -> list:
    """The roles of ``required`` (default every canonical role) that ``roles`` lacks, in order."""
    return [r for r in required if r not in roles]


_SIGNATURES = [  # (rig, names that must all be present, lower case, namespace stripped)
    ("smpl", {"pelvis", "spine3", "left_collar", "left_ankle"}),
    ("deepmimic", {"root", "chest", "left_ankle", "left_wrist", "left_toe"}),
    ("bandai", {"hips", "chest", "upperleg_l", "lowerarm_l", "toes_l"}),
    ("cmu", {"hips", "lhipjoint", "lowerback", "spine1", "neck1", "leftfingerbase", "lthumb"}),
    ("cmu", {"hips", "lhipjoint", "lowerback", "spine1", "neck1", "leftarm"}),
    ("holden21", {"hips", "leftupleg", "lefttoebase", "spine1", "neck1", "leftarm", "lefthandindex1"}),
    ("lafan1", {"hips", "leftupleg", "lefttoe", "spine2", "leftforearm"}),
    ("mixamo", {"hips", "leftupleg", "lefttoebase", "spine2", "leftforearm"}),
]
RIG_NAMES = {
    "cmu": "CMU mocap, cgspeed BVH conversion", "holden21": "CMU retargeted, 21 joints (Holden et al. 2016)",
    "mixamo": "Adobe Mixamo", "lafan1": "Ubisoft LAFAN1", "smpl": "SMPL body model",
    "bandai": "Bandai Namco Research Motion", "deepmimic": "DeepMimic humanoid", "unknown": "not recognised",
}
"""Rig name -> description, for reports."""


def detect_rig(names) -> str:
    """Name of the known rig a list of joint names belongs to (see the module docstring), else
    ``"unknown"``. Roles do not depend on it: :func:`guess_roles` works on any names."""
    plain = [_PREFIX.sub("", str(n)).lower() for n in names]
    if any(str(n).lower().startswith("mixamorig") for n in names):
        return "mixamo"
    have = set(plain)
    for rig, need in _SIGNATURES:
        if need <= have:
            if rig == "holden21" and "lhipjoint" in have:
                continue
            return rig
    return "unknown"


@dataclass(frozen=True)
class RolesReport:
    """Which rig a skeleton looks like and which roles it has.

    Attributes
    ----------
    rig : str
        Key of :data:`RIG_NAMES` (``"unknown"`` when not recognised).
    roles : dict
        Role -> joint name.
    missing : tuple of str
        Canonical roles without a joint.
    """

    rig: str
    roles: dict = field(default_factory=dict)
    missing: tuple = ()

    def describe(self) -> str:
        """One line, e.g. ``"cmu (CMU mocap, cgspeed BVH conversion); all 18 roles"``."""
        head = f"{self.rig} ({RIG_NAMES.get(self.rig, self.rig)})"
        if not self.missing:
            return f"{head}; all {len(ROLES)} roles"
        return (f"{head}; {len(ROLES) - len(self.missing)}/{len(ROLES)} roles, missing: "
                f"{', '.join(self.missing)} ({roles_hint(self.missing)})")


def rig_report(names, roles: dict) -> RolesReport:
    """:class:`RolesReport` of joint ``names`` with the given ``roles`` (e.g. ``skeleton.roles``)."""
    return RolesReport(detect_rig(names), dict(roles), tuple(missing_roles(roles)))


# ---------------------------------------------------------------------------------------- units
CMU_SCALE = 0.07
"""Metres per CMU (cgspeed BVH) unit. The ASF convention, 1 unit = 1/0.45 inch = 0.0564 m, makes the
cgspeed skeleton's head joint stand about 1.3 m above its toes, and its trunk looks short; 0.07 puts
that head joint at about 1.6 m, a person about 1.75 m tall. Pass ``scale=0.056444`` for the ASF
convention."""

UNITS = (
    ("m", 1.0, "metres"),
    ("cm", 0.01, "centimetres"),
    ("mm", 0.001, "millimetres"),
    ("inch", 0.0254, "inches"),
    ("cmu", CMU_SCALE, "CMU mocap units: 0.07 m each puts the head joint about 1.6 m up"),
)
"""Candidate units: (key, metres per file unit, description)."""

HEAD_HEIGHT = 1.6
"""Metres: head joint above the soles for an adult about 1.75 m tall; the unit guess aims at it."""

PLAUSIBLE = (0.4, 4.0)
"""Metres: head heights a guess may produce; outside this the unit stays unknown (scale 1)."""


@dataclass(frozen=True)
class UnitGuess:
    """The length unit of a file.

    Attributes
    ----------
    unit : str
        Key of :data:`UNITS`, ``"unknown"`` or ``"given"`` (a ``scale`` was passed).
    scale : float
        Metres per file unit, the factor that was applied.
    file_height : float
        Standing height (head joint above the lowest foot or toe, rest pose) in file units.
    detected : str
        The unit the heuristic picked, even when ``scale`` was given.
    """

    unit: str
    scale: float
    file_height: float
    detected: str

    @property
    def height(self) -> float:
        """Standing height in metres after scaling."""
        return self.file_height * self.scale

    def describe(self) -> str:
        """E.g. ``"cm (centimetres), scale 0.01, height 1.49 m"``."""
        names = {k: d for k, _, d in UNITS}
        what = {"given": "scale given", "unknown": "unit not recognised"}.get(self.unit, names.get(self.unit))
        return f"{self.unit} ({what}), scale {self.scale:.6g}, height {self.height:.2f} m"


def _rest_positions(parents, offsets):
    pos = np.zeros((len(parents), 3))
    for j, p in enumerate(parents):
        pos[j] = offsets[j] + (pos[p] if p >= 0 else 0.0)
    return pos


def standing_height(names, parents, offsets, roles: dict | None = None, global_pos=None) -> float:
    """Height of a skeleton in its own units.

    The head joint's height above the lowest foot or toe joint in the rest pose (offsets alone). When
    those roles are missing or the rest pose is not upright (a Z-up file), the largest extent of
    the rest pose along one axis; when every offset is zero (files that animate all translations),
    the median over frames of that extent in ``global_pos``.

    Parameters
    ----------
    names : sequence of str, length J
    parents : array of int, shape (J,)
    offsets : array, shape (J, 3), file units
    roles : dict, optional
        Role -> joint name (default: :func:`guess_roles`).
    global_pos : array, shape (F, J, 3), file units, optional

    Returns
    -------
    float, file units (0 when nothing can be measured)
    """
    names = list(names)
    roles = guess_roles(names, parents) if roles is None else roles
    pos = _rest_positions(np.asarray(parents), np.asarray(offsets, float))
    extent = float(np.ptp(pos, axis=0).max()) if len(pos) else 0.0
    feet = [names.index(roles[r]) for r in ("left_foot", "right_foot", "left_toe", "right_toe")
            if roles.get(r) in names]
    if roles.get("head") in names and feet:
        h = float(pos[names.index(roles["head"]), 1] - pos[feet, 1].min())
        if h > 0.5 * extent:
            return h
    if extent > 1e-9 or global_pos is None or len(global_pos) == 0:
        return extent
    return float(np.median(np.ptp(np.asarray(global_pos, float), axis=1).max(axis=-1)))


def guess_units(file_height: float, scale: float | None = None) -> UnitGuess:
    """Pick the unit of a file from its standing height (:func:`standing_height`).

    The heuristic: among :data:`UNITS`, the one whose metres-per-unit makes the height closest to
    :data:`HEAD_HEIGHT` on a log scale (so 60-ish units reads as inches, 150-ish as centimetres,
    15-35 as CMU units); if even that height is outside :data:`PLAUSIBLE`, the unit is
    ``"unknown"`` and the scale 1.

    Parameters
    ----------
    file_height : float, file units
    scale : float, optional
        A scale the caller insists on (metres per file unit); it wins, the guess is still reported.

    Returns
    -------
    UnitGuess
    """
    detected, best = "unknown", 1.0
    if file_height > 0 and np.isfinite(file_height):
        key, s, _ = min(UNITS, key=lambda u: abs(np.log(file_height * u[1] / HEAD_HEIGHT)))
        if PLAUSIBLE[0] <= file_height * s <= PLAUSIBLE[1]:
            detected, best = key, s
    if scale is not None:
        return UnitGuess("given", float(scale), float(file_height), detected)
    return UnitGuess(detected, best, float(file_height), detected)


def unit_warning(guess: UnitGuess, where: str) -> str | None:
    """The warning to show when a unit was guessed and is not metres (None otherwise)."""
    if guess.unit in ("given", "m"):
        return None
    if guess.unit == "unknown":
        return (f"{where}: could not tell the length unit (standing height {guess.file_height:.4g} file units); "
                "kept the file's numbers as metres; pass scale=... (CLI: --scale) to convert")
    asf = " or scale=0.056444 for the CMU ASF convention" if guess.unit == "cmu" else ""
    return (f"{where}: lengths look like {guess.describe()}; converted to metres. "
            f"Pass scale=... (CLI: --scale) to override, e.g. scale=1 to keep the file's numbers{asf}")
