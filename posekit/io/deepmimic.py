"""Convert the DeepMimic humanoid clips carried by pybullet's wheel into posekit arrays.

Used only by ``posekit data build-sample`` (which needs the optional ``build-data`` extra, i.e.
pybullet); at run time the lessons read the converted file in ``data_samples/``.

Source format (Peng et al. 2018, "DeepMimic", motion files ``humanoid3d_*.txt``): each frame is
``[duration, root xyz, root quat, chest quat, neck quat, right hip quat, right knee angle,
right ankle quat, right shoulder quat, right elbow angle, left hip quat, left knee angle,
left ankle quat, left shoulder quat, left elbow angle]`` — 44 numbers, quaternions scalar-first
``(w, x, y, z)``, knee/elbow angles in radians about the joint's z axis, Y up, the character
facing +X. The skeleton comes from ``humanoid/humanoid.urdf``, whose lengths are 4x the motion's
(pybullet's DeepMimic environment loads it with ``globalScaling=0.25``).

The conversion turns the world by -90 degrees about Y so that the character faces +Z
(:mod:`posekit.conventions`): offsets, root positions and every local rotation are conjugated by
that turn, which turns all FK positions by it.
"""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ..kinematics import fk
from ..skeleton import Skeleton

__all__ = ["CLIPS", "deepmimic_skeleton", "read_deepmimic_motion", "URDF_SCALE"]

URDF_SCALE = 0.25
"""Metres per URDF unit for pybullet's DeepMimic humanoid."""

CLIPS = ("walk", "run", "jump", "kick", "punch", "spin", "spinkick", "cartwheel", "crawl", "roll",
         "backflip", "dance_a", "dance_b", "getup_facedown", "getup_faceup")

# posekit joint order: (name, parent name, URDF joint it comes from or None for an added end point)
_JOINTS = [  # depth-first, the order a BVH file would list them
    ("root", None, "root"), ("chest", "root", "chest"), ("neck", "chest", "neck"), ("head", "neck", None),
    ("right_shoulder", "chest", "right_shoulder"), ("right_elbow", "right_shoulder", "right_elbow"),
    ("right_wrist", "right_elbow", "right_wrist"),
    ("left_shoulder", "chest", "left_shoulder"), ("left_elbow", "left_shoulder", "left_elbow"),
    ("left_wrist", "left_elbow", "left_wrist"),
    ("right_hip", "root", "right_hip"), ("right_knee", "right_hip", "right_knee"),
    ("right_ankle", "right_knee", "right_ankle"), ("right_toe", "right_ankle", None),
    ("left_hip", "root", "left_hip"), ("left_knee", "left_hip", "left_knee"),
    ("left_ankle", "left_knee", "left_ankle"), ("left_toe", "left_ankle", None),
]
# end points placed from the URDF collision shapes (URDF units): head = centre of the neck link's
# sphere; toe = front of the sole of the ankle link's box (centre 0.18,-0.09,0; size 0.708,0.22,0.36)
_END_POINTS = {"head": (0.0, 0.7, 0.0), "right_toe": (0.534, -0.2, 0.0), "left_toe": (0.534, -0.2, 0.0)}

# motion-file layout after the duration: (joint, kind) with kind 'pos', 'quat' or 'angle'
_LAYOUT = [("root", "pos"), ("root", "quat"), ("chest", "quat"), ("neck", "quat"),
           ("right_hip", "quat"), ("right_knee", "angle"), ("right_ankle", "quat"),
           ("right_shoulder", "quat"), ("right_elbow", "angle"),
           ("left_hip", "quat"), ("left_knee", "angle"), ("left_ankle", "quat"),
           ("left_shoulder", "quat"), ("left_elbow", "angle")]

ROLES = {
    "pelvis": "root", "chest": "chest", "neck": "neck", "head": "head",
    "left_hip": "left_hip", "left_knee": "left_knee", "left_foot": "left_ankle", "left_toe": "left_toe",
    "right_hip": "right_hip", "right_knee": "right_knee", "right_foot": "right_ankle", "right_toe": "right_toe",
    "left_shoulder": "left_shoulder", "left_elbow": "left_elbow", "left_hand": "left_wrist",
    "right_shoulder": "right_shoulder", "right_elbow": "right_elbow", "right_hand": "right_wrist",
}

TURN = Rotation.from_euler("y", -90, degrees=True)
"""World turn applied during conversion: DeepMimic faces +X, posekit faces +Z."""


