"""Lesson 03: pose autoencoder, latent-space solvers (Victor et al. 2021) and the neural IK solver."""

import numpy as np
import pytest
import torch

from posekit.data import load_sample
from posekit.data.cases import build_cases, case_split
from posekit.data.metrics import body_joints, bone_length_error, mpjpe
from posekit.ik import EFFECTOR_SETS, Effector, effector_set, make_solver
from posekit.data.pose_vectors import STD_FLOOR, feature_columns, pose_data, pose_vectors, poses_from_vectors
from posekit.models.pose_autoencoder.data import training_pairs
from posekit.models.pose_autoencoder.networks import CHAIN, GROUPS, AESolvers, PoseAutoencoder
from posekit.data.bandai_mini import LICENCE
from posekit.models.pose_autoencoder.networks import weights_path
from posekit.models.pose_autoencoder.train import solver_loss, train_ae_solvers
from posekit.models.pose_autoencoder.solver import NeuralIKSolver


@pytest.fixture(scope="module")
def tiny(mini, tmp_path_factory):
    """A model trained for seconds (every stage runs), saved and loaded back."""
    path = tmp_path_factory.mktemp("ae") / "tiny.pt"
    model, report = train_ae_solvers(mini, out=path, progress=False, ae_epochs=2, solver_epochs=1, chain_epochs=1,
                                     pairs=3000)
    return model, report, path


@pytest.fixture(scope="module")
def cases(mini):
    return build_cases(mini, 40, 0, "other-clip")


def test_pose_vectors_round_trip_and_root_frame(mini):
    s = mini.skeleton
    pos = mini.global_pos[::997]
    x, origin, angle = pose_vectors(s, pos)
    assert x.shape == (len(pos), 3 * len(body_joints(s))) and 0 not in body_joints(s)  # joint_Root is no pose
    pel = feature_columns(s, ["pelvis"])
    assert np.allclose(x[:, pel[[0, 2]]], 0.0, atol=1e-9)  # the pelvis sits above the root frame's origin
    assert np.allclose(poses_from_vectors(s, x, origin, angle), pos, atol=1e-9)  # the helper root comes back too
    with pytest.raises(ValueError, match="not a body joint"):
        feature_columns(s, ["joint_Root"])


def test_pose_data_floors_the_std_and_mirrors(mini):
    train, _, _, _ = case_split(mini)
    d = pose_data(mini, train[:500])
    assert len(d.x) == 2 * d.n and d.mirrored
    assert d.norm.std.min() >= STD_FLOOR - 1e-12
    lh, rh = feature_columns(mini.skeleton, ["left_hand"]), feature_columns(mini.skeleton, ["right_hand"])
    assert np.allclose(d.x[d.n:, lh] * [-1, 1, 1], d.x[: d.n, rh], atol=1e-5)  # row n+i mirrors row i


def test_training_pairs_stay_in_one_clip_within_a_second(mini):
    train, _, _, _ = case_split(mini)
    d = pose_data(mini, train)
    a, b = training_pairs(mini, d, 5000, seed=3)
    assert np.all((a < d.n) == (b < d.n)) and 0.3 < np.mean(a >= d.n) < 0.7  # mirrored pairs, both rows
    fa, fb = d.frames[a % d.n], d.frames[b % d.n]
    assert np.all(fa != fb) and np.all(mini.clip_id[fa] == mini.clip_id[fb])
    assert np.all(np.abs(fa - fb) * mini.frame_time[mini.clip_id[fa]] <= 1.0 + 1e-9)
    assert np.array_equal(training_pairs(mini, d, 100, seed=3)[0], training_pairs(mini, d, 100, seed=3)[0])


def test_tied_decoder_is_the_transposed_encoder_without_biases():
    torch.manual_seed(0)
    ae = PoseAutoencoder(12, hidden=8, latent=4, tied=True)
    untied = PoseAutoencoder(12, hidden=8, latent=4, tied=False)
    assert sum(p.numel() for p in untied.parameters()) > sum(p.numel() for p in ae.parameters())
    z = torch.randn(5, 4)
    w1, w2, w3 = ae.enc1.weight, ae.enc2.weight, ae.enc3.weight
    by_hand = torch.relu(torch.relu(z @ w3) @ w2) @ w1
    assert torch.allclose(ae.decode(z), by_hand)


