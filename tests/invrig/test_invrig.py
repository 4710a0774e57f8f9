"""Lesson 02: the rig, the animator, GPR, Jacobian refinement, supersampling, the network."""


import numpy as np
import pytest

from posekit import rest_pose
from posekit.kinematics import bone_lengths_of
from posekit.invrig import (GPR, KERNELS, METHODS, LearnedJacobian, greedy_subsample, line_search_theta0,
                                refine, sample_controls)
from posekit.invrig.nn import load_inverse_net, train_inverse_net
from posekit.invrig.nn import weights_path
from posekit.invrig import HumanoidRig, animate, heuristic_inverse, standard_sets


@pytest.fixture(scope="module")
def rig(skel):
    return HumanoidRig(skel)


@pytest.fixture(scope="module")
def data(rig):
    train, test, clip = standard_sets(rig)
    return train, rig.evaluate(train), test, rig.evaluate(test)


# ------------------------------------------------------------------ rig
def test_rig_default_is_the_rest_pose_on_the_floor(rig, skel):
    rest = rest_pose(skel)
    rest = rest - [0, rest[:, 1].min(), 0]
    np.testing.assert_allclose(rig.evaluate(rig.default()), rest, atol=1e-3)
    assert 30 <= rig.n_controls <= 60


def test_rig_keeps_bones_and_places_ik_handles(rig, skel, data):
    train, X, _, _ = data
    np.testing.assert_allclose(bone_lengths_of(skel, X), np.broadcast_to(skel.bone_lengths(), X.shape[:2]), atol=1e-9)
    reach = np.linalg.norm(train[:, [rig.index(f"l_hand_{a}") for a in "xyz"]] - X[:, skel.index("left_shoulder")], axis=1)
    inside = reach < 0.99 * skel.bone_lengths()[[skel.index("left_elbow"), skel.index("left_hand")]].sum()
    np.testing.assert_allclose(X[inside, skel.index("left_hand")],
                               train[inside][:, [rig.index(f"l_hand_{a}") for a in "xyz"]], atol=1e-9)


def test_rig_is_not_injective_and_has_dead_controls(rig):
    y = rig.default()
    a, b, c = y.copy(), y.copy(), y.copy()
    a[rig.index("root_pitch")] = 0.4
    b[rig.index("spine_lower_bend")] = 0.4
    c[rig.index("root_pitch")] = c[rig.index("spine_lower_bend")] = 0.2
    np.testing.assert_allclose(rig.evaluate(a), rig.evaluate(b), atol=1e-12)
    np.testing.assert_allclose(rig.evaluate(a), rig.evaluate(c), atol=1e-12)
    assert np.abs(rig.evaluate(a) - rig.evaluate(y)).max() > 0.1
    d = y.copy()
    d[rig.index("jaw_open")] = 1.0
    np.testing.assert_array_equal(rig.evaluate(d), rig.evaluate(y))


def test_rig_jacobian_matches_finite_differences(rig, data):
    y = data[0][[10, 500]]
    J = rig.jacobian(y)
    assert J.shape == (2, 54, rig.n_controls)
    k = rig.index("neck_turn")
    step = np.zeros(rig.n_controls)
    step[k] = 1e-6
    fd = (rig.evaluate(y + step) - rig.evaluate(y - step)).reshape(2, -1) / 2e-6
    np.testing.assert_allclose(J[:, :, k], fd, atol=1e-5)


def test_a_pose_evaluates_to_the_same_bits_whatever_else_is_in_the_call(rig, data):
    """refine takes the rig's value at y from its Jacobian's call (``value=True``), and evaluate solves the four
    limbs in one call: each pose's numbers must not depend on its neighbours."""
    y = data[0][:7]
    alone = np.stack([rig.evaluate(y[i]) for i in range(len(y))])
    assert np.array_equal(rig.evaluate(y), alone)
    x, J = rig.jacobian(y, value=True)
    assert np.array_equal(x, alone.reshape(len(y), -1)) and np.array_equal(J, rig.jacobian(y))
    assert np.array_equal(rig.jacobian(y[3:4]), J[3:4])


