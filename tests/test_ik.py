"""The Solver conformance suite (every registered solver runs it) and FABRIK/CCD/DLS specifics."""

import numpy as np
import pytest

from posekit import fk
from posekit.bench.ik import SOLVERS, _numpy_fabrik, build_cases, make_solver
from posekit.ik import (EFFECTOR_SETS, Effector, FabrikSolver, IKResult, Pose, Solver, default_constraints,
                        effector_set, fabrik_chain, fix_bone_lengths)
from posekit.ik.fabrik import straighten_chain
from posekit.ik.fabrik_batched import fabrik_batched
from posekit.ik.two_bone import two_bone_ik
from posekit.kinematics import bone_lengths_of


@pytest.fixture(scope="module")
def cases(sample):
    return build_cases(sample, 40, seed=1)


@pytest.fixture(params=sorted(SOLVERS))
def solver(request, skel):
    return make_solver(request.param, skel)


# ------------------------------------------------------------------ conformance: any solver
def _check_conformance(solver, cases):
    """What the Solver interface promises, checked by calling it (``isinstance(x, Solver)`` only
    looks at attribute names)."""
    s = cases.skeleton
    assert isinstance(solver, Solver) and isinstance(solver.name, str) and solver.name
    assert solver.skeleton.n_joints == s.n_joints
    effs = effector_set(s, "5", cases.target_pos[1])
    res = solver.solve(cases.pose(1), effs)
    assert isinstance(res, IKResult) and isinstance(res.pose, Pose) and isinstance(res.info, dict)
    pos = res.pose.global_pos
    assert isinstance(pos, np.ndarray) and pos.shape == (s.n_joints, 3) and pos.dtype == np.float64
    assert np.all(np.isfinite(pos))
    assert isinstance(res.converged, (bool, np.bool_)) and isinstance(res.iterations, (int, np.integer))
    assert res.iterations >= 0
    err = np.asarray(res.effector_error)
    assert err.shape == (len(effs),)
    true_err = np.linalg.norm(pos[s.indices([e.joint for e in effs])] - [e.target for e in effs], axis=1)
    np.testing.assert_allclose(err, true_err, atol=1e-9)  # the reported errors are the real ones
    if res.pose.local_rot is not None:
        assert res.pose.local_rot.shape == (s.n_joints, 4) and res.pose.root_pos.shape == (3,)


def test_implements_the_protocol(solver, cases):
    _check_conformance(solver, cases)


def test_conformance_check_catches_a_broken_solver(skel, cases):
    class Broken:  # right attribute names, wrong answers
        name = "broken"

        def __init__(self, skeleton, result):
            self.skeleton, self.result = skeleton, result

        def solve(self, start, effectors):
            return self.result(start)

    J = skel.n_joints
    for result in (lambda st: None,
                   lambda st: IKResult(Pose(st.global_pos[:-1]), True, 0, np.zeros(5)),
                   lambda st: IKResult(Pose(st.global_pos), True, 0, np.zeros(5)),  # errors made up
                   lambda st: IKResult(Pose(np.full((J, 3), np.nan)), False, 1, np.zeros(5))):
        broken = Broken(skel, result)
        assert isinstance(broken, Solver)  # the runtime Protocol check alone lets it through
        with pytest.raises(AssertionError):
            _check_conformance(broken, cases)


@pytest.mark.parametrize("effectors, share", [("2", 0.9), ("5point", 0.2)])
def test_reaches_reachable_targets_and_keeps_bones(solver, cases, effectors, share):
    s = cases.skeleton
    converged = 0
    for i in range(len(cases)):
        start = cases.pose(i)
        before = start.global_pos.copy()
        res = solver.solve(start, effector_set(s, effectors, cases.target_pos[i]))
        pos = res.pose.global_pos
        assert pos.shape == (s.n_joints, 3) and np.all(np.isfinite(pos))
        np.testing.assert_allclose(bone_lengths_of(s, pos), bone_lengths_of(s, before), atol=1e-6)
        np.testing.assert_allclose(pos[s.index("pelvis")], before[s.index("pelvis")], atol=1e-9)
        np.testing.assert_array_equal(start.global_pos, before)  # input untouched
        assert res.converged == bool(np.all(res.effector_error <= 1e-3))
        idx = s.indices([e.joint for e in effector_set(s, effectors, cases.target_pos[i])])
        err0 = np.linalg.norm(before[idx] - cases.target_pos[i, idx], axis=1).max()
        assert res.effector_error.max() <= max(err0, 1e-3)  # never worse than the start
        converged += res.converged
    assert converged / len(cases) >= share  # reachable by construction (the target pose solves it)


