"""Lesson 04: structured prediction layers, the AE-GAN (Victor & Meyer, JFIG 2020) and IK by latent
optimisation."""

import numpy as np
import pytest
import torch

from posekit.data import load_sample
from posekit.data.cases import build_cases, case_split
from posekit.data.metrics import body_joints, bone_length_error
from posekit.ik import EFFECTOR_SETS, Effector, make_solver
from posekit.data.pose_vectors import pose_data
from posekit.models.aegan.networks import AEGAN, body_parents, weights_path
from posekit.models.aegan.train import LOSSES, train_aegan
from posekit.models.aegan.solver import LatentOptSolver
from posekit.models.aegan.latent_opt import adam, lbfgs
from posekit.models.aegan.spl import NumpySPL, StructuredPrediction, dense_twin, tree_levels


@pytest.fixture(scope="module")
def shipped(mini):
    return AEGAN.load(weights_path(), skeleton=mini.skeleton)


@pytest.fixture(scope="module")
def tiny(mini, tmp_path_factory):
    """An AE-GAN trained for a few steps (every loss runs), saved and loaded back."""
    path = tmp_path_factory.mktemp("aegan") / "tiny.pt"
    model, report = train_aegan(mini, out=path, progress=False, steps=30, log_every=10)
    return model, report, path


def test_tree_levels_group_joints_by_depth_with_their_ancestors():
    parents = [-1, 0, 1, 0, 3]  # two chains from one root
    lv = tree_levels(parents)
    assert [list(js) for js, _ in lv] == [[0], [1, 3], [2, 4]]
    assert lv[2][1].tolist() == [[1], [3]]  # parent only
    assert tree_levels(parents, "all")[2][1].tolist() == [[1, 0], [3, 0]]  # nearest ancestor first
    with pytest.raises(ValueError, match="no root above it"):
        tree_levels([1, 0])
    with pytest.raises(ValueError, match="ancestors must be"):
        tree_levels(parents, "siblings")


@pytest.mark.parametrize("ancestors", ["parent", "all"])
def test_spl_predicts_in_tree_order_and_numpy_matches_torch(mini, ancestors):
    parents = body_parents(mini.skeleton)
    torch.manual_seed(0)
    layer = StructuredPrediction(10, parents, 3, 8, ancestors)
    h = torch.randn(6, 10, requires_grad=True)
    out = layer(h)
    g = torch.randn_like(out)
    (out * g).sum().backward()
    ref = NumpySPL(layer)
    o, cache = ref.forward(h.detach().numpy())
    assert np.allclose(o, out.detach().numpy(), atol=1e-5)
    assert np.allclose(ref.backward(cache, g.numpy()), h.grad.numpy(), atol=1e-5)
    # a joint's prediction depends on its ancestors' weights, never on a descendant's: change the
    # output weights of the deepest level and the joints above it keep their outputs
    with torch.no_grad():
        layer.w_out[-1].add_(1.0)
    deep = set(layer.levels[-1][0].tolist())
    changed = (layer(h).detach() - out.detach()).reshape(6, -1, 3).abs().amax((0, 2)) > 1e-7
    assert {int(j) for j in np.nonzero(changed.numpy())[0]} == deep


def test_spl_has_fewer_parameters_than_its_dense_twin(mini):
    parents = body_parents(mini.skeleton)
    J = len(parents)
    spl = StructuredPrediction(252, parents, 3, 16)
    dense = dense_twin(252, J, 3, 16)
    n = lambda m: sum(p.numel() for p in m.parameters())  # noqa: E731
    # shared U: 252 * 16 J + 16 J; parents: 3 * 16 per non-root joint; outputs: (16 * 3 + 3) J
    assert n(spl) == 252 * 16 * J + 16 * J + 3 * 16 * (J - 1) + (16 * 3 + 3) * J
    assert n(dense) == 252 * 16 * J + 16 * J + 16 * J * 3 * J + 3 * J
    assert n(spl) < n(dense)


def test_aegan_networks_have_the_papers_shapes(mini):
    train, _, _, _ = case_split(mini)
    d = pose_data(mini, train[:100])
    m = AEGAN.new(mini.skeleton, d.norm)
    c = m.config
    assert c.n_joints == len(body_joints(mini.skeleton)) == 21 and c.n_joints * c.per_joint == 252
    x = torch.as_tensor(d.normalized()[:5])
    z = m.encoder(x)
    assert z.shape == (5, 32) and bool((z.abs() < 1).all())  # tanh range: the prior's cube
    assert m.generator(z).shape == (5, 63)
    assert m.pose_disc(x).shape == (5, 1) and m.latent_disc(z).shape == (5, 1)
    layers = [mod for mod in m.latent_disc.net if isinstance(mod, torch.nn.Linear)]
    assert [lay.out_features for lay in layers] == [256] * 4 + [1]