def test_solver_loss_weights_the_other_joints_by_k():
    x = torch.zeros(2, 6)
    d = torch.zeros(2, 6)
    d[:, 0:3] = 1.0  # wrong target joint
    d[:, 3:6] = 2.0  # wrong other joint
    loss = solver_loss(6, [0, 1, 2], k=0.1)
    assert float(loss(d, x)) == pytest.approx(1.0 + 0.1 * 4.0)


def test_training_lowers_the_losses_and_saves_everything(tiny, mini):
    model, report, path = tiny
    assert report["autoencoder"]["val"][-1] < report["autoencoder"]["train"][0]
    assert set(report["solvers"]) == set(GROUPS) | {f"chained {g}" for g in CHAIN[1:]}
    back = AESolvers.load(path, skeleton=mini.skeleton)
    assert set(back.solvers) == set(GROUPS) and set(back.chained) == set(CHAIN[1:])
    assert back.info["command"].startswith("posekit train ae-solvers --seed 0") and "CC BY-NC" in back.info["licence"]
    x = torch.as_tensor(model.norm.normalize(pose_vectors(mini.skeleton, mini.global_pos[:50])[0]), dtype=torch.float32)
    with torch.no_grad():  # float16 storage: the reloaded model gives the same poses to a small fraction of a mm
        a, b = model.ae(x), back.ae(x)
    assert torch.max(torch.abs(a - b) * torch.as_tensor(model.norm.std, dtype=torch.float32)) < 2e-3


def test_numpy_networks_match_torch(tiny, mini):
    model = tiny[0]
    fast = model.compile()
    x = model.norm.normalize(pose_vectors(mini.skeleton, mini.global_pos[:64])[0]).astype(np.float32)
    p = {g: x[:, model.columns(g)] for g in CHAIN}
    with torch.no_grad():
        z = model.ae.encode(torch.as_tensor(x))
        zc = model.latent(z, {g: torch.as_tensor(v) for g, v in p.items()})
        dec = model.ae.decode(zc).numpy()
    assert np.allclose(fast.encode(x), z.numpy(), atol=1e-4)
    assert np.allclose(fast.decode(fast.latent(fast.encode(x), p)), dec, atol=1e-4)


@pytest.mark.parametrize("post", ["none", "bones"])
@pytest.mark.parametrize("chain", [False, True])
def test_compiled_single_pose_path_equals_the_batched_one(tiny, cases, post, chain):
    s = cases.skeleton
    solver = NeuralIKSolver(s, model=tiny[0], post=post, chain=chain)
    for e in ("2", "5"):
        j = s.indices(EFFECTOR_SETS[e])
        batch, _, _ = solver.predict(cases.start_pos[:10], j, cases.target_pos[:10][:, j])
        for i in range(10):
            one, _, _ = solver.predict_one(cases.start_pos[i], j, cases.target_pos[i][j])
            assert np.allclose(one, batch[i], atol=1e-5)


def test_the_authors_chaining_decodes_and_encodes_again_between_stages(tiny, mini, cases):
    """reencode=True: z = E(D(z)) between two stages (the authors' CombinedSequentialIKSolver), on both the batched
    and the compiled single-pose path; one stage alone is untouched by it."""
    fast, s = tiny[0].compile(), cases.skeleton
    x = tiny[0].norm.normalize(pose_vectors(mini.skeleton, mini.global_pos[:8])[0]).astype(np.float32)
    p = {g: x[:, tiny[0].columns(g)] for g in CHAIN}
    z = fast.encode(x)
    by_hand = z
    for k, g in enumerate(CHAIN):
        if k:
            by_hand = fast.encode(fast.decode(by_hand))
        by_hand = fast._mlp(fast.solvers[g], np.concatenate([by_hand, p[g]], axis=-1))
    assert np.allclose(fast.latent(z, p, chain=list(CHAIN), chain_aware=False, reencode=True), by_hand, atol=1e-5)
    assert not np.allclose(fast.latent(z, p, chain=list(CHAIN), chain_aware=False), by_hand, atol=1e-3)
    one = {"hands": p["hands"]}
    assert np.array_equal(fast.latent(z, one, reencode=True), fast.latent(z, one))
    solver = NeuralIKSolver(s, model=tiny[0], post="none", chain=True, chain_aware=False, reencode=True)
    j = s.indices(EFFECTOR_SETS["5"])
    batch, _, _ = solver.predict(cases.start_pos[:5], j, cases.target_pos[:5][:, j])
    for i in range(5):
        assert np.allclose(solver.predict_one(cases.start_pos[i], j, cases.target_pos[i][j])[0], batch[i], atol=1e-5)


