"""Lesson 05: ProtoRes (Oreshkin et al. 2022), its baselines, its data, losses, benchmarks and Solver wrapper."""

import json

import numpy as np
import pytest
import torch

from posekit.ik import Effector, make_solver
from posekit.ik.bone_rotations import check_roundtrip, rotations_from_positions, shortest_rotation
from posekit.kinematics import bone_lengths_of, fk
from posekit.models.protores.networks import (ARCHS, KIND_IDS, PosingNet, ProtoResConfig, ProtoResEncoder, centroid,
                                              sigma_to_tolerance, tolerance_to_sigma, weights_path)
from posekit.evaluation.effector_cases import FIVE_POINT, ZONES, build_benchmark, load_benchmark
from posekit.models.protores.data import PoseBank, draw_batch
from posekit.models.protores.solver import MAX_EFFECTORS, ProtoResSolver
from posekit.models.protores.train import LOSSES, geodesic, losses, train_protores
from posekit.rotations import quat_to_matrix
from posekit.transforms import mirror_frame_signs, mirror_positions, mirror_rotation_matrices


@pytest.fixture(scope="module")
def bank(mini):
    return PoseBank(mini, mini.split.val[:300], mirror=True)


@pytest.fixture(scope="module")
def solver(mini):
    return ProtoResSolver(mini.skeleton)


@pytest.fixture(scope="module")
def five(mini):
    return load_benchmark("5point", mini)


@pytest.fixture(scope="module")
def random_bench(mini):
    return load_benchmark("random", mini)


# ------------------------------------------------------------------------------------------ data
def test_mirroring_a_skeleton_whose_frames_are_not_mirror_images(mini):
    s = mini.skeleton
    assert not s.is_symmetric()  # a quaternion flip would not do here
    R = quat_to_matrix(mini.local_rot[:500])
    signs = mirror_frame_signs(s, R)
    assert np.all(np.prod(signs, axis=1) == -1)
    Rm, rm = mirror_rotation_matrices(s, R, mini.root_pos[:500], signs)
    assert np.abs(fk(s, Rm, rm)[0] - mirror_positions(s, mini.global_pos[:500])).max() < 1e-3
    assert np.allclose(np.swapaxes(Rm, -1, -2) @ Rm, np.eye(3), atol=1e-9)
    back, rb = mirror_rotation_matrices(s, Rm, rm, signs)
    assert np.allclose(back, R, atol=1e-12) and np.allclose(rb, mini.root_pos[:500])


def test_draw_batch_follows_algorithm_1(bank):
    gen = torch.Generator().manual_seed(0)
    for _ in range(5):
        b = draw_batch(bank, 64, gen)
        N = b.joint.shape[1]
        assert 3 <= N <= 16
        assert (b.kind[:, :3] == KIND_IDS["position"]).all()
        for kind in (0, 1):  # no joint twice within one kind
            for i in range(64):
                j = b.joint[i][b.kind[i] == kind]
                assert len(j) == len(torch.unique(j))
        assert ((b.tol >= 0) & (b.tol <= 1)).all()
        # rotations in the input are the (noisy) world rotations: orthonormal 6D columns
        rot = b.value[b.kind == 1]
        assert torch.allclose(rot[:, :3].norm(dim=-1), torch.ones(len(rot)), atol=1e-5)


def test_noise_scale_follows_the_tolerance(bank):
    """sigma = sigma_M Lambda^eta: at Lambda = 1 a position is off by about 0.1 m per axis, at Lambda <= 0.5 not
    at all."""
    gen = torch.Generator().manual_seed(1)
    loose, tight = [], []
    for _ in range(20):
        b = draw_batch(bank, 128, gen, yaw=False)
        pos = b.kind == 0
        err = (b.value[..., :3] - b.global_pos[torch.arange(128)[:, None], torch.as_tensor(bank.body)[b.joint]])
        loose.append(err[pos & (b.tol > 0.97)])
        tight.append(err[pos & (b.tol < 0.5)])
    assert 0.06 < float(torch.cat(loose).std()) < 0.1
    assert float(torch.cat(tight).abs().max()) < 1e-4
    assert tolerance_to_sigma(1.0) == pytest.approx(0.1)
    assert sigma_to_tolerance(tolerance_to_sigma(0.8)) == pytest.approx(0.8)


