"""Benchmark plug-ins, held-out case generation and the shared pose metrics (``posekit bench ...``)."""

import json

import numpy as np
import pytest

from posekit.bench.plugin import arg, register_benchmark, unregister_benchmark
from posekit.cli import main
from posekit.data import MotionSet, split_by_clip
from posekit.data.cases import build_cases, case_split, placement_joints
from posekit.data.metrics import NaturalnessIndex, body_joints, bone_length_error, mpjpe, rotation_error
from posekit.ik import registry
from posekit.ik.api import IKResult
from posekit.kinematics import fk, rest_pose
from posekit.rotations import axis_angle_to_quat, quat_multiply
from posekit.transforms import to_root_space


def ensure_classical_solvers():
    """Until posekit.ik registers its solvers itself: register the classical ones that are missing
    (temporary, test setup only)."""
    from posekit.ik import CCDSolver, DLSSolver, FabrikSolver

    have = registry.solver_names()
    for name, factory, kw in (("fabrik", FabrikSolver, {}), ("fabrik-constrained", FabrikSolver, {"constraints": True}),
                              ("ccd", CCDSolver, {}), ("dls", DLSSolver, {})):
        if name not in have:
            registry.register(name, factory, **kw)


@pytest.fixture(scope="module")
def solvers():
    ensure_classical_solvers()


# ------------------------------------------------------------------------------- plug-in registry
def test_a_registered_benchmark_is_a_subcommand_with_tables_and_json(capsys):
    def toy(args):
        return [{"method": "a", "n": args.n, "value_mm": 1.5 * args.n}, {"method": "b", "n": args.n, "value_mm": 2.0}]

    register_benchmark("toy-bench", toy, help="a toy benchmark", args=[arg("--n", type=int, default=3, help="size")],
                       tables=[("Toy table", ["method", "n", "value_mm"])], labels={"value_mm": "value mm"})
    try:
        assert main(["bench", "toy-bench", "--n", "4"]) == 0
        out = capsys.readouterr().out.splitlines()
        assert out[0] == "Toy table" and out[1].split() == ["method", "n", "value", "mm"]
        assert out[3].split() == ["a", "4", "6"] and out[4].split() == ["b", "4", "2"]
        assert main(["bench", "toy-bench", "--json"]) == 0
        assert json.loads(capsys.readouterr().out) == toy(type("A", (), {"n": 3}))
        with pytest.raises(SystemExit):
            main(["bench", "toy-bench", "--help"])
        assert "size (default: 3)" in " ".join(capsys.readouterr().out.split())
        with pytest.raises(ValueError, match="already registered"):
            register_benchmark("toy-bench", toy)
    finally:
        unregister_benchmark("toy-bench")
    with pytest.raises(SystemExit):  # gone again
        main(["bench", "toy-bench"])


class _Stay:
    """A 'solver' that returns its start pose: its errors are the start's."""

    name = "test-stay"
    kinds = ("position",)
    needs_start = True

    def __init__(self, skeleton):
        self.skeleton = skeleton

    def solve(self, start, effectors):
        err = np.array([np.linalg.norm(start.global_pos[self.skeleton.index(e.joint)] - e.target) for e in effectors])
        return IKResult(start.copy(), False, 0, err)


def test_a_registered_solver_is_an_ik_benchmark_method(sample, capsys):
    registry.register("test-stay", _Stay, description="returns the start pose", replace=True)
    try:
        assert main(["bench", "ik", "--solvers", "test-stay", "--effectors", "2", "--cases", "12", "--methods", "none",
                     "--json"]) == 0
        (row,) = json.loads(capsys.readouterr().out)
        cases = build_cases(sample, 12)
        assert row["method"] == "test-stay" and row["start"] == "same-clip" and row["cases"] == 12
        # the benchmark measured the start poses themselves, with the shared metric code
        expect = np.median(mpjpe(sample.skeleton, cases.start_pos, cases.target_pos)) * 1e3
        assert row["mpjpe_mm_median"] == pytest.approx(expect) and row["mpjpe_mm_median"] > 10
        assert row["converged_fraction"] == 0 and "rotation_error_deg_median" in row  # the start has rotations
        from posekit.bench.ik import resolve_solvers

        assert "test-stay" in resolve_solvers("all")
    finally:
        registry.unregister("test-stay")


def test_unknown_names_are_refused(solvers):
    from posekit.bench.plugin import get_benchmark

    b = get_benchmark("ik")
    for argv, msg in ((["--solvers", "magic"], "unknown solver 'magic'"),
                      (["--effectors", "7"], "unknown effector set '7'"),
                      (["--start", "sideways"], "unknown start condition 'sideways'"),
                      (["--methods", "abacus"], "unknown ik method 'abacus'")):
        with pytest.raises(ValueError, match=msg):
            b.run(b.namespace(**{a.lstrip("-"): v for a, v in zip(argv[::2], argv[1::2])}, cases=5))