def test_training_runs_every_loss_is_seeded_and_round_trips(mini, tiny, tmp_path):
    model, report, path = tiny
    assert report["steps"] == 30 and set(LOSSES) <= set(report["curves"])
    assert all(len(report["curves"][k]) == 3 for k in LOSSES)
    assert all(0 <= a <= 1 for a in report["curves"]["acc_x"] + report["curves"]["acc_z"])
    again, _ = train_aegan(mini, out=False, progress=False, steps=30, log_every=10)
    for a, b in zip(model.generator.parameters(), again.generator.parameters()):
        assert torch.equal(a, b)  # one seed, the same weights
    back = AEGAN.load(path, skeleton=mini.skeleton)
    assert back.info["command"].startswith("posekit train aegan --seed 0") and "CC BY-NC" in back.info["licence"]
    x = pose_data(mini, case_split(mini)[1][:50], mirror=False, norm=model.norm).normalized()
    assert np.allclose(back.decode(back.encode(x)), model.decode(model.encode(x)), atol=1e-5)
    with pytest.raises(ValueError, match="unknown setting"):
        train_aegan(mini, out=False, progress=False, stepz=3)


def test_weights_for_another_skeleton_are_refused(mini, shipped):
    other = load_sample().skeleton
    with pytest.raises(ValueError):
        AEGAN.load(weights_path(), skeleton=other)
    with pytest.raises(ValueError, match="trained for skeleton"):
        LatentOptSolver(other, model=shipped)


def test_shipped_space_is_invertible_and_its_prior_decodes_to_poses(mini, shipped):
    from posekit.data.metrics import NaturalnessIndex
    from posekit.models.aegan.latent_space import AEGANSpace, compare_spaces

    train, _, test, _ = case_split(mini)
    x = pose_data(mini, test[::20], mirror=False, norm=shipped.norm).normalized()
    nat = NaturalnessIndex(mini.skeleton, mini.global_pos[train], max_poses=5000)
    r = compare_spaces([AEGANSpace(shipped)], x, mini.skeleton, shipped.norm, nat, mini.global_pos[train[0]],
                       judge=shipped.pose_score, n=200)["AE-GAN"]
    floor = float(np.median(nat.distance(mini.global_pos[test[::20]]))) * 1000
    assert r["x_mm"] < 60 and r["prior"]["natural_mm"] < floor + 20 and 0 <= r["prior"]["real"] <= 1


def _problem(solver, cases, joints):
    return solver.problem(cases.start_pos, joints, cases.target_pos[:, joints])[0]


@pytest.mark.parametrize("optimizer", [adam, lbfgs])
def test_optimisers_lower_eq6_and_stop_within_budget(mini, shipped, optimizer):
    solver = LatentOptSolver(mini.skeleton, model=shipped)
    cases = build_cases(mini, 12, 0, "other-clip")
    joints = mini.skeleton.indices(EFFECTOR_SETS["5"])
    prob = _problem(solver, cases, joints)
    f0 = prob.loss(solver.net, prob.z0)[0]
    z, iters, err = optimizer(solver.net, prob, max_iter=15)
    f1 = prob.loss(solver.net, z)[0]
    assert np.all(f1 <= f0 + 1e-9) and np.median(f1) < 0.5 * np.median(f0)
    assert np.all(iters <= 15) and np.all(np.abs(z) <= 1) and np.isfinite(z).all()
    assert np.allclose(err, prob.loss(solver.net, z)[1], atol=1e-6)  # the errors are those of the codes returned


def test_latent_opt_solves_any_joint_set_and_batch_equals_single(mini, shipped):
    s = mini.skeleton
    solver = make_solver("latent-opt-raw", s)
    cases = build_cases(mini, 6, 0, "same-clip")
    joints = ["left_hand", "right_foot", "head"]  # no network was trained for this set: none needs to be
    effs = [[Effector(j, cases.target_pos[i, s.index(j)], tolerance=0.01) for j in joints] for i in range(6)]
    single = [solver.solve(cases.pose(i), effs[i]) for i in range(6)]
    batch = solver.solve_batch([cases.pose(i) for i in range(6)], effs)
    for a, b in zip(single, batch):
        assert np.allclose(a.pose.global_pos, b.pose.global_pos, atol=1e-5) and a.iterations == b.iterations
    assert np.median([r.effector_error.max() for r in single]) < 0.02
    with pytest.raises(ValueError, match="not a body joint"):
        solver.solve(cases.pose(0), [Effector("joint_Root", cases.target_pos[0, 0])])


def test_bad_input_nan_and_unreachable(mini):
    s = mini.skeleton
    solver = make_solver("latent-opt", s)
    start = build_cases(mini, 1, 0, "rest").pose(0)
    with pytest.raises(ValueError):
        solver.solve(start, [Effector("left_hand", [np.nan, 1.0, 0.0])])
    far = start.global_pos[s.index("left_hand")] + [0.0, 5.0, 0.0]  # 5 m above: out of any pose's reach
    res = solver.solve(start, [Effector("left_hand", far)])
    assert np.isfinite(res.pose.global_pos).all() and not res.converged
    assert res.iterations <= solver.options["max_iter"] and res.info["out_of_range"] == [s.names[s.index("left_hand")]]
    ref = mini.global_pos[0][None]
    assert bone_length_error(s, res.pose.global_pos[None], ref)[0] < 1e-6  # post-processing keeps every bone
    with pytest.raises(ValueError, match="optimizer must be"):
        make_solver("latent-opt", s, optimizer="sgd")
    with pytest.raises(ValueError, match="unknown option"):
        make_solver("latent-opt", s, momentum=0.9)