def test_solver_contract(tiny, cases):
    s = cases.skeleton
    solver = NeuralIKSolver(s, model=tiny[0])
    effs = [effector_set(s, "2", cases.target_pos[i]) for i in range(6)]
    one = [solver.solve(cases.pose(i), effs[i]) for i in range(6)]
    batch = solver.solve_batch([cases.pose(i) for i in range(6)], effs)
    for a, b, e in zip(one, batch, effs):
        assert np.allclose(a.pose.global_pos, b.pose.global_pos, atol=1e-5)
        assert a.effector_error.shape == (2,) and a.info["stages"] == ["hands"]
        # post-processing: effectors on their targets, then bone lengths restored exactly
        assert bone_length_error(s, a.pose.global_pos[None], cases.start_pos[:1]).max() < 1e-9
    res = NeuralIKSolver(s, model=tiny[0], chain=True).solve(cases.pose(0), effector_set(s, "5", cases.target_pos[0]))
    assert res.info["stages"] == list(CHAIN)
    with pytest.raises(ValueError, match="which is not exactly one"):
        solver.solve(cases.pose(0), [Effector("left_hand", cases.target_pos[0, s.index("left_hand")])])
    with pytest.raises(ValueError, match="does not support effector kind 'rotation'"):
        solver.solve(cases.pose(0), [Effector("head", [0, 0, 0, 1], kind="rotation")])


def test_bad_input(tiny, cases):
    s = cases.skeleton
    solver = NeuralIKSolver(s, model=tiny[0])
    t = cases.target_pos[0]
    with pytest.raises(ValueError, match="NaN"):
        solver.solve(cases.pose(0), [Effector("left_hand", [np.nan, 0, 0]), Effector("right_hand", t[13])])
    far = solver.solve(cases.pose(0), [Effector("left_hand", t[9] + [0, 5.0, 0]), Effector("right_hand", t[13])])
    assert np.all(np.isfinite(far.pose.global_pos)) and far.info["out_of_range"] == ["Hand_L"]
    assert "out_of_range" not in solver.solve(cases.pose(0), effector_set(s, "2", t)).info
    other = load_sample().skeleton
    with pytest.raises(ValueError, match="trained for skeleton joints"):
        NeuralIKSolver(other, weights=tiny[2])


def test_shipped_weights_are_marked_and_beat_fabrik_from_another_clip(mini):
    path = weights_path()
    model = AESolvers.load(path, skeleton=mini.skeleton)
    assert model.info["licence"] == LICENCE and model.info["command"].startswith("posekit train ae-solvers")
    assert set(model.solvers) == set(GROUPS) and set(model.chained) == set(CHAIN[1:])
    c = build_cases(mini, 200, 0, "other-clip")
    s = c.skeleton
    for e in ("2", "5"):
        fab, neu = make_solver("fabrik", s), make_solver("neural", s)
        effs = [effector_set(s, e, c.target_pos[i]) for i in range(len(c))]
        pf = np.stack([fab.solve(c.pose(i), effs[i]).pose.global_pos for i in range(len(c))])
        pn = np.stack([r.pose.global_pos for r in neu.solve_batch([c.pose(i) for i in range(len(c))], effs)])
        assert np.median(mpjpe(s, pn, c.target_pos)) < np.median(mpjpe(s, pf, c.target_pos))


def test_exercise_checkers_accept_right_and_refuse_wrong_answers(capsys):
    from posekit.data.metrics import body_joints
    from posekit.exercises import check_authors_loss, check_pose_from_vector, check_pose_vector
    from posekit.transforms import facing_angle

    def in_root_frame(s, p):  # the root frame by hand (the checker refuses posekit's to_root_space)
        p = np.asarray(p, dtype=float)
        a = float(facing_angle(s, p))
        turn = np.array([[np.cos(a), 0.0, -np.sin(a)], [0.0, 1.0, 0.0], [np.sin(a), 0.0, np.cos(a)]])
        return (p - p[s.index("pelvis")] * np.array([1.0, 0.0, 1.0])) @ turn.T

    def right_vector(s, p):
        return in_root_frame(s, p)[body_joints(s)].reshape(-1)

    def wrong_vector(s, p):  # keeps joint_Root: the trap of the issue
        return in_root_frame(s, p)[:-1].reshape(-1)

    def bandai_only(s, p):  # "the helper root is joint 0": true of Bandai's skeleton, not of another one
        return in_root_frame(s, p)[1:].reshape(-1)

    from posekit.data.pose_vectors import poses_from_vectors

    assert check_pose_vector(right_vector) and not check_pose_vector(wrong_vector)
    assert not check_pose_vector(bandai_only)
    assert not check_pose_from_vector(lambda s, x, o, a: poses_from_vectors(s, x[None], o[None], np.array([a]))[0])

    def weighted(d, t, c, w):
        m = np.ones(d.shape[1])
        m[list(c)] = w
        return (m * (d - t) ** 2).mean(), 2 * m * (d - t) / d.size, (d.shape[1] - len(c)) / (w * len(c))
    assert check_authors_loss(weighted) and not check_authors_loss(lambda d, t, c, w: weighted(d, t, c, 1.0))
    out = capsys.readouterr().out
    assert out.count("✓") == 2 and out.count("✗") == 4