# ------------------------------------------------------------------------------------------ model
def test_prototype_encoder_matches_eq2_by_hand_and_ignores_order():
    torch.manual_seed(0)
    enc = ProtoResEncoder(5, 8, blocks=3, layers=2).eval()
    x = torch.randn(2, 4, 5)
    e, xr = 0.0, x
    for r, blk in enumerate(enc.blocks, start=1):  # Eq. 2 written out
        h = xr
        for fc in blk.fc:
            h = torch.nn.functional.leaky_relu(fc(h))
        b, f = torch.relu(h + blk.skip(xr)), blk.forecast(h)
        e = e + f
        p = e.mean(1)
        xr = torch.relu(b - p[:, None] / r)
    assert torch.allclose(enc(x), p, atol=1e-6)
    assert torch.allclose(enc(x[:, [2, 0, 3, 1]]), enc(x), atol=1e-6)
    assert enc(x[:, :1]).shape == (2, 8)  # any N >= 1


@pytest.mark.parametrize("arch", ARCHS)
def test_every_encoder_gives_a_pose_that_keeps_bone_lengths(mini, arch):
    torch.manual_seed(0)
    net = PosingNet(mini.skeleton, ProtoResConfig(21, arch=arch, width=32, d_model=16, heads=2)).eval()
    gen = torch.Generator().manual_seed(0)
    b = draw_batch(PoseBank(mini, mini.split.val[:50]), 8, gen)
    out = net(b.joint, b.kind, b.value, b.tol)
    P = out["global_pos"].detach().numpy().astype(float)
    assert np.abs(bone_lengths_of(mini.skeleton, P) - mini.skeleton.bone_lengths()).max() < 1e-5
    # the centroid re-referencing: moving every target moves the pose by as much
    d = torch.tensor([0.7, -0.2, 1.5])
    v2 = b.value.clone()
    v2[..., :3] += torch.where((b.kind != 1)[..., None], d, torch.zeros(3))
    out2 = net(b.joint, b.kind, v2, b.tol)
    assert torch.allclose(out2["global_pos"], out["global_pos"] + d, atol=1e-4)
    assert torch.allclose(out2["local_rot"], out["local_rot"], atol=1e-5)


@pytest.mark.parametrize("arch", ["protores", "masked-fcr"])
@pytest.mark.parametrize("gpd", [True, False])
def test_numpy_pass_equals_torch(mini, arch, gpd):
    from posekit.models.protores.fast import NumpyPosingNet

    torch.manual_seed(1)
    net = PosingNet(mini.skeleton, ProtoResConfig(21, arch=arch, width=24, gpd=gpd)).eval()
    b = draw_batch(PoseBank(mini, mini.split.val[:50]), 5, torch.Generator().manual_seed(4))
    with torch.no_grad():
        ref = net(b.joint, b.kind, b.value, b.tol)
    got = NumpyPosingNet(net).forward(b.joint.numpy(), b.kind.numpy(), b.value.numpy(), b.tol.numpy())
    for k in ("global_pos", "global_rot", "local_rot", "root_pos"):
        assert np.abs(got[k] - ref[k].numpy()).max() < 1e-5, k
    assert (got["gpd_pos"] is None) == (ref["gpd_pos"] is None)
    with pytest.raises(ValueError, match="Transformer"):
        NumpyPosingNet(PosingNet(mini.skeleton, ProtoResConfig(21, arch="transformer", width=16, d_model=16, heads=2)))


