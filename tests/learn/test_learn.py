"""posekit.learn: checkpoints that refuse what they were not made for, the seeded training loop,
the one-thread context, and ``posekit train --list``."""

import numpy as np
import pytest
import torch

from posekit.cli import build_parser, main
from posekit.data.dataset import NormStats
from posekit.learn import Curves, fit, load_checkpoint, save_checkpoint, single_thread
from posekit.skeleton import Skeleton


@pytest.fixture
def toy():
    skel = Skeleton(["hips", "knee", "foot"], [-1, 0, 1], [[0, 1, 0], [0, -0.45, 0.01], [0, -0.42, 0]],
                    roles={"pelvis": "hips"}, name="toy")
    torch.manual_seed(0)
    net = torch.nn.Sequential(torch.nn.Linear(9, 8), torch.nn.ReLU(), torch.nn.Linear(8, 2))
    rng = np.random.default_rng(0)
    norms = {"x": NormStats.fit(rng.normal(size=(50, 9))), "y": NormStats.fit(rng.normal(size=(50, 2)))}
    config = {"n_in": 9, "n_out": 2, "hidden": 8, "l1": 1e-4, "controls": ["a", "b"], "nested": {"k": [1, 2.5]},
              "flag": True, "none": None}
    return skel, net, norms, config


def _save(path, toy, **kw):
    skel, net, norms, config = toy
    args = dict(kind="toy", config=config, skeleton=skel, norms=norms, command="posekit train toy --seed 3",
                seed=3, data="three random poses", licence="CC0", extra={"curve": np.arange(4.0), "n": 7})
    args.update(kw)
    return save_checkpoint(path, net, **args)


def test_checkpoint_round_trip_is_exact(tmp_path, toy):
    skel, net, norms, config = toy
    path = _save(tmp_path / "toy.pt", toy)
    torch.load(path, weights_only=True)  # only tensors and plain values: safe loading works
    d = load_checkpoint(path, kind="toy", skeleton=skel, norms=norms, expect={"hidden": 8, "controls": ("a", "b")})
    for k, v in net.state_dict().items():
        assert torch.equal(d["state"][k], v)
    assert d["config"] == config
    s = d["skeleton"]
    assert s.names == skel.names and s.name == "toy" and s.roles == {"pelvis": "hips"}
    assert np.array_equal(s.parents, skel.parents) and np.array_equal(s.offsets, skel.offsets)
    for name, ns in norms.items():
        assert np.array_equal(d["norms"][name].mean, ns.mean) and np.array_equal(d["norms"][name].std, ns.std)
    assert (d["command"], d["seed"], d["data"], d["licence"]) == ("posekit train toy --seed 3", 3,
                                                                  "three random poses", "CC0")
    assert np.array_equal(d["extra"]["curve"], np.arange(4.0)) and d["extra"]["n"] == 7
    rebuilt = torch.nn.Sequential(torch.nn.Linear(9, 8), torch.nn.ReLU(), torch.nn.Linear(8, 2))
    rebuilt.load_state_dict(d["state"])
    x = torch.randn(5, 9)
    assert torch.equal(rebuilt(x), net(x))


def test_half_checkpoint_is_smaller_and_loads_as_float32(tmp_path, toy):
    big = torch.nn.Linear(64, 64)
    full = save_checkpoint(tmp_path / "f.pt", big, kind="toy", config={})
    half = save_checkpoint(tmp_path / "h.pt", big, kind="toy", config={}, half=True)
    assert half.stat().st_size < 0.7 * full.stat().st_size
    d = load_checkpoint(half)
    assert d["half"] and d["state"]["weight"].dtype == torch.float32
    assert torch.equal(d["state"]["weight"], big.weight.detach().half().float())


def _other_skeleton(skel, names=None, parents=None, offsets=None):
    return Skeleton(names or skel.names, skel.parents if parents is None else parents,
                    skel.offsets if offsets is None else offsets)


@pytest.mark.parametrize("case, match", [
    ("names", r"trained for skeleton joints other than this skeleton's: 1 of 3 joint names differ \(joint 2 is "
              r"'foot' there, 'toe' here\)$"),
    ("parents", r"trained for skeleton parents other than this skeleton's: 1 joint\(s\) hang from another parent "
                r"\(joint 'foot': parent 1 there, 0 here\)$"),
    ("offsets", r"trained for other skeleton offsets: joint 'knee'"),
    ("norm", r"normalisation 'x' differs from the one given \(mean differs by up to 0.5"),
    ("norm_missing", r"has no normalisation 'z' \(it has: \['x', 'y'\]\)"),
    ("kind", r"holds a 'toy' model, expected kind 'protores'"),
    ("config", r"config field 'hidden' is 8, expected 2048"),
    ("config_missing", r"has no config field 'depth'"),
])
def test_mismatch_is_refused_naming_the_field(tmp_path, toy, case, match):
    skel, net, norms, config = toy
    path = _save(tmp_path / "toy.pt", toy)
    off = np.array(skel.offsets)
    off[1, 1] += 0.05
    kw = {
        "names": dict(skeleton=_other_skeleton(skel, names=["hips", "knee", "toe"])),
        "parents": dict(skeleton=_other_skeleton(skel, parents=[-1, 0, 0])),
        "offsets": dict(skeleton=_other_skeleton(skel, offsets=off)),
        "norm": dict(norms={"x": NormStats(norms["x"].mean + 0.5, norms["x"].std)}),
        "norm_missing": dict(norms={"z": norms["x"]}),
        "kind": dict(kind="protores"),
        "config": dict(expect={"hidden": 2048}),
        "config_missing": dict(expect={"depth": 3}),
    }[case]
    with pytest.raises(ValueError, match=match) as e:
        load_checkpoint(path, **kw)
    assert str(path) in str(e.value)


