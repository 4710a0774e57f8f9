"""Rigs in the wild: role guessing, unit detection, per-subject offsets (posekit.io.rigs)."""

import json
import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from posekit.data import load_sample, open_dataset
from posekit.io.rigs import (CMU_SCALE, detect_rig, guess_roles, guess_units, missing_roles, rig_report,
                               standing_height)
from posekit.data.bandai import BANDAI_ROLES
from posekit.io.bvh import read_bvh, write_bvh
from posekit.skeleton import ROLES, Skeleton

# ------------------------------------------------------------------ rigs: (name, parent name, offset)
_CMU_LEG = [("{L}HipJoint", "Hips", (0, 0, 0)), ("{Side}UpLeg", "{L}HipJoint", (1.8, -1.75, 0.85)),
            ("{Side}Leg", "{Side}UpLeg", (2.4, -6.6, 0)), ("{Side}Foot", "{Side}Leg", (2.5, -6.9, 0)),
            ("{Side}ToeBase", "{Side}Foot", (0.16, -0.44, 2.0))]
_CMU_ARM = [("{Side}Shoulder", "Spine1", (0, 0, 0)), ("{Side}Arm", "{Side}Shoulder", (3.3, 0.9, 0.05)),
            ("{Side}ForeArm", "{Side}Arm", (5.0, 0, 0)), ("{Side}Hand", "{Side}ForeArm", (3.4, 0, 0)),
            ("{Side}FingerBase", "{Side}Hand", (0, 0, 0)), ("{Side}HandIndex1", "{Side}FingerBase", (0.8, 0, 0)),
            ("{L}Thumb", "{Side}Hand", (0, 0, 0))]


def _sided(table, side):
    sign = 1.0 if side == "Left" else -1.0
    fill = lambda s: s.format(Side=side, L=side[0])
    return [(fill(n), fill(p), (sign * o[0], o[1], o[2])) for n, p, o in table]


def cmu_rig():
    """The cgspeed CMU BVH layout (31 joints) in CMU units, offsets close to subject 01's."""
    return ([("Hips", None, (0, 0, 0))] + _sided(_CMU_LEG, "Left") + _sided(_CMU_LEG, "Right")
            + [("LowerBack", "Hips", (0, 0, 0)), ("Spine", "LowerBack", (0, 2.2, 0)),
               ("Spine1", "Spine", (0.05, 2.2, -0.1)), ("Neck", "Spine1", (0, 0, 0)),
               ("Neck1", "Neck", (-0.1, 1.45, 0.25)), ("Head", "Neck1", (0.15, 1.45, -0.3))]
            + _sided(_CMU_ARM, "Left") + _sided(_CMU_ARM, "Right"))


_MIXAMO_LEG = [("{Side}UpLeg", "Hips", (9, -7, 0)), ("{Side}Leg", "{Side}UpLeg", (0, -42, 0)),
               ("{Side}Foot", "{Side}Leg", (0, -41, 0)), ("{Side}ToeBase", "{Side}Foot", (0, -7, 12)),
               ("{Side}Toe_End", "{Side}ToeBase", (0, 0, 8))]
_MIXAMO_ARM = [("{Side}Shoulder", "Spine2", (6, 12, 0)), ("{Side}Arm", "{Side}Shoulder", (12, 0, 0)),
               ("{Side}ForeArm", "{Side}Arm", (27, 0, 0)), ("{Side}Hand", "{Side}ForeArm", (26, 0, 0)),
               ("{Side}HandIndex1", "{Side}Hand", (9, 0, 0))]


def mixamo_rig(prefix="mixamorig:"):
    """A Mixamo export in centimetres (fingers trimmed to one), names with a namespace prefix."""
    rig = ([("Hips", None, (0, 97, 0)), ("Spine", "Hips", (0, 10, 0.5)), ("Spine1", "Spine", (0, 12, 0)),
            ("Spine2", "Spine1", (0, 13, 0)), ("Neck", "Spine2", (0, 15, 0)), ("Head", "Neck", (0, 10, 2)),
            ("HeadTop_End", "Head", (0, 18, 2))]
           + _sided(_MIXAMO_ARM, "Left") + _sided(_MIXAMO_ARM, "Right")
           + _sided(_MIXAMO_LEG, "Left") + _sided(_MIXAMO_LEG, "Right"))
    return [(prefix + n, p and prefix + p, o) for n, p, o in rig]