def test_centroid_weights_tight_position_effectors():
    kind = torch.tensor([[0, 0, 1]])
    value = torch.tensor([[[0.0, 0, 0, 0, 0, 0], [1.0, 0, 0, 0, 0, 0], [9.0, 9, 9, 0, 0, 0]]])
    c = centroid(kind, value, torch.tensor([[0.0, 1.0, 0.0]]))
    assert c[0, 0] == pytest.approx(1e-3 / 1.002, rel=1e-3)  # the loose one barely counts; rotations not at all
    assert centroid(torch.tensor([[1]]), value[:, 2:], torch.zeros(1, 1)).abs().max() == 0


# ------------------------------------------------------------------------------------------ losses
def test_losses_vanish_on_the_truth_and_weight_tight_effectors(bank):
    gen = torch.Generator().manual_seed(2)
    b = draw_batch(bank, 16, gen)
    truth = {"global_pos": b.global_pos, "global_rot": b.global_rot, "local_rot": b.local_rot, "gpd_pos": b.global_pos}
    t = losses(truth, b, bank.body)
    assert float(t["ikd_l2"]) == 0 and float(t["gpd_l2"]) == 0
    assert float(t["loc_geo"]) < 2e-3  # arccos(1 - 1e-6): the clamp, nothing else
    # the clamp keeps the gradient finite at an exact prediction
    A = torch.eye(3).repeat(4, 1, 1).requires_grad_()
    geodesic(A, torch.eye(3).repeat(4, 1, 1)).sum().backward()
    assert torch.isfinite(A.grad).all()
    # an error on a tight effector's joint costs up to W_M times an error on a free joint
    off = dict(truth, global_pos=b.global_pos.clone())
    i, k = 0, 0
    j = int(torch.as_tensor(bank.body)[b.joint[i, k]])
    off["global_pos"][i, j, 0] += 0.01
    tight = float(losses(off, b, bank.body)["ikd_l2"])
    free = next(int(x) for x in bank.body if int(x) not in set(torch.as_tensor(bank.body)[b.joint[i]].tolist()))
    off2 = dict(truth, global_pos=b.global_pos.clone())
    off2["global_pos"][i, free, 0] += 0.01
    w = min(1000.0, 1 / max(float(b.sigma[i, k]), 1e-3))
    assert tight / float(losses(off2, b, bank.body)["ikd_l2"]) == pytest.approx(w, rel=1e-3)
    flat = float(losses(off, b, bank.body, weighted=False)["ikd_l2"])
    assert flat == pytest.approx(float(losses(off2, b, bank.body, weighted=False)["ikd_l2"]), rel=1e-4)


def test_training_is_seeded_and_the_checkpoint_round_trips(mini, tmp_path):
    cfg = ProtoResConfig(21, width=32)
    a, ra = train_protores(mini, steps=6, log_every=3, val_batches=1, progress=False, out=tmp_path / "a.pt", config=cfg)
    b, _ = train_protores(mini, steps=6, log_every=3, val_batches=1, progress=False, out=False, config=cfg)
    for (k, x), y in zip(a.state_dict().items(), b.state_dict().values()):
        assert torch.equal(x, y), k
    assert set(LOSSES) <= set(ra["curves"]) and ra["curves"]["step"] == [3, 6]
    loaded = PosingNet.load(tmp_path / "a.pt", skeleton=mini.skeleton)
    assert "CC BY-NC" in loaded.checkpoint["licence"]
    assert "posekit train protores" in loaded.checkpoint["command"]
    gen = torch.Generator().manual_seed(0)
    bt = draw_batch(PoseBank(mini, mini.split.val[:20]), 4, gen)
    assert torch.allclose(loaded(bt.joint, bt.kind, bt.value, bt.tol)["global_pos"],
                          a(bt.joint, bt.kind, bt.value, bt.tol)["global_pos"], atol=1e-5)