# ------------------------------------------------------------------------------- case generation
def _check_aligned_and_consistent(cases):
    s, pel = cases.skeleton, cases.skeleton.pelvis()
    np.testing.assert_allclose(cases.start_pos[:, pel], cases.target_pos[:, pel], atol=1e-12)
    np.testing.assert_allclose(fk(s, cases.start_rot, cases.start_root, cases.start_local_pos)[0], cases.start_pos,
                               atol=1e-6)
    np.testing.assert_allclose(fk(s, cases.target_rot, cases.target_root, cases.target_local_pos)[0], cases.target_pos,
                               atol=1e-6)
    # root frame: the target's pelvis is above the origin
    np.testing.assert_allclose(cases.target_pos[:, pel, [0, 2]], 0, atol=1e-9)


def test_cases_come_from_the_sets_own_test_split(mini):
    cases = build_cases(mini, 300, seed=0)
    test = set(mini.split.test)
    assert set(cases.target_frame) <= test and set(cases.start_frame) <= test
    np.testing.assert_array_equal(cases.train_frames, mini.split.train)
    assert "own split" in cases.split
    truth = to_root_space(mini.skeleton, mini.global_pos[cases.target_frame])[0]  # those frames, in their root frame
    np.testing.assert_allclose(cases.target_pos, truth, atol=1e-9)


def test_without_its_own_split_cases_use_the_clip_level_split(sample):
    cases = build_cases(sample, 100, seed=3)
    train, _, test = split_by_clip(sample, seed=3, fallback=True)
    assert set(cases.target_frame) <= set(test) and set(cases.start_frame) <= set(test)
    np.testing.assert_array_equal(cases.train_frames, train)


def test_same_clip_starts_are_another_frame_within_one_second(mini):
    cases = build_cases(mini, 300, seed=1, start="same-clip")
    a, b = cases.start_frame, cases.target_frame
    assert np.all(mini.clip_id[a] == mini.clip_id[b]) and np.all(a != b)
    gap_s = np.abs(a - b) * mini.frame_time[mini.clip_id[b]]
    assert gap_s.max() <= 1.0 + 1e-9 and gap_s.max() > 0.5  # the whole second is used
    _check_aligned_and_consistent(cases)
    old = build_cases(mini, 300, seed=1, start="frame")  # the earlier name is an alias
    np.testing.assert_array_equal(old.start_frame, a)
    assert old.start == "same-clip"


def test_other_clip_starts_are_from_another_held_out_clip_with_the_same_targets(mini):
    same = build_cases(mini, 300, seed=2, start="same-clip")
    other = build_cases(mini, 300, seed=2, start="other-clip")
    np.testing.assert_array_equal(other.target_frame, same.target_frame)
    assert np.all(mini.clip_id[other.start_frame] != mini.clip_id[other.target_frame])
    assert set(other.start_frame) <= set(mini.split.test)
    assert len(np.unique(mini.clip_id[other.start_frame])) > 5
    _check_aligned_and_consistent(other)


def test_rest_starts_are_the_rest_pose_when_it_stands(sample, mini):
    # DeepMimic's zero-rotation pose stands: it is the rest start
    cases = build_cases(sample, 50, seed=0, start="rest")
    s, pel = sample.skeleton, sample.skeleton.pelvis()
    np.testing.assert_array_equal(cases.start_rot, np.broadcast_to([0, 0, 0, 1.0], cases.start_rot.shape))
    rest = rest_pose(s)
    np.testing.assert_allclose(cases.start_pos - cases.start_pos[:, pel, None],
                               np.broadcast_to(rest - rest[pel], cases.start_pos.shape), atol=1e-12)
    assert np.all(cases.start_frame == -1)
    _check_aligned_and_consistent(cases)
    # Bandai's does not (its bones lie along +X): the rest start is the typical training pose, upright
    cases = build_cases(mini, 50, seed=0, start="rest")
    s, pel = mini.skeleton, mini.skeleton.pelvis()
    assert not np.allclose(cases.start_rot, [0, 0, 0, 1.0])
    assert np.all(cases.start_rot == cases.start_rot[:1])          # one start pose for every case
    p = cases.start_pos[0]
    assert p[s.index("head"), 1] - p[pel, 1] > 0.4 and p[pel, 1] - p[s.index("left_foot"), 1] > 0.6
    assert np.all(cases.start_frame == -1)
    _check_aligned_and_consistent(cases)


