"""The hand-written baseline: a retargeting script that reads rig controls off joint positions.

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb`` as the first row of the Table 1 comparison
(Holden, Saito & Komura 2017 compare against such a script). It copies what can be read directly —
the IK handles are the wrist and ankle positions, the COG position is the pelvis — and estimates
the rest with simple geometry, putting the whole forward lean in ``root_pitch`` and leaving the
swivels, side bend and twist at zero: it knows nothing about how animators split a pose between
redundant controls.
"""

from __future__ import annotations

import numpy as np

from ..transforms import facing_angle
from .humanoid import HumanoidRig

__all__ = ["heuristic_inverse"]


def _angle_in_plane(v, fwd):
    """Forward lean of direction v (N, 3) from vertical, in the plane of the facing direction."""
    return np.arctan2(np.sum(v * fwd, axis=1), v[:, 1])


def heuristic_inverse(rig: HumanoidRig, positions) -> np.ndarray:
    """Estimate controls from joint positions (N, J, 3) -> (N, C)."""
    x = np.asarray(positions, dtype=float)
    s = rig.skeleton
    if x.ndim != 3 or x.shape[1:] != (s.n_joints, 3):
        raise ValueError(f"positions: expected shape (N, {s.n_joints}, 3), got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError("positions contain NaN or inf")
    N = len(x)
    y = np.tile(rig.default(), (N, 1))
    i, j = rig.index, s.index
    pelvis = x[:, j("pelvis")]
    y[:, i("root_tx")], y[:, i("root_tz")] = pelvis[:, 0], pelvis[:, 2]
    y[:, i("root_ty")] = pelvis[:, 1] - rig.rest_pelvis_height
    yaw = facing_angle(s, x)
    y[:, i("root_yaw")] = yaw
    fwd = np.stack([np.sin(yaw), np.zeros(N), np.cos(yaw)], 1)
    hips = x[:, j("left_hip")] - x[:, j("right_hip")]
    y[:, i("root_roll")] = -np.arctan2(hips[:, 1], np.linalg.norm(hips[:, [0, 2]], axis=1))
    lower = _angle_in_plane(x[:, j("chest")] - pelvis, fwd)
    upper = _angle_in_plane(x[:, j("neck")] - x[:, j("chest")], fwd)
    y[:, i("root_pitch")] = lower
    y[:, i("spine_lower_bend")] = 0.0
    y[:, i("spine_upper_bend")] = upper - lower
    y[:, i("neck_nod")] = _angle_in_plane(x[:, j("head")] - x[:, j("neck")], fwd) - upper
    for side, full in (("l", "left"), ("r", "right")):
        y[:, [i(f"{side}_hand_{a}") for a in "xyz"]] = x[:, j(f"{full}_hand")]
        y[:, [i(f"{side}_foot_{a}") for a in "xyz"]] = x[:, j(f"{full}_foot")]
        toe = x[:, j(f"{full}_toe")] - x[:, j(f"{full}_foot")]
        rest = rig.skeleton.offsets[j(f"{full}_toe")]
        y[:, i(f"{side}_foot_pitch")] = (np.arctan2(-toe[:, 1], np.sum(toe * fwd, axis=1))
                                         - np.arctan2(-rest[1], rest[2]))
    return np.clip(y, rig.low, rig.high)