def test_start_at_the_solution_needs_no_iteration(solver, cases):
    s = cases.skeleton
    start = cases.pose(0)
    res = solver.solve(start, effector_set(s, "5", start.global_pos))
    assert res.converged and res.iterations == 0
    np.testing.assert_allclose(res.pose.global_pos, start.global_pos, atol=1e-6)


def test_unreachable_target_is_flagged_never_nan(solver, cases):
    s = cases.skeleton
    start = cases.pose(0)
    hand = s.index("left_hand")
    far = start.global_pos[hand] + np.array([10.0, 0.0, 0.0])
    res = solver.solve(start, [Effector("left_hand", far)])
    assert not res.converged and np.all(np.isfinite(res.pose.global_pos))
    assert res.effector_error[0] < np.linalg.norm(far - start.global_pos[hand])  # moved towards it


@pytest.mark.parametrize("effector, msg", [
    (Effector("left_hand", [np.nan, 0, 0]), "NaN or inf"),
    (Effector("left_hand", [0, 0]), r"shape \(3,\)"),
    (Effector("left_pinky", [0, 0, 0]), "valid names: root, chest"),
    (Effector("left_hand", [0, 0, 0], kind="look-at"), "kind 'look-at' is not supported"),
    (Effector("left_hand", [0, 0, 0], tolerance=0), "tolerance must be a positive"),
])
def test_bad_effectors_raise_clear_errors(solver, cases, effector, msg):
    with pytest.raises(ValueError, match=msg):
        solver.solve(cases.pose(0), [effector])


def test_bad_start_pose_raises(solver, cases, skel):
    bad = cases.pose(0)
    bad.global_pos = bad.global_pos[:-1]
    for start in (bad, "not a pose"):
        with pytest.raises(ValueError, match="start pose|expected a Pose"):
            solver.solve(start, [Effector("left_hand", [0, 1, 0])])


# ------------------------------------------------------------------ FABRIK specifics
def test_fabrik_chain_reaches_and_keeps_lengths(rng):
    p = np.cumsum(np.vstack([[0, 0, 0], rng.normal(size=(4, 3)) * 0.2]), axis=0)
    lengths = np.linalg.norm(np.diff(p, axis=0), axis=1)
    target = p[0] + np.array([0.3, 0.2, -0.1])
    out, ok, it = fabrik_chain(p, target, 1e-4, 100)
    assert ok and np.linalg.norm(out[-1] - target) <= 1e-4
    np.testing.assert_allclose(np.linalg.norm(np.diff(out, axis=0), axis=1), lengths, atol=1e-9)
    np.testing.assert_array_equal(out[0], p[0])


def test_fabrik_chain_unreachable_stretches_straight():
    p = np.array([[0, 0, 0], [0, 1.0, 0], [0, 2.0, 0.0]])
    out, ok, _ = fabrik_chain(p, np.array([5.0, 0, 0]))
    assert not ok
    np.testing.assert_allclose(out, [[0, 0, 0], [1, 0, 0], [2, 0, 0]], atol=1e-12)


def test_zero_length_bone_is_refused(skel, sample):
    with pytest.raises(ValueError, match="zero-length"):
        fabrik_chain(np.array([[0, 0, 0], [0, 0, 0], [1.0, 0, 0]]), np.zeros(3))
    pos = sample.global_pos[0].copy()
    pos[skel.index("left_elbow")] = pos[skel.index("left_shoulder")]
    with pytest.raises(ValueError, match="zero-length bone to joint left_elbow"):
        FabrikSolver(skel).solve(Pose(pos), [Effector("left_hand", pos[skel.index("left_hand")] + 0.1)])


def _limit_violations(skel, pos, cons):
    bad = 0.0
    for name, limit in cons.max_angle.items():
        j = skel.index(name)
        p, g = skel.parents[j], skel.parents[skel.parents[j]]
        e, u = pos[p] - pos[g], pos[j] - pos[p]
        ang = np.arccos(np.clip(e @ u / np.linalg.norm(e) / np.linalg.norm(u), -1, 1))
        bad = max(bad, ang - limit)
    return bad