def test_rig_clamps_and_reports_and_refuses_nan(rig):
    y = rig.default()
    y[rig.index("neck_turn")] = 5.0
    c, rep = rig.clamp(y)
    assert c[rig.index("neck_turn")] == rig.high[rig.index("neck_turn")]
    assert rep.count == 1 and "neck_turn" in str(rep)
    with pytest.warns(RuntimeWarning, match="clamped: 1 values clamped; worst per control: neck_turn by 3.8"):
        np.testing.assert_allclose(rig.evaluate(y), rig.evaluate(c))
    with pytest.raises(ValueError, match="NaN"):
        rig.evaluate(np.full(rig.n_controls, np.nan))
    with pytest.raises(ValueError, match=r"expected shape \(\.\.\., 34\)"):
        rig.evaluate(np.zeros(33))
    with pytest.raises(ValueError, match="unknown rig control 'tail'"):
        rig.index("tail")


def test_animator_is_seeded_smooth_and_test_is_more_extreme(rig, data):
    train, _, test, _ = data
    again, _ = animate(rig, 20, 200, 20, 1.0, seed=0)
    np.testing.assert_array_equal(train, again)
    assert np.all(train >= rig.low) and np.all(train <= rig.high)
    step = np.abs(np.diff(train.reshape(20, 200, -1), axis=1)).max()
    assert step < 0.3
    angles = [rig.index(n) for n in ("spine_upper_bend", "neck_turn", "spine_twist")]
    assert np.all(test[:, angles].std(0) > train[:, angles].std(0))
    np.testing.assert_array_equal(train[:, rig.index("jaw_open")], 0.0)


def test_heuristic_copies_handles(rig, data):
    _, _, test, Xt = data
    y = heuristic_inverse(rig, Xt)
    np.testing.assert_allclose(y[:, [rig.index(f"r_foot_{a}") for a in "xyz"]],
                               Xt[:, rig.skeleton.index("right_foot")], atol=1e-9)
    with pytest.raises(ValueError, match="NaN"):
        heuristic_inverse(rig, np.full_like(Xt[:2], np.nan))
    with pytest.raises(ValueError, match=r"expected shape \(N, 18, 3\)"):
        heuristic_inverse(rig, Xt[:, :-1])


# ------------------------------------------------------------------ GPR
def test_squared_exponential_matches_scikit_learn(rng):
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF

    X, Xq = rng.normal(size=(60, 4)), rng.normal(size=(9, 4))
    Y = np.sin(X @ rng.normal(size=(4, 2)))
    ours = GPR("squared_exponential", theta0=1.3, theta1=1e-2).fit(X, Y)
    sk = GaussianProcessRegressor(RBF(1.3), alpha=1e-2, optimizer=None, normalize_y=True)
    sk.fit(ours.x_norm.normalize(X), Y)
    np.testing.assert_allclose(ours.predict(Xq), sk.predict(ours.x_norm.normalize(Xq)), atol=1e-8)


def test_multiquadric_kernel_is_indefinite_but_solved(rng):
    X = rng.normal(size=(50, 5))
    eig = np.linalg.eigvalsh(KERNELS["multiquadric"][0](X, X, 1.0))
    assert (eig > 0).sum() == 1  # conditionally negative definite: no Cholesky
    Y = rng.normal(size=(50, 3))
    m = GPR("multiquadric", 1.0, 1e-8).fit(X, Y)
    np.testing.assert_allclose(m.predict(X), Y, atol=1e-4)  # interpolates with tiny regularisation


def test_ill_conditioned_kernel_gets_jitter_not_nan(rng):
    X = np.repeat(rng.normal(size=(10, 3)), 3, axis=0)  # every row three times
    Y = rng.normal(size=(30, 2))
    with pytest.warns(RuntimeWarning, match="jitter"):
        m = GPR("squared_exponential", 1.0, 0.0).fit(X, Y)
    assert m.jitter > 0 and np.all(np.isfinite(m.predict(X)))


def test_gpr_bad_queries(rng):
    m = GPR().fit(rng.normal(size=(10, 3)), rng.normal(size=(10, 2)))
    with pytest.raises(ValueError, match="NaN"):
        m.predict(np.array([[np.nan, 0, 0]]))
    with pytest.raises(ValueError, match="expected 3 features per row, got 4"):
        m.predict(np.zeros((2, 4)))
    with pytest.raises(ValueError, match="unknown kernel"):
        GPR("cosine")


