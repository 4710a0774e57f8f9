"""The Bandai Namco Research Motion Datasets 1 and 2 (Kobayashi et al. 2023, arXiv 2306.08861): where they
live and how their joints are named.

Read by path from ``$POSEKIT_DATA_DIR`` (:func:`posekit.paths.require_shared_data`) and never copied
(CC BY-NC 4.0, Bandai Namco Research Inc.): whole sets by :func:`posekit.data.load_bandai`, lesson 03's
full-scale protocols by :mod:`posekit.data.bandai_full`, and the small set shipped with posekit by
:mod:`posekit.data.bandai_mini`.
"""

from __future__ import annotations

__all__ = ["BANDAI_FOLDERS", "BANDAI_ROLES"]

BANDAI_FOLDERS = {"bandai1": "bandai-namco-1", "bandai2": "bandai-namco-2-every4th"}

BANDAI_ROLES = {
    "pelvis": "Hips", "chest": "Chest", "neck": "Neck", "head": "Head",
    "left_hip": "UpperLeg_L", "left_knee": "LowerLeg_L", "left_foot": "Foot_L", "left_toe": "Toes_L",
    "right_hip": "UpperLeg_R", "right_knee": "LowerLeg_R", "right_foot": "Foot_R", "right_toe": "Toes_R",
    "left_shoulder": "UpperArm_L", "left_elbow": "LowerArm_L", "left_hand": "Hand_L",
    "right_shoulder": "UpperArm_R", "right_elbow": "LowerArm_R", "right_hand": "Hand_R",
}