def _with_local_pos(ms, bump=None):
    """``ms`` with per-frame translations that equal the offsets except at the root (which moves)."""
    lp = np.broadcast_to(ms.skeleton.offsets, ms.local_rot.shape[:2] + (3,)).copy()
    lp[:, 0] = ms.root_pos
    if bump is not None:
        frames, joint, by = bump
        lp[frames, ms.skeleton.index(joint), 0] += by
    return MotionSet(ms.skeleton, ms.local_rot, ms.root_pos, ms.global_pos, ms.clip_id, ms.clip_names, ms.frame_time,
                     lp, ms.source)


def test_rest_is_allowed_when_only_the_placement_translates(sample):
    assert list(placement_joints(sample.skeleton)) == [0]
    cases = build_cases(_with_local_pos(sample), 20, start="rest")
    assert len(cases) == 20
    test = case_split(sample)[2]
    with pytest.raises(ValueError, match=r"translation of left_elbow differs by 1 mm"):
        build_cases(_with_local_pos(sample, (test[:3], "left_elbow", 1e-3)), 20, start="rest")
    # a bump outside the held-out frames does not matter
    train = case_split(sample)[0]
    assert len(build_cases(_with_local_pos(sample, (train[:3], "left_elbow", 1e-3)), 20, start="rest")) == 20


def test_start_conditions_that_cannot_work_are_refused(sample):
    with pytest.raises(ValueError, match="unknown start condition 'sideways'.*same-clip, other-clip, rest"):
        build_cases(sample, 5, start="sideways")
    one = sample.select(sample.clip_frames(2))
    with pytest.raises(ValueError, match="other-clip start .* needs at least two held-out clips"):
        with pytest.warns(UserWarning, match="too few for a clip-level split"):
            build_cases(one, 5, start="other-clip")


# ------------------------------------------------------------------------------- metrics
def test_body_joints_leave_out_a_root_that_only_places_the_body(mini, sample):
    assert mini.skeleton.names[0] == "joint_Root" and 0 not in body_joints(mini.skeleton)
    assert len(body_joints(mini.skeleton)) == 21
    assert list(body_joints(sample.skeleton)) == list(range(18))  # DeepMimic's root is the pelvis


def test_mpjpe_ignores_joint_root(mini):
    s = mini.skeleton
    truth = mini.global_pos[100]
    moved = truth.copy()
    moved[0] += [0.3, -0.5, 0.2]  # only joint_Root differs
    assert mpjpe(s, moved, truth) == 0
    hand = truth.copy()
    hand[s.index("left_hand")] += [0.0, 0.21, 0.0]
    assert mpjpe(s, hand, truth) == pytest.approx(0.21 / 21)
    # pelvis-relative: a pose carried 1 m away is the same pose
    assert mpjpe(s, truth + [1.0, 0, 0], truth) == pytest.approx(0, abs=1e-12)


def test_bone_length_error_of_a_stretched_pose(mini):
    s = mini.skeleton
    pose = mini.global_pos[7]
    assert bone_length_error(s, pose, pose) == 0
    hand = s.index("left_hand")
    forearm = pose[hand] - pose[s.parents[hand]]
    stretched = pose.copy()
    stretched[hand] += 0.03 * forearm / np.linalg.norm(forearm)  # the hand has no children on this skeleton
    assert bone_length_error(s, stretched, pose) == pytest.approx(0.03)
    placed = pose.copy()
    placed[0] += [0, -0.2, 0]  # joint_Root -> Hips is not a body bone
    assert bone_length_error(s, placed, pose) == 0


def test_rotation_error_is_the_mean_geodesic_over_body_joints(mini):
    s = mini.skeleton
    q = mini.local_rot[50]
    assert rotation_error(s, q, q) == pytest.approx(0, abs=1e-7)
    turned = q.copy()
    elbow = s.index("left_elbow")
    turned[elbow] = quat_multiply(q[elbow], axis_angle_to_quat([1.0, 0, 0], np.radians(30)))
    assert np.degrees(rotation_error(s, turned, q)) == pytest.approx(30 / 21, rel=1e-6)


def test_naturalness_is_zero_on_training_poses_and_the_floor_is_below_a_perturbed_pose(mini):
    train = mini.global_pos[mini.split.train]
    index = NaturalnessIndex(mini.skeleton, train, max_poses=3000, seed=0)
    assert len(index) == 3000 and np.array_equal(index.kept, NaturalnessIndex(mini.skeleton, train, 3000, 0).kept)
    np.testing.assert_allclose(index.distance(train[index.kept[:20]]), 0, atol=1e-9)
    # MPJPE-style: one of 21 body joints 21 cm off is at most 1 cm from its training pose
    one = train[index.kept[5]].copy()
    one[mini.skeleton.index("left_hand")] += [0, 0.21, 0]
    assert 0 < index.distance(one) <= 0.01 + 1e-9
    cases = build_cases(mini, 40, seed=0)
    floor = index.distance(cases.target_pos)
    noisy = cases.target_pos + np.random.default_rng(0).normal(0, 0.05, cases.target_pos.shape)
    assert np.all(index.distance(noisy) >= floor) and np.all(floor > 0)