def test_line_search_and_greedy_subsampling(data):
    train, X, test, Xt = data
    X = X.reshape(len(X), -1)
    best, table = line_search_theta0(X[::8], train[::8])
    assert len(table) == 13 and 1e-4 <= best <= 1e2 and best == min(table, key=lambda r: r[1])[0]
    # the linear kernel barely feels theta0 (its CV errors differ ~1e-12): a tie, which must not be
    # decided by rounding noise but by the documented rule (the smallest theta0)
    best_lin, table_lin = line_search_theta0(X[::8], train[::8], "linear")
    errs = np.array([e for _, e in table_lin])
    assert np.ptp(errs) < 1e-6 * errs.min() and best_lin == table_lin[0][0] == 1e-4
    idx = greedy_subsample(X, train, 300, theta0=best)
    assert len(set(idx)) == 300
    sd = np.maximum(train.std(0), 1e-3)
    # the subsample stands in for the whole animation: it should predict the animation better than
    # a random subsample of the same size
    err = lambda rows: np.mean(np.abs(GPR("multiquadric", best).fit(X[rows], train[rows]).predict(X) - train) / sd)
    rand = np.random.default_rng(0).choice(len(X), 300, replace=False)
    assert err(idx) < err(rand)


# ------------------------------------------------------------------ Jacobians, sampling, network
def test_refinement_reduces_joint_error(rig, data):
    train, _, test, Xt = data
    y0 = heuristic_inverse(rig, Xt[:50])
    before = np.linalg.norm(rig.evaluate(y0) - Xt[:50], axis=-1).mean()
    after = np.linalg.norm(rig.evaluate(refine(rig, Xt[:50], y0, "computed", 3)) - Xt[:50], axis=-1).mean()
    assert after < 0.5 * before
    lj = LearnedJacobian(rig, train[::20], theta0=1.0)
    J = rig.jacobian(train[5:6])
    assert np.linalg.norm(lj(train[5:6]) - J) < 0.5 * np.linalg.norm(J)


@pytest.mark.parametrize("method", METHODS)
def test_sampling_methods(rig, data, method):
    train = data[0]
    s = sample_controls(method, train, 3000, rig.low, rig.high, seed=1)
    assert s.shape == (3000, rig.n_controls) and np.all(s >= rig.low) and np.all(s <= rig.high)
    used = train.std(0) > 1e-6
    assert np.abs(s.mean(0) - train.mean(0))[used].max() < 0.5 * (rig.high - rig.low)[used].max()


@pytest.mark.parametrize("method", METHODS)
def test_sampling_follows_its_data(method):
    # synthetic controls with a different mean and spread per control and two strongly correlated
    # controls: a sampler that ignored its data (or its correlations, where it claims to model
    # them) would fail here
    rng = np.random.default_rng(3)
    mu, sd = rng.uniform(-1, 1, 6), rng.uniform(0.05, 0.3, 6)
    Y = rng.normal(mu, sd, size=(4000, 6))
    Y[:, 1] = mu[1] + (Y[:, 0] - mu[0]) / sd[0] * sd[1] + rng.normal(0, 0.02 * sd[1], 4000)
    s = sample_controls(method, Y, 4000, np.full(6, -10.0), np.full(6, 10.0), seed=2)
    # uniform samples the data's box, whose centre (the mid-range) sits off the mean by chance
    assert np.all(np.abs(s.mean(0) - mu) < (0.5 if method == "uniform" else 0.25) * sd), np.abs(s.mean(0) - mu) / sd
    ratio = s.std(0) / Y.std(0)
    assert np.all((ratio > 0.5) & (ratio < (2.5 if method == "uniform" else 1.5))), ratio
    assert s.min(0).min() >= -10 and s.max(0).max() <= 10
    corr = np.corrcoef(s[:, 0], s[:, 1])[0, 1]
    if method in ("mvn", "gmm", "pca"):
        assert corr > 0.9, corr
    else:  # independent per-control samplers lose the correlation: the lesson's point
        assert abs(corr) < 0.1, corr


def test_network_trains_and_shipped_weights_check_their_rig(rig, data, tmp_path):
    train, X, test, Xt = data
    net, losses = train_inverse_net(X[:2000], train[:2000], epochs=3, hidden=64, progress=False)
    assert losses[-1] < losses[0]
    shipped = load_inverse_net(weights_path("pca"), rig.names, rig.skeleton.names)
    y = shipped.predict(Xt[:10])
    assert y.shape == (10, rig.n_controls) and np.all(np.isfinite(y))
    with pytest.raises(ValueError, match="trained for rig controls"):
        load_inverse_net(weights_path("pca"), rig.names[:-1], rig.skeleton.names)
    with pytest.raises(ValueError, match="trained for skeleton joints"):
        load_inverse_net(weights_path("pca"), rig.names, list(rig.skeleton.names)[::-1])
    with pytest.raises(ValueError, match="NaN"):
        shipped.predict(np.full((1, 54), np.nan))