# ------------------------------------------------------------------------------------------ benchmarks
def test_benchmarks_are_reproducible_and_follow_their_rules(mini, five, random_bench):
    s = mini.skeleton
    assert len(five) == 1000 and (five.n == 5).all()
    assert (five.joint[:, :5] == s.indices(FIVE_POINT)).all() and (five.kind[:, :5] == 0).all()
    assert np.isin(five.frames, mini.split.test).all()
    r = random_bench
    assert r.n.min() == 6 and r.n.max() == 12
    zones = [set(s.indices(z)) for z in ZONES.values()]
    for i in range(len(r)):
        pos = set(r.joint[i, : r.n[i]][r.kind[i, : r.n[i]] == 0].tolist())
        assert all(pos & z for z in zones)
        effs = r.effectors(i)  # the Solver API accepts every case (no conflicting effectors)
        assert len(make_solver("dls", s).resolve(effs)) == r.n[i]
    again = build_benchmark("random", mini)
    assert np.array_equal(again.joint, r.joint) and np.allclose(again.value, r.value, atol=1e-6)


def test_rotations_from_positions_put_bones_on_new_positions(mini):
    s = mini.skeleton
    L0 = quat_to_matrix(mini.local_rot[:20])
    assert check_roundtrip(s, L0, mini.root_pos[:20]) < 1e-12
    P1 = mini.global_pos[500:520]
    L, r = rotations_from_positions(s, L0, mini.root_pos[:20], P1)
    assert np.abs(fk(s, L, r)[0] - P1).max() < 1e-9
    R = shortest_rotation(np.array([[1.0, 0, 0]]), np.array([[-1.0, 0, 0]]))
    assert np.allclose(R[0] @ [1, 0, 0], [-1, 0, 0]) and np.isclose(np.linalg.det(R[0]), 1)


# ------------------------------------------------------------------------------------------ solver
def test_shipped_weights_are_small_marked_and_beat_the_rest_pose(mini, five):
    """Each shipped network is at most 10 MB, says it was trained for a user's hour of two processes at the
    shipped width, keeps the mini set's licence, and poses nearer the truth than the fitted rest pose."""
    from posekit.models.protores.train import WIDTH

    for arch in ARCHS:
        assert weights_path(arch).stat().st_size <= 10 * 2 ** 20, arch
    from posekit.evaluation.effector_scores import rest_starts, scores
    from posekit.models.protores.solver import run_learned

    q, root = rest_starts(five, mini)
    rest_mm = np.linalg.norm(fk(mini.skeleton, q, root)[0] - five.global_pos, axis=-1).mean() * 1000
    for arch in ARCHS:
        sol = ProtoResSolver(mini.skeleton, arch=arch)
        assert "CC BY-NC 4.0" in sol.net.checkpoint["licence"]
        assert sol.net.checkpoint["command"].startswith("torchrun --nproc-per-node 2 -m posekit train protores ")
        assert sol.net.config.width == WIDTH and sol.net.checkpoint["extra"]["report"]["processes"] == 2, arch
        r = run_learned(sol, five)
        sc = scores(five, r["global_pos"], r["local_rot"], r["global_rot"], r["gpd_pos"])
        assert sc["mpjpe_mm"] < (0.8 if arch == "protores" else 0.95) * rest_mm, arch


def test_solver_api_and_batch_agree(mini, solver, random_bench):
    effs = [random_bench.effectors(i) for i in range(12)]
    one = [solver.solve(None, e) for e in effs]
    many = solver.solve_batch(None, effs)
    for a, b in zip(one, many):
        assert np.abs(a.pose.global_pos - b.pose.global_pos).max() < solver.batch_atol
        assert a.kinds == b.kinds and len(a.effector_error) == len(b.effector_error)
    r = one[0]
    assert np.abs(bone_lengths_of(mini.skeleton, r.pose.global_pos) - mini.skeleton.bone_lengths()).max() < 1e-5
    assert make_solver("protores", mini.skeleton).kinds == ("position", "rotation", "look_at")