def test_bench_ik_runs_latent_rows(mini):
    from posekit.bench import ik as bench_ik

    rows = bench_ik.run(mini, solvers=("latent-opt",), effector_sets=("2",), n_cases=5, start="rest",
                        methods="latent-variants,latent-batched", natural=False)
    methods = {r["method"] for r in rows}
    assert methods == {"latent-opt", "latent-opt-raw", "latent-opt-adam", "latent-opt-adam-raw",
                       "latent-opt-raw batched", "latent-opt batched"}
    row = next(r for r in rows if r["method"] == "latent-opt")
    assert row["model_kb"] > 0 and row["solver_kb"] == 0
    assert all(r["solves_per_s"] > 0 for r in rows if "batched" in r["method"])


def test_compiled_path_matches_numpy(mini, shipped):
    """The numba kernels of one problem compute what the batched numpy path computes: Eq. (6) and its
    gradient to float32 rounding; the optimisers' iterations and results agree in distribution (an
    iterative solve amplifies rounding, so a rare problem may settle in another local minimum)."""
    from posekit.models.aegan import fast as LK

    solver = LatentOptSolver(mini.skeleton, model=shipped, post="none")
    cases = build_cases(mini, 40, 0, "other-clip")
    joints = mini.skeleton.indices(EFFECTOR_SETS["5"])
    prob = _problem(solver, cases, joints)
    gen, work = LK.flatten_generator(solver.net), LK.workspace(LK.flatten_generator(solver.net))
    z = np.random.default_rng(0).uniform(-1, 1, (5, 32)).astype(np.float32)
    f_np, err_np, g_np = prob.loss(solver.net, z, np.arange(5))
    for i in range(5):
        err, g = np.zeros(len(joints)), np.zeros(32, np.float32)
        f = LK.loss_grad(z[i], prob.columns, prob.target[i], prob.scale, *gen,
                        LK.needed_joints(prob.columns, gen[4], gen[5]), work, err, g)
        assert np.isclose(f, f_np[i], rtol=1e-4) and np.allclose(err, err_np[i], atol=1e-6)
        assert np.allclose(g, g_np[i], rtol=1e-3, atol=1e-5 * np.abs(g_np[i]).max())
    pos_b, _, it_b, _ = solver.predict(cases.start_pos, joints, cases.target_pos[:, joints])
    one = [solver.predict_one(cases.start_pos[i], joints, cases.target_pos[i, joints]) for i in range(len(cases))]
    pos_s, it_s = np.stack([o[0] for o in one]), np.array([o[2] for o in one])
    eff = lambda p: np.median(np.linalg.norm(p[:, joints] - cases.target_pos[:, joints], axis=-1).max(-1))  # noqa: E731
    assert abs(eff(pos_s) - eff(pos_b)) < 2e-3 and abs(np.median(it_s) - np.median(it_b)) <= 3
    assert np.median(np.abs(pos_s - pos_b).max((1, 2))) < 0.01


def test_checkers_accept_a_right_answer_and_reject_a_wrong_one(capsys):
    """Lesson 04's checkers on answers written here (tests/test_exercises.py lists every wrong answer and right
    variant of each)."""
    from posekit.exercises import check_adversarial, check_latent_loss

    def loss(x, t, cols, sc):
        diff = (x[cols] - t) * sc
        g = np.zeros_like(x)
        g[cols] = 2 * diff * sc
        return (diff ** 2).sum(), g

    def adversarial(real, fake, s):
        sig = lambda v: 0.5 * (1 + np.tanh(v / 2))  # noqa: E731 - finite everywhere
        loss_d = np.mean(s * np.logaddexp(0, -real) + (1 - s) * np.logaddexp(0, real)) + np.mean(np.logaddexp(0, fake))
        return (loss_d, (sig(real) - s) / len(real), sig(fake) / len(fake), np.mean(np.logaddexp(0, -fake)),
                (sig(fake) - 1) / len(fake))

    assert check_latent_loss(loss) and check_adversarial(adversarial)
    assert not check_latent_loss(lambda x, t, c, s: (np.sum(((x[c] - t)) ** 2), np.zeros_like(x)))  # forgot metres

    def saturating(real, fake, s):
        out = list(adversarial(real, fake, s))
        out[3] = np.mean(-np.logaddexp(0, fake))  # log(1 - sigmoid(l))
        return tuple(out)

    assert not check_adversarial(saturating)
    assert "the saturating form" in capsys.readouterr().out
