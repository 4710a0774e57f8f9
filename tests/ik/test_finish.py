"""A learned pose with an exact finish (posekit.ik.finish): the learned solver, then DLS from its pose."""

import numpy as np
import pytest

from posekit.data.cases import build_cases
from posekit.ik import Effector, effector_set, make_solver, solver_info, solver_names
from posekit.ik.finish import FINISHED, JUDGE_POSES, finished_name, judge_for


@pytest.fixture(scope="module")
def cases(mini):
    return build_cases(mini, n_cases=12, seed=3, start="other-clip")


def test_every_learned_solver_has_a_finished_twin_for_every_kind():
    for learned in FINISHED:
        name = finished_name(learned)
        assert name in solver_names()
        info = solver_info(name)
        assert set(info.kinds) == {"position", "rotation", "look_at"}
        assert info.needs_start == solver_info(learned).needs_start


@pytest.mark.parametrize("learned", FINISHED)
def test_the_finish_meets_every_effector_the_learned_pose_misses(learned, cases):
    s = cases.skeleton
    solver, raw = make_solver(finished_name(learned), s), make_solver(learned, s)
    met = 0
    for i in range(len(cases)):
        effs = effector_set(s, "5", cases.target_pos[i])
        start = cases.pose(i) if raw.needs_start else None
        r, r0 = solver.solve(cases.pose(i), effs), raw.solve(start, effs)
        assert np.all(np.isfinite(r.pose.global_pos)) and r.pose.local_rot is not None
        assert r.effector_error.max() <= r0.effector_error.max() + 1e-12  # never worse than the learned pose
        assert {"learned_ms", "finish_ms", "learned_converged", "finish_iterations"} <= set(r.info)
        met += r.converged
    assert met == len(cases)


def test_rotation_and_look_at_effectors_are_met_after_a_positions_only_learned_solver(cases):
    s = cases.skeleton
    solver = make_solver("neural+dls", s)
    true = cases.target_pos[0]
    from posekit.kinematics import fk

    G = fk(s, cases.target_rot[0], cases.target_root[0], cases.target_local_pos[0]
           if cases.target_local_pos is not None else None)[1]  # the true pose's world rotations
    effs = effector_set(s, "2", true)
    head = s.index("head")
    effs.append(Effector("head", true[head] + np.array([0.0, 0.0, 1.0]), kind="look_at"))
    effs.append(Effector("left_hand", G[s.index("left_hand")], kind="rotation"))
    r = solver.solve(cases.pose(0), effs)
    assert r.converged and r.kinds == ("position", "position", "look_at", "rotation")


@pytest.mark.parametrize("learned", ["protores", "latent-opt"])
def test_a_pelvis_target_is_met_from_the_learned_pose_not_only_from_the_start(learned, cases):
    # lesson 05's random effectors always hold a position on a joint of the hips zone (the pelvis); DLS keeps
    # its base joint in place, so the finish must first move the learned pose onto that target
    from posekit.bench.ik import case_effectors

    s = cases.skeleton
    solver = make_solver(finished_name(learned), s, choose="learned")  # the start's answer only when stuck
    effs = case_effectors(cases, "random")
    pelvis = s.names[s.pelvis()]
    finished = 0
    for i in range(len(cases)):
        assert any(e.joint == pelvis and e.kind == "position" for e in effs[i])
        r = solver.solve(cases.pose(i), effs[i])
        assert r.converged
        finished += r.info.get("kept") is None  # met from the learned pose, not by the fallback from the start
    assert finished >= len(cases) - 1


@pytest.mark.parametrize("name", ["fabrik", "ccd", "dls"])
def test_a_position_effector_on_the_base_moves_the_start_onto_it(name, cases):
    s = cases.skeleton
    pelvis, hand = s.pelvis(), s.index("left_hand")
    start = cases.pose(0)
    goal = start.global_pos[pelvis] + np.array([0.3, -0.05, 0.2])
    reach = cases.target_pos[0][hand] - cases.target_pos[0][pelvis] + goal  # the true hand, relative to the new pelvis
    effs = [Effector(s.names[pelvis], goal), Effector("left_hand", reach)]
    r = make_solver(name, s).solve(start, effs)
    assert np.linalg.norm(r.pose.global_pos[pelvis] - goal) < 1e-9  # met exactly: the body moved as a whole
    assert r.effector_error[0] < 1e-9 and np.all(np.isfinite(r.pose.global_pos))
    if r.pose.local_rot is not None:
        from posekit.kinematics import fk

        assert np.allclose(fk(s, r.pose.local_rot, r.pose.root_pos, r.pose.local_pos)[0], r.pose.global_pos)
    assert np.allclose(start.global_pos[pelvis], cases.pose(0).global_pos[pelvis])  # the caller's start is untouched


def test_unreachable_targets_give_the_best_pose_found_never_nan(cases):
    s = cases.skeleton
    solver = make_solver("protores+dls", s)
    far = [Effector("left_hand", [30.0, 1.0, 0.0]), Effector("right_hand", [-30.0, 1.0, 0.0])]
    r = solver.solve(cases.pose(0), far)
    assert not r.converged and np.all(np.isfinite(r.pose.global_pos))
    raw = make_solver("protores", s).solve(None, far)
    assert r.effector_error.max() <= raw.effector_error.max() + 1e-12