SMPL_NAMES = ["pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2", "left_ankle",
              "right_ankle", "spine3", "left_foot", "right_foot", "neck", "left_collar", "right_collar", "head",
              "left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist",
              "left_hand", "right_hand"]
SMPL_PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]
_SMPL_OFFSETS = {"pelvis": (0, 0.93, 0), "left_hip": (0.06, -0.09, 0), "spine1": (0, 0.11, -0.01),
                 "left_knee": (0.04, -0.38, 0), "spine2": (0, 0.14, 0.01), "left_ankle": (-0.01, -0.4, -0.04),
                 "spine3": (0, 0.06, 0), "left_foot": (0.04, -0.06, 0.12), "neck": (0, 0.21, -0.03),
                 "left_collar": (0.08, 0.11, -0.01), "head": (0, 0.09, 0.05), "left_shoulder": (0.12, 0.05, 0),
                 "left_elbow": (0.26, 0, 0), "left_wrist": (0.25, 0, 0), "left_hand": (0.08, 0, 0)}


def smpl_rig():
    """SMPL's 24 joints in metres (offsets near the neutral template)."""
    out = []
    for n, p in zip(SMPL_NAMES, SMPL_PARENTS):
        o = _SMPL_OFFSETS.get(n) or _SMPL_OFFSETS[n.replace("right", "left")]
        if n.startswith("right"):
            o = (-o[0], o[1], o[2])
        out.append((n, None if p < 0 else SMPL_NAMES[p], o))
    return out


LAFAN1 = [("Hips", None), ("LeftUpLeg", "Hips"), ("LeftLeg", "LeftUpLeg"), ("LeftFoot", "LeftLeg"),
          ("LeftToe", "LeftFoot"), ("RightUpLeg", "Hips"), ("RightLeg", "RightUpLeg"), ("RightFoot", "RightLeg"),
          ("RightToe", "RightFoot"), ("Spine", "Hips"), ("Spine1", "Spine"), ("Spine2", "Spine1"),
          ("Neck", "Spine2"), ("Head", "Neck"), ("LeftShoulder", "Spine2"), ("LeftArm", "LeftShoulder"),
          ("LeftForeArm", "LeftArm"), ("LeftHand", "LeftForeArm"), ("RightShoulder", "Spine2"),
          ("RightArm", "RightShoulder"), ("RightForeArm", "RightArm"), ("RightHand", "RightForeArm")]
BANDAI = [("joint_Root", None), ("Hips", "joint_Root"), ("Spine", "Hips"), ("Chest", "Spine"), ("Neck", "Chest"),
          ("Head", "Neck"), ("Shoulder_L", "Chest"), ("UpperArm_L", "Shoulder_L"), ("LowerArm_L", "UpperArm_L"),
          ("Hand_L", "LowerArm_L"), ("Shoulder_R", "Chest"), ("UpperArm_R", "Shoulder_R"),
          ("LowerArm_R", "UpperArm_R"), ("Hand_R", "LowerArm_R"), ("UpperLeg_L", "Hips"), ("LowerLeg_L", "UpperLeg_L"),
          ("Foot_L", "LowerLeg_L"), ("Toes_L", "Foot_L"), ("UpperLeg_R", "Hips"), ("LowerLeg_R", "UpperLeg_R"),
          ("Foot_R", "LowerLeg_R"), ("Toes_R", "Foot_R")]
HOLDEN21 = ["Hips", "LeftUpLeg", "LeftLeg", "LeftFoot", "LeftToeBase", "RightUpLeg", "RightLeg", "RightFoot",
            "RightToeBase", "Spine", "Spine1", "Neck1", "Head", "LeftArm", "LeftForeArm", "LeftHand",
            "LeftHandIndex1", "RightArm", "RightForeArm", "RightHand", "RightHandIndex1"]
HOLDEN21_PARENTS = [-1, 0, 1, 2, 3, 0, 5, 6, 7, 0, 9, 10, 11, 10, 13, 14, 15, 10, 17, 18, 19]


def names_parents(rig):
    names = [r[0] for r in rig]
    return names, [-1 if r[1] is None else names.index(r[1]) for r in rig]