def test_tighter_tolerance_gives_smaller_effector_error(solver, random_bench):
    from posekit.evaluation.effector_scores import scores
    from posekit.models.protores.solver import run_learned

    errs = []
    for lam in (0.0, 1.0):
        r = run_learned(solver, random_bench, tolerance=lam)
        errs.append(scores(random_bench, r["global_pos"], r["local_rot"], r["global_rot"])["pos_mm"])
    assert errs[0] < errs[1]


def test_bad_input_gets_a_clear_error(mini, solver):
    s = mini.skeleton
    hand = s.index("Hand_L")
    ok = (np.array([hand]), np.array([0]), np.zeros((1, 6)), np.array([0.0]))
    solver.predict(*ok)
    with pytest.raises(ValueError, match="not a body joint"):
        solver.predict(np.array([0]), *ok[1:])
    with pytest.raises(ValueError, match="unknown kind"):
        solver.predict(ok[0], np.array([5]), *ok[2:])
    with pytest.raises(ValueError, match="NaN"):
        solver.predict(*ok[:2], np.full((1, 6), np.nan), ok[3])
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        solver.predict(*ok[:3], np.array([1.5]))
    with pytest.raises(ValueError, match="at least one"):
        solver.predict(np.zeros(0, int), np.zeros(0, int), np.zeros((0, 6)), np.zeros(0))
    n = MAX_EFFECTORS + 1
    with pytest.raises(ValueError, match="at most"):
        solver.predict(np.full(n, hand), np.zeros(n, int), np.zeros((n, 6)), np.zeros(n))
    with pytest.raises(ValueError, match="unknown effector kind"):
        solver.solve(None, [Effector("Hand_L", [0, 1, 0], kind="orientation")])
    with pytest.raises(ValueError, match="valid"):
        solver.solve(None, [Effector("Tail", [0, 1, 0])])
    with pytest.raises(ValueError, match="sigma_M"):
        solver.solve(None, [Effector("Hand_L", [0, 1, 0], tolerance=0.5)])
    with pytest.raises(ValueError, match="not a body joint"):
        solver.solve(None, [Effector("joint_Root", [0, 1, 0])])


def test_far_targets_give_a_valid_flagged_pose(mini, solver):
    r = solver.solve(None, [Effector("Hand_L", [50.0, 1, 0]), Effector("Foot_R", [0.0, 0.1, 0]),
                            Effector("Head", [0.0, 1.7, 0])])
    assert np.isfinite(r.pose.global_pos).all()
    assert np.abs(bone_lengths_of(mini.skeleton, r.pose.global_pos) - mini.skeleton.bone_lengths()).max() < 1e-4
    assert "Hand_L" in r.info["out_of_range"]