def test_constraints_are_respected_and_matter(skel, cases):
    cons = default_constraints(skel)
    free, limited = FabrikSolver(skel), FabrikSolver(skel, constraints=True)
    rng = np.random.default_rng(4)
    worst_free = worst_limited = 0.0
    for i in range(len(cases)):
        start = cases.pose(i)
        # hands pulled to random points around the body: often needs an arm bent the wrong way
        effs = [Effector(h, start.global_pos[skel.index("chest")] + rng.normal(0, 0.35, 3))
                for h in ("left_hand", "right_hand")]
        worst_free = max(worst_free, _limit_violations(skel, free.solve(start, effs).pose.global_pos, cons))
        worst_limited = max(worst_limited, _limit_violations(skel, limited.solve(start, effs).pose.global_pos, cons))
    assert worst_limited <= 1e-6
    assert worst_free > np.radians(5)  # the test would notice constraints that do nothing


def test_real_poses_satisfy_the_default_constraints(sample):
    cons = default_constraints(sample.skeleton)
    assert max(_limit_violations(sample.skeleton, p, cons) for p in sample.global_pos[::3]) <= 0


def test_fix_bone_lengths(skel, sample, rng):
    true = sample.global_pos[100:110]
    noisy = true + rng.normal(0, 0.02, true.shape)
    for keep in ("leaves", "root"):
        fixed = fix_bone_lengths(skel, noisy, keep=keep)
        np.testing.assert_allclose(bone_lengths_of(skel, fixed), np.broadcast_to(skel.bone_lengths(), (10, 18)),
                                   atol=1e-9)
    before = np.abs(bone_lengths_of(skel, noisy) - skel.bone_lengths()).max()
    assert before > 0.01
    np.testing.assert_array_equal(fix_bone_lengths(skel, noisy, keep="root")[:, 0], noisy[:, 0])
    with pytest.raises(ValueError, match="NaN"):
        fix_bone_lengths(skel, np.full((18, 3), np.nan))


@pytest.mark.parametrize("effectors", ["2", "5", "5point"])
def test_batched_equals_single(skel, cases, effectors):
    eff = skel.indices(EFFECTOR_SETS[effectors])
    tg = cases.target_pos[:, eff]
    pos, conv, it = fabrik_batched(skel, cases.start_pos, eff, tg)
    solver = FabrikSolver(skel)
    for i in range(0, len(cases), 5):
        res = solver.solve(Pose(cases.start_pos[i]), [Effector(int(e), tg[i, k]) for k, e in enumerate(eff)])
        np.testing.assert_allclose(pos[i], res.pose.global_pos, atol=1e-12)
        assert conv[i] == res.converged and it[i] == res.iterations
    one = cases.start_pos[:1].copy()  # a batch of one used to be solved in the caller's array
    fabrik_batched(skel, one, eff, tg[:1])
    np.testing.assert_array_equal(one, cases.start_pos[:1])


def test_numpy_baseline_runs_the_same_algorithm(skel, cases):
    solver = FabrikSolver(skel)  # the benchmark's speed comparison is like with like
    for effectors in ("2", "5", "5point"):
        eff = skel.indices(EFFECTOR_SETS[effectors])
        for i in range(0, len(cases), 8):
            res = solver.solve(Pose(cases.start_pos[i]), [Effector(int(e), cases.target_pos[i, e]) for e in eff])
            np.testing.assert_allclose(_numpy_fabrik(skel, cases.start_pos[i], eff, cases.target_pos[i, eff]),
                                       res.pose.global_pos, atol=1e-9)


def _converged_share(solver, cases, effectors):
    s = cases.skeleton
    return np.mean([solver.solve(cases.pose(i), effector_set(s, effectors, cases.target_pos[i])).converged
                    for i in range(len(cases))])


@pytest.fixture(scope="module")
def bench_cases(sample):
    return build_cases(sample, n_cases=200)  # the benchmark's held-out cases (default seed)


@pytest.mark.parametrize("effectors", ["2", "5", "5point"])
def test_fabrik_converges_on_held_out_cases(skel, bench_cases, effectors):
    # "5" puts the head at 97-99.5 % of the pelvis->head reach: plain FABRIK converged in 29 % of
    # these cases within 20 iterations, the near-extended chain step brings it to ~100 %
    assert _converged_share(FabrikSolver(skel), bench_cases, effectors) >= 0.95


@pytest.mark.shared_data
def test_fabrik_converges_on_bandai_held_out_cases(shared_data):
    from posekit.data import load_bandai

    ms = load_bandai(1, data_dir=shared_data, progress=False)
    cases = build_cases(ms, n_cases=200)
    solver = FabrikSolver(ms.skeleton)
    for effectors in ("5", "5point"):  # plain FABRIK: 75 % and 83 %
        assert _converged_share(solver, cases, effectors) >= 0.95