def skeleton_of(rig, k=1.0):
    names, parents = names_parents(rig)
    return Skeleton(names, parents, np.array([r[2] for r in rig], float) * k)


def expected(pelvis, chest, neck, head, hip, knee, foot, toe, shoulder, elbow, hand, sides=("Left", "Right")):
    """Roles from name templates such as ``"{Side}UpLeg"``."""
    out = {"pelvis": pelvis, "chest": chest, "neck": neck, "head": head}
    for role, t in zip(("hip", "knee", "foot", "toe", "shoulder", "elbow", "hand"),
                       (hip, knee, foot, toe, shoulder, elbow, hand)):
        for side, word in zip(("left", "right"), sides):
            out[f"{side}_{role}"] = t.format(Side=word, side=word)
    return {r: out[r] for r in ROLES}


CMU_ROLES = expected("Hips", "Spine1", "Neck", "Head", "{Side}UpLeg", "{Side}Leg", "{Side}Foot", "{Side}ToeBase",
                     "{Side}Arm", "{Side}ForeArm", "{Side}Hand")
MIXAMO_ROLES = {r: "mixamorig:" + n for r, n in expected(
    "Hips", "Spine2", "Neck", "Head", "{Side}UpLeg", "{Side}Leg", "{Side}Foot", "{Side}ToeBase", "{Side}Arm",
    "{Side}ForeArm", "{Side}Hand").items()}
SMPL_ROLES = expected("pelvis", "spine3", "neck", "head", "{side}_hip", "{side}_knee", "{side}_ankle", "{side}_foot",
                      "{side}_shoulder", "{side}_elbow", "{side}_wrist", sides=("left", "right"))


def motion(skel, frames, rng, hip_height):
    """Smooth random local rotations (F, J, 4) and a root walking along +Z (F, 3), in skel's units."""
    t = np.linspace(0, 1, frames)[:, None, None]
    a, b = rng.normal(0, 0.25, (2, 1, skel.n_joints, 3))
    q = Rotation.from_rotvec((a + t * b).reshape(-1, 3)).as_quat().reshape(frames, skel.n_joints, 4)
    root = np.stack([np.zeros(frames), np.full(frames, hip_height), np.linspace(0, hip_height, frames)], -1)
    return q, root


def write_rig(path, rig, rng, k=1.0, frames=12, file_scale=1.0, hip_height=None):
    """Write ``rig`` (offsets times ``k``, in the rig's units) as BVH, lengths times ``file_scale``."""
    skel = skeleton_of(rig, k)
    h = hip_height if hip_height is not None else -_rest(skel)[:, 1].min()
    q, root = motion(skel, frames, rng, h)
    write_bvh(path, skel, q, 1 / 120, root_pos=root, scale=file_scale)
    return path


def _rest(skel):
    pos = np.zeros((skel.n_joints, 3))
    for j, p in enumerate(skel.parents):
        pos[j] = skel.offsets[j] + (pos[p] if p >= 0 else 0)
    return pos - skel.offsets[0]


# ------------------------------------------------------------------ roles
@pytest.mark.parametrize("rig, roles, name", [
    (cmu_rig(), CMU_ROLES, "cmu"),
    (mixamo_rig(), MIXAMO_ROLES, "mixamo"),
    (smpl_rig(), SMPL_ROLES, "smpl"),
])
def test_guess_roles_of_common_rigs(rig, roles, name):
    names, parents = names_parents(rig)
    assert guess_roles(names, parents) == roles
    assert guess_roles(names) == roles  # names alone are enough for these
    assert detect_rig(names) == name
    assert missing_roles(guess_roles(names, parents)) == []