def _parse_urdf(path: Path) -> dict:
    text = Path(path).read_text(encoding="utf-8", errors="replace").replace("\x00", "")
    root = ET.fromstring(text.strip())
    joints = {}
    for j in root.findall("joint"):
        origin = j.find("origin")
        xyz = [float(v) for v in re.split(r"\s+", origin.get("xyz").strip())] if origin is not None else [0, 0, 0]
        axis = j.find("axis")
        joints[j.get("name")] = {
            "type": j.get("type"),
            "parent": j.find("parent").get("link"),
            "xyz": np.array(xyz),
            "axis": np.array([float(v) for v in axis.get("xyz").split()]) if axis is not None else None,
        }
    return joints


def deepmimic_skeleton(urdf_path) -> tuple[Skeleton, dict]:
    """The posekit skeleton (18 joints, metres, facing +Z) and the hinge axes of knees and elbows.

    Returns
    -------
    skeleton : Skeleton
    hinge_axes : dict
        Joint name -> (3,) hinge axis in the joint's own frame, before the world turn.
    """
    urdf = _parse_urdf(urdf_path)
    names = [n for n, _, _ in _JOINTS]
    parents, offsets, hinges = [], [], {}
    for name, parent, src in _JOINTS:
        parents.append(-1 if parent is None else names.index(parent))
        if src is None:
            off = np.array(_END_POINTS[name])
        else:
            if src not in urdf:
                raise ValueError(f"{urdf_path}: joint {src!r} not found in the URDF")
            off = urdf[src]["xyz"]
            if urdf[src]["type"] == "revolute":
                hinges[name] = urdf[src]["axis"]
        offsets.append(TURN.apply(off * URDF_SCALE))
    skel = Skeleton(names, parents, np.array(offsets), roles=ROLES, name="deepmimic")
    return skel, hinges


def read_deepmimic_motion(motion_path, skeleton: Skeleton, hinge_axes: dict):
    """Read one ``humanoid3d_*.txt`` clip.

    Returns
    -------
    local_rot : ndarray, shape (F, 18, 4)
        Local quaternions ``(x, y, z, w)`` in posekit's frame (end points get the identity).
    root_pos : ndarray, shape (F, 3), metres
    frame_time : float
        Median frame duration in seconds.
    """
    motion_path = Path(motion_path)
    data = json.loads(motion_path.read_text())
    frames = np.asarray(data["Frames"], dtype=float)
    if frames.ndim != 2 or frames.shape[1] != 44:
        raise ValueError(f"{motion_path}: expected frames of 44 numbers, got shape {frames.shape}")
    F = frames.shape[0]
    local = {n: np.tile([0.0, 0.0, 0.0, 1.0], (F, 1)) for n in skeleton.names}
    root_pos = None
    col = 1
    for joint, kind in _LAYOUT:
        if kind == "pos":
            root_pos = frames[:, col:col + 3]
            col += 3
        elif kind == "quat":
            wxyz = frames[:, col:col + 4]
            local[joint] = wxyz[:, [1, 2, 3, 0]]
            col += 4
        else:
            local[joint] = Rotation.from_rotvec(frames[:, col:col + 1] * hinge_axes[joint]).as_quat()
            col += 1
    # conjugate by the world turn: q' = T q T^-1, p' = T p
    local_rot = np.stack([(TURN * Rotation.from_quat(local[n]) * TURN.inv()).as_quat() for n in skeleton.names], 1)
    local_rot = np.where(local_rot[..., 3:4] < 0, -local_rot, local_rot)
    root_pos = TURN.apply(root_pos)
    frame_time = float(np.median(frames[:, 0]))
    return local_rot, root_pos, frame_time


def build_arrays(pybullet_data_dir) -> dict:
    """Convert all 15 clips; returns the arrays saved in ``data_samples/deepmimic_humanoid.npz``."""
    base = Path(pybullet_data_dir)
    skel, hinges = deepmimic_skeleton(base / "humanoid" / "humanoid.urdf")
    rots, roots, ids, times = [], [], [], []
    for c, clip in enumerate(CLIPS):
        lr, rp, ft = read_deepmimic_motion(base / "data" / "motions" / f"humanoid3d_{clip}.txt", skel, hinges)
        rots.append(lr)
        roots.append(rp)
        ids.append(np.full(len(lr), c))
        times.append(ft)
    local_rot = np.concatenate(rots)
    root_pos = np.concatenate(roots)
    global_pos = fk(skel, local_rot, root_pos)[0]
    return {
        **skel.to_arrays(),
        "local_rot": local_rot.astype(np.float32),
        "root_pos": root_pos.astype(np.float32),
        "global_pos": global_pos.astype(np.float32),
        "clip_id": np.concatenate(ids).astype(np.int16),
        "clip_names": np.array(CLIPS, dtype=str),
        "frame_time": np.array(times),
    }