def test_straighten_chain(rng):
    bones = np.array([0.0, 1.0, 0.0]) + rng.normal(0, 0.1, (4, 3))
    bones *= 0.2 / np.linalg.norm(bones, axis=1, keepdims=True)
    p = np.vstack([np.zeros(3), np.cumsum(bones, axis=0)])
    reach = 0.8
    u = np.array([0.3, 0.8, -0.2]) / np.linalg.norm([0.3, 0.8, -0.2])
    assert fabrik_chain(p, 0.995 * reach * u)[2] == 20  # plain FABRIK's slow regime: not in 20 iterations
    for frac in (0.92, 0.995, 0.99999):
        m, out = straighten_chain(p, frac * reach * u)
        assert m == 0 and np.linalg.norm(out[-1] - frac * reach * u) < 1e-9
        np.testing.assert_allclose(np.linalg.norm(np.diff(out, axis=0), axis=1), 0.2, atol=1e-12)
        np.testing.assert_array_equal(out[0], p[0])
    # out of reach: exactly Algorithm 1's straight chain
    np.testing.assert_allclose(straighten_chain(p, 3 * u)[1], fabrik_chain(p, 3 * u)[0], atol=1e-12)
    assert straighten_chain(p, 0.5 * reach * u) is None  # well inside the reach: left to the passes
    two, span = p[:3], np.linalg.norm(p[2])  # two bones: one part to straighten
    assert straighten_chain(two, 0.999 * span * u, may_bend=False) is None  # would need more bend
    m, out = straighten_chain(two, 0.999 * span * u)
    assert np.linalg.norm(out[-1] - 0.999 * span * u) < 1e-9


def test_constraints_hold_with_straightened_chains(skel, cases):
    cons, limited = default_constraints(skel), FabrikSolver(skel, constraints=True)
    worst = max(_limit_violations(skel, limited.solve(cases.pose(i), effector_set(skel, e, cases.target_pos[i]))
                                  .pose.global_pos, cons)
                for e in ("5", "5point") for i in range(len(cases)))
    assert worst <= 1e-6


def test_rotation_solvers_return_consistent_rotations(cases):
    s = cases.skeleton
    for name in ("ccd", "dls"):
        res = make_solver(name, s).solve(cases.pose(3), effector_set(s, "5", cases.target_pos[3]))
        q = res.pose.local_rot
        np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-9)
        np.testing.assert_allclose(fk(s, q, res.pose.root_pos)[0], res.pose.global_pos, atol=1e-9)


def test_rotation_solvers_need_rotations(cases):
    with pytest.raises(ValueError, match="needs local_rot"):
        make_solver("ccd", cases.skeleton).solve(Pose(cases.start_pos[0]), [Effector("left_hand", [0, 1, 0])])


# ------------------------------------------------------------------ two-bone IK
def test_two_bone_reaches_bends_to_pole_and_clamps():
    root, mid, end = np.array([0, 1.0, 0]), np.array([0, 0.5, 0]), np.array([0, 0.0, 0])
    target, pole = np.array([0.3, 0.4, 0.0]), np.array([0, 0.5, 1.0])
    m, e, ok = two_bone_ik(root, mid, end, target, pole)
    assert ok and np.allclose(e, target)
    assert np.isclose(np.linalg.norm(m - root), 0.5) and np.isclose(np.linalg.norm(e - m), 0.5)
    assert m[2] > 0  # bent towards the pole (+Z)
    m, e, ok = two_bone_ik(root, mid, end, np.array([0, 3.0, 0]), pole)
    assert not ok and np.isclose(np.linalg.norm(e - root), 1.0, atol=1e-5)


@pytest.mark.shared_data
def test_solvers_on_bandai(shared_data):
    from posekit.data import load_bandai

    ms = load_bandai(1, data_dir=shared_data, pattern="*_walk_*.bvh", progress=False)
    cases = build_cases(ms, 10, seed=0)
    for name in ("fabrik", "ccd", "dls"):
        solver = make_solver(name, ms.skeleton)
        for i in range(len(cases)):
            res = solver.solve(cases.pose(i), effector_set(ms.skeleton, "5point", cases.target_pos[i]))
            assert np.all(np.isfinite(res.pose.global_pos))
            np.testing.assert_allclose(bone_lengths_of(ms.skeleton, res.pose.global_pos)[2:],
                                       bone_lengths_of(ms.skeleton, cases.start_pos[i])[2:], atol=1e-6)