def test_mixamo_prefix_variants_and_lafan1_bandai_holden():
    for prefix in ("mixamorig1:", "mixamorig_", ""):
        names, parents = names_parents(mixamo_rig(prefix))
        assert guess_roles(names, parents) == {r: n.replace("mixamorig:", prefix) for r, n in MIXAMO_ROLES.items()}
        assert detect_rig(names) == "mixamo"
    names, parents = names_parents([(n, p, None) for n, p in LAFAN1])
    roles = guess_roles(names, parents)
    assert detect_rig(names) == "lafan1" and roles["left_toe"] == "LeftToe" and roles["chest"] == "Spine2"
    assert roles["left_shoulder"] == "LeftArm" and not missing_roles(roles)
    names, parents = names_parents([(n, p, None) for n, p in BANDAI])
    assert guess_roles(names, parents) == BANDAI_ROLES and detect_rig(names) == "bandai"
    roles = guess_roles(HOLDEN21, HOLDEN21_PARENTS)
    assert detect_rig(HOLDEN21) == "holden21" and not missing_roles(roles)
    assert roles["neck"] == "Neck1" and roles["chest"] == "Spine1" and roles["left_toe"] == "LeftToeBase"


def test_guess_reproduces_the_deepmimic_preset():
    s = load_sample().skeleton
    assert guess_roles(s.names, s.parents) == s.roles and detect_rig(s.names) == "deepmimic"


def test_smpl_traps_shoulder_wrist_ankle():
    roles = guess_roles(SMPL_NAMES, SMPL_PARENTS)
    # SMPL's "left_foot" is the toe joint, its "left_shoulder" the upper arm, its collar the clavicle
    assert roles["left_foot"] == "left_ankle" and roles["left_toe"] == "left_foot"
    assert roles["left_shoulder"] == "left_shoulder" and roles["left_hand"] == "left_wrist"
    assert "left_collar" not in roles.values()


def test_missing_roles_are_reported_and_errors_say_how_to_pass_them(tmp_path, rng):
    from posekit.ik.api import effector_set
    from posekit.transforms import to_root_space

    rig = [r for r in mixamo_rig("") if "Toe" not in r[0] and "Hand" not in r[0]]
    path = write_rig(tmp_path / "nohands.bvh", rig, rng, file_scale=1.0)
    m = read_bvh(path, scale=0.01)
    assert m.rig.missing == ("left_toe", "right_toe", "left_hand", "right_hand")
    assert "missing: " in m.rig.describe() and "roles=" in m.rig.describe()
    with pytest.raises(ValueError, match=r"role\(s\) left_hand, right_hand .*effector set '2'.*roles=\{'left_hand'"):
        effector_set(m.skeleton, "2", m.global_positions()[0])
    bare = Skeleton(["root", "a", "b"], [-1, 0, 1], np.ones((3, 3)))
    with pytest.raises(ValueError, match=r"left_hip, right_hip .*facing.*roles="):
        to_root_space(bare, np.zeros((3, 3)))
    # supplying the roles fixes it: by argument, or afterwards on the skeleton
    fixed = read_bvh(path, scale=0.01, roles={"left_hand": "LeftForeArm", "right_hand": "RightForeArm"})
    assert len(effector_set(fixed.skeleton, "2", fixed.global_positions()[0])) == 2
    assert m.skeleton.with_roles({"left_hand": "LeftForeArm"}).index("left_hand") == m.skeleton.index("LeftForeArm")


def test_unknown_role_joint_is_an_error(tmp_path, rng):
    path = write_rig(tmp_path / "smpl.bvh", smpl_rig(), rng)
    with pytest.raises(ValueError, match="roles name joints the file does not have"):
        read_bvh(path, roles={"head": "Kopf"})


# ------------------------------------------------------------------ units
@pytest.mark.parametrize("file_scale, unit", [(1.0, "m"), (100.0, "cm"), (1000.0, "mm"), (1 / 0.0254, "inch")])
def test_units_detected_from_standing_height(tmp_path, rng, file_scale, unit):
    path = write_rig(tmp_path / f"smpl_{unit}.bvh", smpl_rig(), rng, file_scale=file_scale)
    truth = read_bvh(path, scale=1 / file_scale).global_positions()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = read_bvh(path, scale=None)
    assert m.units.unit == unit and m.units.scale == pytest.approx(1 / file_scale, rel=0.02)
    assert 1.45 < m.units.height < 1.65
    np.testing.assert_allclose(m.global_positions(), truth, atol=0.02 * 1.6)
    assert bool([w for w in caught if "lengths look like" in str(w.message)]) == (unit != "m")