def test_solver_panel_shows_a_refusal_and_keeps_the_other_views(mini):
    from posekit.viz import SolverPanel

    c = build_cases(mini, 3, 0, "other-clip")
    s = c.skeleton
    panel = SolverPanel(s, {n: make_solver(n, s) for n in ("fabrik", "neural")}, c.pose(0),
                        effector_set(s, "5", c.target_pos[0]), truth=c.target_pos[0])
    assert panel.labels["neural"].value.startswith("<b>") and not isinstance(panel.results["neural"], Exception)
    panel.move_target("left_elbow", c.target_pos[0][s.index("left_elbow")] + 0.05)  # no network for this joint set
    assert isinstance(panel.results["neural"], ValueError) and "cannot solve" in panel.labels["neural"].value
    assert len(panel.results["fabrik"].effector_error) == 6 and "worst effector" in panel.labels["fabrik"].value


def test_bench_ik_runs_table_1_side_by_side(mini):
    from posekit.bench import ik as bench_ik

    rows = bench_ik.run(mini, solvers="fabrik,neural", effector_sets=("2", "5"), n_cases=15, start="rest,other-clip",
                        peers=False, baseline=False)
    got = {(r["method"], r["effectors"], r["start"]) for r in rows}
    for st in ("rest", "other-clip"):
        for e in ("2", "5"):
            for name in ("fabrik", "neural", "neural-raw", "neural-fabrik", "neural batched", "neural-raw batched",
                         "neural networks only"):
                assert (name, e, st) in got, (name, e, st)
        assert ("neural-chained", "5", st) in got and ("neural-chained", "2", st) not in got  # one stage: no chain
    by = {(r["method"], r["effectors"], r["start"]): r for r in rows}
    n2 = by[("neural", "2", "rest")]
    assert n2["paper_latency_ms"] == 1.47 and n2["paper_kb"] == 442 and 100 < n2["solver_kb"] <= 500 < n2["model_kb"]
    assert by[("neural batched", "5", "rest")]["us_per_pose"] > 0
    assert by[("neural", "2", "rest")]["bone_length_error_mm_max"] < 1e-6 < by[("neural-raw", "2", "rest")][
        "bone_length_error_mm_max"]


def test_cli_bench_defaults_to_the_data_the_weights_were_made_for(capsys):
    import json

    from posekit.cli import main

    assert main(["bench", "ik", "--solvers", "fabrik,neural", "--effectors", "2,5", "--cases", "10", "--json",
                 "--methods", "none"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert {r["method"] for r in rows} == {"fabrik", "neural"}
    assert all(r["data"].startswith("bandai-mini") for r in rows)
    assert main(["bench", "ik", "--solvers", "neural", "--data", "sample", "--cases", "5"]) == 2
    assert "trained for skeleton joints" in capsys.readouterr().err


def test_bench_all_skips_learned_solvers_made_for_another_skeleton():
    from posekit.bench import ik as bench_ik

    with pytest.warns(UserWarning, match="skipping solver\\(s\\) ") as record:
        rows = bench_ik.run(load_sample(), solvers="all", effector_sets=("2",), n_cases=5, methods="none")
    message = str(record[0].message)
    assert all(f"'{n}'" in message for n in ("neural", "neural-raw", "latent-opt", "latent-opt-raw"))
    assert {r["method"] for r in rows} >= {"fabrik", "dls"}
    assert not any(r["method"].startswith(("neural", "latent")) for r in rows)
    assert len(record) == 1