def test_bench_protores_prints_every_table(capsys):
    from posekit.cli import main

    assert main(["bench", "protores", "--cases", "12", "--no-speed", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    tables = {r["table"] for r in rows}
    assert {1, "claims", "tolerance", "training", 2} <= tables
    methods = {r["method"] for r in rows if r["table"] == 1}
    assert methods == {"ProtoRes", "Masked-FCR", "Transformer", "FABRIK", "DLS"}
    assert all(isinstance(r["holds"], bool) for r in rows if r["table"] == "claims")


def test_bench_protores_scores_a_weights_folder_and_refuses_a_bad_one(capsys, tmp_path, mini):
    """``--weights DIR``: the folder's networks are scored (here ProtoRes a few steps old: worse than the shipped
    one), each file it lacks is the shipped one; a folder without checkpoints is refused with a sentence."""
    from posekit.cli import main

    from posekit.data.metrics import body_joints

    cfg = ProtoResConfig(len(body_joints(mini.skeleton)), width=32, blocks=1, layers=1)
    train_protores(mini, steps=4, log_every=2, val_batches=1, progress=False, out=tmp_path / "protores.pt", config=cfg)
    assert main(["bench", "protores", "--cases", "12", "--no-speed", "--no-classical", "--json"]) == 0
    table = lambda out: {r["method"]: r for r in json.loads(out) if r["table"] == 1 and r["benchmark"] == "random"}  # noqa: E731
    shipped = table(capsys.readouterr().out)
    assert main(["bench", "protores", "--cases", "12", "--no-speed", "--no-classical", "--json",
                 "--weights", str(tmp_path)]) == 0
    mine = table(capsys.readouterr().out)
    assert mine["ProtoRes"]["ikd_l2_e3"] > shipped["ProtoRes"]["ikd_l2_e3"]
    assert mine["Masked-FCR"]["ikd_l2_e3"] == shipped["Masked-FCR"]["ikd_l2_e3"]  # not in the folder: the shipped one
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["bench", "protores", "--weights", str(empty)]) == 2
    assert "holds no .pt file" in capsys.readouterr().err


def test_the_shipped_protores_beats_fabrik_and_dls_on_the_5_point_benchmark(mini):
    """The shipped ProtoRes (a user's hour of two cores, README): on the 5-point benchmark its L_ikd-L2 is below
    FABRIK's and DLS's — the paper's key claim, which a quarter hour of one core did not reach."""
    from posekit.evaluation.effector_scores import run_classical, scores
    from posekit.models.protores.solver import run_learned

    b = load_benchmark("5point", mini)
    r = run_learned(ProtoResSolver(mini.skeleton, arch="protores"), b)
    mine = scores(b, r["global_pos"], r["local_rot"], r["global_rot"])["ikd_l2"]
    for method in ("fabrik", "dls"):
        c = run_classical(method, b, mini, progress=False)
        assert mine < scores(b, c["global_pos"], c["local_rot"], c["global_rot"])["ikd_l2"], method


def test_studies_shipped_row_is_scored_again_without_touching_the_trained_runs(tmp_path, monkeypatch, capsys):
    """``posekit train protores-studies --shipped``: the shipped row of both study files is scored again from the
    shipped network (a stale row is replaced, not added to), with its width, processes and compute; every trained
    run is kept as it was."""
    import shutil

    from posekit.cli import main
    from posekit.models.protores import studies
    from posekit.models.protores.train import STEPS, WIDTH

    files = {}
    for name, fn in (("ablation", studies.studies_path), ("scaling", studies.scaling_path)):
        files[name] = tmp_path / fn().name
        shutil.copy(fn(), files[name])
        monkeypatch.setattr(studies, f"{'studies' if name == 'ablation' else 'scaling'}_path",
                            lambda p=files[name]: p)
    before = {k: json.loads(p.read_text()) for k, p in files.items()}
    for res in before.values():
        stale = next(r for r in res["rows"] if r["method"].startswith("ProtoRes (shipped"))
        stale["random_ikd_l2_e3"] = 999.0
    for k, p in files.items():
        p.write_text(json.dumps(before[k]))
    assert main(["train", "protores-studies", "--shipped"]) == 0
    assert "the shipped ProtoRes (torchrun" in capsys.readouterr().out
    for k, p in files.items():
        after = json.loads(p.read_text())
        shipped = [r for r in after["rows"] if r["method"].startswith("ProtoRes (shipped")]
        assert len(shipped) == 1 and shipped[0]["random_ikd_l2_e3"] < 10, k
        row = shipped[0]
        assert (row["width"], row["processes"], row["steps"]) == (WIDTH, 2, STEPS["protores"])
        trained = lambda res: [r for r in res["rows"] if not r["method"].startswith("ProtoRes (shipped")]  # noqa: E731
        assert trained(after) == trained(before[k]), k
    row = next(r for r in json.loads(files["scaling"].read_text())["rows"] if r["method"].startswith("ProtoRes (sh"))
    assert row["compute"] == row["parameters"] * row["steps"] * row["batch"]