def test_naturalness_small_queries_find_what_scikit_learn_finds(mini):
    """A query of a few poses (what an exact finish asks for each answer) skips scikit-learn and compares with
    every kept pose at once; it must return the same distances as the tree search."""
    train = mini.global_pos[mini.split.train]
    index = NaturalnessIndex(mini.skeleton, train, max_poses=2000, seed=0)
    cases = build_cases(mini, 60, seed=0)
    poses = cases.target_pos + np.random.default_rng(1).normal(0, 0.02, cases.target_pos.shape)
    big = index.distance(poses)  # 60 poses: scikit-learn
    assert len(poses) > index.BRUTE_MAX
    small = np.concatenate([index.distance(poses[i:i + 2]) for i in range(0, len(poses), 2)])
    np.testing.assert_allclose(small, big, rtol=1e-12, atol=1e-12)
    assert index.distance(poses[3]).shape == ()


# ------------------------------------------------------------------------------- the bandai-mini command
def test_bench_ik_on_bandai_mini_every_start_condition(solvers, capsys, monkeypatch):
    monkeypatch.setattr("posekit.bench.ik_methods.BATCH_SOLVES", 1000)  # throughput needs no 20,000 here
    argv = ["bench", "ik", "--solvers", "fabrik,ccd,dls", "--effectors", "2,5", "--start", "rest,same-clip,other-clip",
            "--data", "bandai-mini", "--cases", "20", "--no-peers"]
    assert main(argv + ["--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    solved = [r for r in rows if r["method"] in ("fabrik", "ccd", "dls")]
    assert {(r["method"], r["effectors"], r["start"]) for r in solved} == {
        (m, e, st) for m in ("fabrik", "ccd", "dls") for e in ("2", "5") for st in ("rest", "same-clip", "other-clip")}
    keys = {"latency_ms_median", "effector_error_mm_median", "mpjpe_mm_median", "bone_length_error_mm_max",
            "converged_fraction", "iterations_median", "memory_kb", "natural_mm_median", "natural_floor_mm_median"}
    floors = set()
    for r in solved:
        assert keys <= set(r) and r["cases"] == 20 and r["data"].startswith("bandai-mini")
        assert r["bone_length_error_mm_max"] < 1e-3 and r["natural_floor_mm_median"] > 0
        assert ("rotation_error_deg_median" in r) == (r["method"] != "fabrik")  # FABRIK returns positions only
        floors.add(round(r["natural_floor_mm_median"], 9))
        if r["method"] == "dls":
            assert r["converged_fraction"] >= 0.9
    assert len(floors) == 1  # the same targets under every start condition
    for st in ("rest", "same-clip", "other-clip"):
        for e in ("2", "5"):
            pick = lambda m: next(r for r in rows if r["method"] == m and r["effectors"] == e and r["start"] == st)
            baseline = pick("baseline: numpy per-joint FABRIK")["latency_ms_median"]
            assert pick("fabrik")["latency_ms_median"] <= 0.5 * baseline
            assert pick("fabrik batched")["solves_per_s"] > 0
    assert main(argv + ["--cases", "5", "--methods", "none"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert max(len(line) for line in lines) <= 100, max(lines, key=len)
    assert [line.split(" (")[0] for line in lines if line.startswith("Start: ")] == \
        ["Start: rest", "Start: same-clip", "Start: other-clip"]
    assert "natural mm" in out and "floor mm" in out and "rotation deg" in out


def test_review_edges_give_clear_answers(sample):
    # effector lists with spaces, a zero case count, an argparse-made default namespace
    from posekit.bench.ik import run
    from posekit.bench.plugin import get_benchmark

    rows = run(sample, solvers="fabrik", effector_sets="2, 5", n_cases=5, methods="none", natural=False)
    assert {r["effectors"] for r in rows if r["method"] == "fabrik"} == {"2", "5"}
    with pytest.raises(ValueError, match="at least 1"):
        run(sample, solvers="fabrik", effector_sets="2", n_cases=0, methods="none")
    ns = get_benchmark("ik").namespace()
    assert ns.cases == 1000 and ns.no_peers is False and ns.json is False