def test_cmu_units_make_a_person(tmp_path, rng):
    path = write_rig(tmp_path / "01_01.bvh", cmu_rig(), rng)
    raw = read_bvh(path)  # default scale 1: the file's numbers, ~23 units tall
    assert 20 < raw.units.file_height < 26 and raw.units.unit == "given" and raw.units.detected == "cmu"
    with pytest.warns(UserWarning, match=r"01_01.bvh: lengths look like cmu .*scale=\.\.\.") as caught:
        m = read_bvh(path, scale=None)
    assert not any("CMU_SCALE" in str(w.message) for w in caught)  # a person's words, not a Python constant
    assert m.units.scale == CMU_SCALE and 1.5 < m.units.height < 2.0
    np.testing.assert_allclose(m.skeleton.offsets, raw.skeleton.offsets * CMU_SCALE)
    assert guess_units(23.0, scale=0.056444).scale == 0.056444  # an explicit scale wins


def test_unit_guess_bounds():
    assert guess_units(160).unit == "cm" and guess_units(63).unit == "inch" and guess_units(1600).unit == "mm"
    assert guess_units(1.7).unit == "m" and guess_units(20).unit == "cmu"
    nothing = guess_units(1e7)
    assert nothing.unit == "unknown" and nothing.scale == 1.0
    assert standing_height(["a"], [-1], np.zeros((1, 3))) == 0.0


def test_heights_of_each_dialect():
    for rig, lo, hi in ((cmu_rig(), 20, 26), (mixamo_rig(), 150, 165), (smpl_rig(), 1.45, 1.65)):
        names, parents = names_parents(rig)
        s = skeleton_of(rig)
        assert lo < standing_height(names, parents, s.offsets) < hi


# ------------------------------------------------------------------ folders of subjects
def test_cmu_subjects_with_different_offsets_load_with_per_clip_offsets(tmp_path, rng):
    folder = tmp_path / "cmu"
    folder.mkdir()
    a = write_rig(folder / "01_01.bvh", cmu_rig(), rng, k=1.0, frames=10)
    b = write_rig(folder / "02_01.bvh", cmu_rig(), rng, k=1.12, frames=7)
    with pytest.warns(UserWarning, match="cmu"):
        ms = open_dataset(folder)
    assert ms.n_clips == 2 and ms.local_pos is not None and ms.units.unit == "cmu" and ms.rig.rig == "cmu"
    assert ms.skeleton.roles == CMU_ROLES
    np.testing.assert_allclose(ms.skeleton.offsets, read_bvh(a, scale=CMU_SCALE).skeleton.offsets)
    for c, p in enumerate((a, b)):
        own = read_bvh(p, scale=CMU_SCALE)
        np.testing.assert_allclose(ms.global_pos[ms.clip_frames(c)], own.global_positions(), atol=1e-9)
    # the second subject really is bigger: its clip's bones are 12 % longer
    f1, f2 = ms.clip_frames(0)[0], ms.clip_frames(1)[0]
    leg = lambda f: np.linalg.norm(ms.global_pos[f, ms.skeleton.index("left_knee")]
                                   - ms.global_pos[f, ms.skeleton.index("left_foot")])
    assert leg(f2) / leg(f1) == pytest.approx(1.12, rel=1e-6)
    assert 1.5 < ms.units.height < 2.0


def test_cli_inspect_reports_rig_units_and_roles(tmp_path, rng, capsys):
    from posekit.cli import main

    path = write_rig(tmp_path / "take.bvh", mixamo_rig(), rng)  # written in the rig's units: cm
    with pytest.warns(UserWarning, match="cm"):
        assert main(["data", "inspect", str(path), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["rig"] == "mixamo" and info["missing_roles"] == [] and info["unit"] == "cm"
    assert info["scale"] == 0.01 and 1.5 < info["height_m"] < 1.7
    assert info["roles"]["left_shoulder"] == "mixamorig:LeftArm"
    assert main(["data", "inspect", str(path), "--scale", "0.02"]) == 0
    out = capsys.readouterr().out
    assert "rig         mixamo" in out and "given" in out and "scale 0.02" in out
    assert "left_shoulder" in out and "all 18 roles" in out


def test_rig_report_for_a_skeleton_without_roles():
    r = rig_report(["root", "a"], {})
    assert r.rig == "unknown" and len(r.missing) == len(ROLES) and "roles=" in r.describe()