def test_other_format_version_is_refused(tmp_path, toy):
    path = _save(tmp_path / "toy.pt", toy)
    d = torch.load(path, weights_only=True)
    d["version"] = 99
    torch.save(d, path)
    with pytest.raises(ValueError, match=r"format version 99, this posekit reads version 1; remake it with "
                                         r"`posekit train toy --seed 3`"):
        load_checkpoint(path)


def test_corrupt_or_foreign_files_give_a_clear_error(tmp_path, toy):
    good = _save(tmp_path / "toy.pt", toy).read_bytes()
    garbage = tmp_path / "garbage.pt"
    garbage.write_bytes(b"this is not a checkpoint at all")
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(good[: len(good) // 2])
    unsafe = tmp_path / "unsafe.pt"  # pickles a numpy array: refused by weights_only loading
    torch.save({"state": {}, "x_mean": np.zeros(3)}, unsafe)
    for p in (garbage, truncated, unsafe):
        with pytest.raises(ValueError, match="is not a readable posekit checkpoint") as e:
            load_checkpoint(p)
        assert str(p) in str(e.value)
    foreign = tmp_path / "foreign.pt"
    torch.save({"state": {"w": torch.zeros(2)}}, foreign)
    with pytest.raises(ValueError, match="is not a posekit checkpoint"):
        load_checkpoint(foreign)
    with pytest.raises(FileNotFoundError, match="missing.pt"):
        load_checkpoint(tmp_path / "missing.pt")
    with pytest.raises(TypeError, match=r"config\['bad'\]: cannot store a set"):
        _save(tmp_path / "x.pt", toy, config={"bad": {1, 2}})


def _regression(seed=0, n=300):
    g = torch.Generator().manual_seed(seed)
    x = torch.randn(n, 4, generator=g)
    y = x @ torch.tensor([[1.0], [-2.0], [0.5], [0.0]]) + 0.1 * torch.randn(n, 1, generator=g)
    return x, y


def _mlp(seed=0):
    torch.manual_seed(seed)
    return torch.nn.Sequential(torch.nn.Linear(4, 16), torch.nn.Tanh(), torch.nn.Linear(16, 1))


def _mse(model, x, y):
    return torch.mean((model(x) - y) ** 2)


def _weights(model):
    return [p.detach().clone() for p in model.parameters()]


def test_fit_is_reproducible_for_a_seed():
    data, val = _regression(0), _regression(1, 100)
    runs = []
    for seed in (0, 0, 1):
        m = _mlp()
        c = fit(m, _mse, data, val, epochs=4, batch=32, lr=1e-2, seed=seed, progress=False)
        runs.append((c, _weights(m)))
    (c0, w0), (c1, w1), (c2, w2) = runs
    assert isinstance(c0, Curves) and c0.epochs == 4 and len(c0.val) == 4 and c0.seconds > 0
    assert c0.train == c1.train and c0.val == c1.val and all(torch.equal(a, b) for a, b in zip(w0, w1))
    assert c0.train != c2.train and not all(torch.equal(a, b) for a, b in zip(w0, w2))
    assert c0.train[-1] < c0.train[0] and not c0.stopped_early


def test_fit_follows_the_documented_loop_bit_for_bit():
    """The loop of lesson 02's first network (what made the shipped weights): changing the order
    of shuffling, batches or optimizer steps would move the lesson's numbers."""
    x, y = _regression(0)
    m = _mlp()
    fit(m, _mse, (x, y), epochs=3, batch=64, lr=1e-3, seed=5, progress=False)
    ref = _mlp()
    opt = torch.optim.Adam(ref.parameters(), lr=1e-3)
    g = torch.Generator().manual_seed(5)
    for _ in range(3):
        perm = torch.randperm(len(x), generator=g)
        for k in range(0, len(x), 64):
            idx = perm[k:k + 64]
            loss = _mse(ref, x[idx], y[idx])
            opt.zero_grad()
            loss.backward()
            opt.step()
    assert all(torch.equal(a, b) for a, b in zip(_weights(m), _weights(ref)))


def test_early_stopping_restores_the_best_epoch():
    # train on y = 2x, validate on y = x: from w = 0 the weight walks past 1, so the validation
    # loss falls, then rises
    g = torch.Generator().manual_seed(0)
    x = torch.randn(256, 1, generator=g)
    xv = torch.randn(128, 1, generator=g)

    def line():
        m = torch.nn.Linear(1, 1, bias=False)
        torch.nn.init.zeros_(m.weight)
        return m

    kw = dict(batch=32, lr=0.02, seed=0, optimizer="sgd", progress=False)
    full = line()
    c_full = fit(full, _mse, (x, 2 * x), (xv, xv), epochs=8, **kw)
    assert not c_full.stopped_early and c_full.epochs == 8
    best = int(np.argmin(c_full.val))
    assert 0 < best < 5 and c_full.val[-1] > c_full.val[best]  # it really falls, then rises

    stopped = line()
    c = fit(stopped, _mse, (x, 2 * x), (xv, xv), epochs=8, patience=2, **kw)
    assert c.stopped_early and c.best_epoch == best and c.epochs == best + 3
    assert c.val == c_full.val[:best + 3]
    at_best = line()
    fit(at_best, _mse, (x, 2 * x), (xv, xv), epochs=best + 1, **kw)
    assert torch.equal(stopped.weight, at_best.weight) and not torch.equal(stopped.weight, full.weight)
    with pytest.raises(ValueError, match="patience"):
        fit(line(), _mse, (x, 2 * x), epochs=2, patience=1, **kw)


def test_fit_refuses_a_nan_loss():
    x, y = _regression(0, 64)
    y[3] = float("nan")
    with pytest.raises(ValueError, match="NaN"):
        fit(_mlp(), _mse, (x, y), epochs=1, batch=16, lr=1e-3, seed=0, progress=False)


def test_single_thread_restores_the_thread_count():
    from threadpoolctl import threadpool_info

    before = torch.get_num_threads()
    torch.set_num_threads(2)
    try:
        with single_thread():
            assert torch.get_num_threads() == 1
            assert all(p["num_threads"] == 1 for p in threadpool_info())
        assert torch.get_num_threads() == 2
        with pytest.raises(RuntimeError), single_thread():
            raise RuntimeError("inside")
        assert torch.get_num_threads() == 2
    finally:
        torch.set_num_threads(before)


def test_shipped_invrig_weights_carry_their_provenance(sample):
    from posekit.invrig.nn import load_inverse_net
    from posekit.invrig.nn import weights_path
    from posekit.invrig import HumanoidRig

    skel = sample.skeleton
    d = load_checkpoint(weights_path("pca"), kind="invrig_nn", skeleton=skel,
                        expect={"hidden": 2048, "n_in": 3 * skel.n_joints, "l1": 1e-4})
    assert d["command"] == "posekit train invrig --methods pca --samples 20000 --epochs 20 --seed 0"
    assert d["seed"] == 0 and "deepmimic_humanoid.npz" in d["data"] and "sampling pca" in d["data"]
    assert "MIT" in d["licence"] and "Peng" in d["licence"] and d["half"]
    rig = HumanoidRig(skel)
    net = load_inverse_net(weights_path("pca"), rig.names, skel)  # a Skeleton is checked in full
    assert net.meta["seed"] == 0 and net.x_norm.same_as(d["norms"]["x"])
    off = np.array(skel.offsets)
    off[5] *= 1.1
    moved = Skeleton(skel.names, skel.parents, off)
    with pytest.raises(ValueError, match="trained for other skeleton offsets: joint 'right_elbow'"):
        load_inverse_net(weights_path("pca"), rig.names, moved)


def _train_names():
    train = build_parser()._subparsers._group_actions[0].choices["train"]
    return set(train._subparsers._group_actions[0].choices)


@pytest.mark.parametrize("argv", [["train", "--list"], ["train"]])
def test_train_list_names_every_trainable_model(capsys, argv):
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "invrig" in out and "invrig_nn_{uniform,gaussian,mvn,gmm,pca}.pt" in out and "lesson 02" in out
    listed = {line.split()[0] for line in out.splitlines() if line.startswith("  ") and not line.startswith("   ")}
    assert listed == _train_names() == {"invrig", "ae-solvers", "ae-studies", "aegan", "protores", "protores-studies"}
    assert "ae_solvers.pt" in out and "CC BY-NC 4.0" in out and "lesson 03" in out


def test_fit_refuses_a_nan_validation_loss():
    import torch

    from posekit.learn import fit

    torch.manual_seed(0)
    model = torch.nn.Linear(2, 1)
    x, y = torch.randn(32, 2), torch.randn(32, 1)
    bad = (torch.full((8, 2), float("nan")), torch.randn(8, 1))
    loss = lambda m, a, b: ((m(a) - b) ** 2).mean()
    with pytest.raises(ValueError, match="validation loss"):
        fit(model, loss, (x, y), bad, epochs=2, batch=8, lr=1e-2, seed=0, patience=1, progress=False)
