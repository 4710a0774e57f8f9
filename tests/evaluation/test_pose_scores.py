"""Scoring a method's poses (posekit.evaluation.pose_scores): effector errors measured on the returned pose."""

import numpy as np
import pytest

from posekit.data.cases import build_cases
from posekit.evaluation.pose_scores import case_effector_errors, score_poses
from posekit.ik.api import Effector, effector_set
from posekit.kinematics import fk


def test_effector_errors_measure_the_pose(mini):
    s = mini.skeleton
    pose, q = mini.global_pos[3], mini.local_rot[3]
    effs = effector_set(s, "5", pose)
    p, a, conv = case_effector_errors(s, effs, pose + [0.0, 0.0, 0.0])
    assert p.shape == (5,) and np.all(p == 0) and a.shape == (0,) and conv
    moved = pose.copy()
    moved[s.index("head")] += [0, 0, 0.004]
    p, _, conv = case_effector_errors(s, effs, moved)
    assert p.max() == pytest.approx(0.004) and not conv  # 4 mm against the 1 mm tolerance
    G = fk(s, q)[1]
    head = s.index("head")
    look = Effector(head, pose[head] + G[head] @ np.array([0.0, 0.0, 1.0]), kind="look_at")
    p, a, conv = case_effector_errors(s, [look], pose, q)
    assert p.shape == (0,) and a[0] == pytest.approx(0, abs=1e-6) and conv
    turn = Effector(head, G[head], kind="rotation", tolerance=np.radians(1))
    assert case_effector_errors(s, [turn], pose, q)[1][0] == pytest.approx(0, abs=1e-6)
    p, a, conv = case_effector_errors(s, [effs[0], look], pose)  # no rotations: no angle, not converged
    assert p.shape == (1,) and np.isnan(a[0]) and not conv


def test_a_bad_rotation_target_is_refused_with_the_joint_named(mini):
    s = mini.skeleton
    pose, q = mini.global_pos[3], mini.local_rot[3]
    with pytest.raises(ValueError, match="rotation effector on Head: rotation target is not a rotation matrix"):
        case_effector_errors(s, [Effector("head", np.ones((3, 3)), kind="rotation")], pose, q)


def test_score_poses_counts_a_case_converged_only_when_every_effector_is_met(mini):
    cases = build_cases(mini, n_cases=6, start="other-clip", seed=0)
    s = cases.skeleton
    effs = [effector_set(s, "5", cases.target_pos[i]) for i in range(len(cases))]
    exact = score_poses(cases, cases.target_pos, effs)
    assert exact.converged.all() and np.all(exact.effector_mm == 0) and np.allclose(exact.mpjpe_mm, 0)
    off = cases.target_pos.copy()
    off[2, s.index("left_hand")] += [0.0, 0.002, 0.0]
    sc = score_poses(cases, off, effs)
    assert list(sc.converged) == [True, True, False, True, True, True]
    assert sc.effector_mm[2] == pytest.approx(2.0)
    assert sc.summary()["converged_fraction"] == pytest.approx(5 / 6)


def test_the_angular_median_is_over_the_cases_that_hold_an_angular_effector(mini):
    # lesson 05's random effectors: some cases hold positions only; their worst angular error does not exist
    s = mini.skeleton
    cases = build_cases(mini, n_cases=3, seed=0, start="rest")
    G = [fk(s, cases.target_rot[i], cases.target_root[i])[1] for i in range(3)]
    head = s.index("head")
    effs = [effector_set(s, "2", cases.target_pos[i]) for i in range(3)]
    for i, angle in ((1, 2.0), (2, 4.0)):  # a rotation target turned by 2 and 4 degrees about the vertical
        c, sn = np.cos(np.radians(angle)), np.sin(np.radians(angle))
        effs[i].append(Effector(head, np.array([[c, 0, sn], [0, 1, 0], [-sn, 0, c]]) @ G[i][head], kind="rotation"))
    summary = score_poses(cases, cases.target_pos, effs, cases.target_rot).summary()
    assert summary["effector_error_deg_median"] == pytest.approx(3.0, abs=1e-6)  # (2 + 4) / 2, not NaN
    assert "effector_error_deg_median" not in score_poses(cases, cases.target_pos, effs).summary()  # no rotations