def test_one_pose_rotations_are_the_batched_ones(mini):
    """rotations_from_positions for one pose (the finish's compiled path) equals the numpy path of a batch."""
    from posekit.ik.bone_rotations import rotations_from_positions
    from posekit.rotations import quat_to_matrix

    s = mini.skeleton
    for i in (0, 500, 1500):
        L0 = quat_to_matrix(mini.local_rot[i])[None]
        P = mini.global_pos[[i + 40]]
        one = rotations_from_positions(s, L0, P[:, 0], P)[0]
        two = rotations_from_positions(s, np.concatenate([L0, L0]), np.concatenate([P[:, 0]] * 2),
                                       np.concatenate([P, P]))[0]
        np.testing.assert_allclose(one[0], two[0], atol=1e-12)


def test_a_finish_whose_learned_stage_refuses_says_whose_refusal_and_what_answers(cases):
    """lesson 03's networks exist for fixed joint sets only: a mixed set (positions on a foot, an upper arm and the
    pelvis) has no learned pose to finish, and the refusal names the stage, the sets and the solvers that answer."""
    s = cases.skeleton
    true = cases.target_pos[0]
    effs = [Effector(j, true[s.index(j)]) for j in ("Foot_L", "UpperArm_R", "Hips")]
    with pytest.raises(ValueError) as err:
        make_solver("neural+dls", s).solve(cases.pose(0), effs)
    msg = str(err.value)
    assert msg.startswith("neural+dls: its learned stage 'neural' cannot read these effectors")
    assert "hands: left_hand, right_hand" in msg and "Foot_L, UpperArm_R, Hips" in msg
    assert "'dls' alone" in msg and "'protores+dls'" in msg and "'latent-opt+dls'" in msg



@pytest.mark.parametrize("learned", FINISHED)
def test_of_two_exact_answers_the_more_natural_is_kept(learned, cases):
    """choose="natural" (the default): DLS from the learned pose and DLS from the start; when both meet every
    effector, the one nearer a training pose is returned, and info says both distances."""
    s = cases.skeleton
    solver = make_solver(finished_name(learned), s)
    assert solver.choose == "natural"
    learned_only = make_solver(finished_name(learned), s, choose="learned")
    judged = kept_start = 0
    for i in range(len(cases)):
        effs = effector_set(s, "5", cases.target_pos[i])
        r = solver.solve(cases.pose(i), effs)
        assert r.converged
        if "natural_mm" in r.info:
            judged += 1
            from_learned, from_start = r.info["natural_mm"]
            d = solver.judge.distance(r.pose.global_pos) * 1e3
            if r.info.get("kept") == "start":
                kept_start += 1
                assert from_start < from_learned and d == pytest.approx(from_start)
            else:
                assert from_learned <= from_start and d == pytest.approx(from_learned)
                # the answer from the learned pose is the one choose="learned" gives when it is not stuck there
                r2 = learned_only.solve(cases.pose(i), effs)
                if r2.info.get("kept") is None:
                    np.testing.assert_allclose(r.pose.global_pos, r2.pose.global_pos, atol=1e-12)
    # nearly always both are exact (else the exact one is kept, no judging); and both answers win somewhere
    assert judged >= len(cases) - 2 and 0 < kept_start < judged


def test_the_judge_knows_only_training_poses(mini):
    """The judge compares with frames of the learned solvers' training split: never a held-out pose (a case's
    true pose is not in it), and it refuses a skeleton its data was not recorded on."""
    s = mini.skeleton
    judge = judge_for("bandai-mini", s)
    assert len(judge) == JUDGE_POSES
    train = mini.global_pos[mini.split.train]
    np.testing.assert_allclose(judge.distance(train[judge.kept[:3]]), 0, atol=1e-9)
    test_cases = build_cases(mini, 30, seed=0, start="other-clip")
    assert np.all(judge.distance(test_cases.target_pos) > 1e-3)
    from posekit.data import load_sample

    other = load_sample().skeleton
    assert judge_for("bandai-mini", other) is None and judge_for(None, s) is None


def test_an_unknown_rule_is_refused(cases):
    with pytest.raises(ValueError, match="choose must be one of natural, learned"):
        make_solver("neural+dls", cases.skeleton, choose="best")


def test_the_judge_takes_the_training_poses_of_the_data_being_posed(mini):
    """Within judged_on(motions, frames) a finish judges against those frames (the data a benchmark's --data names),
    not its registered data's; outside, the registered data's judge is back."""
    from posekit.ik.finish import judged_on

    s = mini.skeleton
    frames = np.sort(mini.split.train)[:300]
    with judged_on(mini, frames):
        solver = make_solver("neural+dls", s)
    assert solver.choose == "natural" and solver.judged_on == mini.source and len(solver.judge) == 300
    np.testing.assert_allclose(solver.judge.distance(mini.global_pos[frames[:5]]), 0, atol=1e-9)
    outside = make_solver("neural+dls", s)
    assert outside.judged_on == "bandai-mini" and len(outside.judge) == JUDGE_POSES
