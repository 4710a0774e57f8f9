"""Posing with learned solvers without torch: the checkpoint reader and the numpy networks read from files."""

import collections
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import torch

from posekit.io.torch_file import read_torch_file
from posekit.paths import samples_dir

WEIGHTS = sorted((samples_dir() / "weights").rglob("*.pt"))  # every shipped checkpoint, in any subfolder


def _same(a, b, where="") -> None:
    if isinstance(b, torch.Tensor):
        assert isinstance(a, np.ndarray), where
        assert a.dtype == b.numpy().dtype and a.shape == tuple(b.shape), where
        assert np.array_equal(a, b.numpy()), where
    elif isinstance(b, dict):
        assert list(a) == list(b), where
        for k in b:
            _same(a[k], b[k], f"{where}.{k}")
    elif isinstance(b, (list, tuple)):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{where}[{i}]")
    else:
        assert a == b, where


@pytest.mark.parametrize("path", WEIGHTS, ids=lambda p: p.relative_to(samples_dir() / "weights").as_posix())
def test_reader_gives_what_torch_load_gives(path):
    _same(read_torch_file(path), torch.load(path, map_location="cpu", weights_only=True))


def test_reader_handles_views_scalars_and_every_storage_type(tmp_path):
    x = torch.arange(24.0).reshape(4, 6)
    obj = {"view": x[:, 2:5], "t": x.t(), "scalar": torch.tensor(3.5), "bool": torch.tensor([True, False]),
           "long": torch.arange(5), "half": x.half()[1], "double": x.double(), "empty": torch.zeros(0, 3),
           "int8": torch.tensor([-3, 4], dtype=torch.int8), "nested": [(1, "a"), {"k": None}],
           "od": collections.OrderedDict(a=torch.ones(2))}
    torch.save(obj, tmp_path / "odd.pt")
    _same(read_torch_file(tmp_path / "odd.pt"), torch.load(tmp_path / "odd.pt", weights_only=True))


def test_reader_refuses_other_objects_and_bad_files(tmp_path):
    torch.save({"x": collections.Counter("ab")}, tmp_path / "counter.pt")
    with pytest.raises(ValueError, match="collections.Counter is not a plain value"):
        read_torch_file(tmp_path / "counter.pt")
    (tmp_path / "cut.pt").write_bytes(WEIGHTS[0].read_bytes()[:4000])
    with pytest.raises(ValueError, match="not a zip-format torch file"):
        read_torch_file(tmp_path / "cut.pt")
    with pytest.raises(FileNotFoundError):
        read_torch_file(tmp_path / "missing.pt")


def test_learned_solvers_pose_without_importing_torch():
    code = textwrap.dedent("""
        import sys
        import numpy as np
        from posekit.data.bandai_mini import load_bandai_mini
        from posekit.ik import effector_set, make_solver, solver_names
        from posekit.viz.studio_app import studio_case
        m = load_bandai_mini()
        start, goal, effectors, _ = studio_case(m)
        names = solver_names()
        for name in ("neural", "neural+dls", "latent-opt", "latent-opt+dls", "protores", "protores-masked-fcr",
                     "protores+dls"):
            r = make_solver(name, m.skeleton).solve(start, effectors)
            assert np.isfinite(r.pose.global_pos).all(), name
        print("torch" in sys.modules, len(names))
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-3000:]
    torch_loaded, n = out.stdout.split()
    assert torch_loaded == "False" and int(n) >= 19


def test_numpy_networks_read_from_files_equal_the_torch_ones(mini):
    from posekit.models.aegan.networks import AEGAN
    from posekit.models.aegan.numpy_nets import NumpyAEGAN
    from posekit.models.aegan.numpy_nets import weights_path as aegan_path
    from posekit.models.pose_autoencoder.networks import AESolvers
    from posekit.models.pose_autoencoder.numpy_nets import NumpyAESolvers
    from posekit.models.pose_autoencoder.numpy_nets import weights_path as ae_path
    from posekit.models.protores.fast import NumpyPosingNet, weights_path
    from posekit.models.protores.networks import PosingNet

    rng = np.random.default_rng(0)
    for arch in ("protores", "masked-fcr"):
        net = PosingNet.load(weights_path(arch))
        a, b = NumpyPosingNet.load(weights_path(arch), mini.skeleton), NumpyPosingNet(net)
        assert a.n_parameters() == net.n_parameters()
        args = (rng.integers(0, 21, (3, 5)), rng.integers(0, 3, (3, 5)), rng.normal(size=(3, 5, 6)),
                rng.uniform(size=(3, 5)))
        fa, fb = a.forward(*args), b.forward(*args)
        for k in fa:
            assert np.array_equal(fa[k], fb[k]), (arch, k)
    g = AEGAN.load(aegan_path())
    a, b = NumpyAEGAN.load(aegan_path(), mini.skeleton), g.compile()
    parts = ("encoder", "generator")
    assert [a.n_parameters(k) for k in parts] == [g.n_parameters(k) for k in parts]
    x = rng.normal(size=(4, 63)).astype(np.float32)
    assert np.array_equal(a.encode(x), b.encode(x))
    z = rng.uniform(-1, 1, (4, 32)).astype(np.float32)
    (xa, ca), (xb, cb) = a.forward(z), b.forward(z)
    assert np.array_equal(xa, xb) and np.array_equal(a.vjp(ca, x), b.vjp(cb, x))
    assert np.array_equal(a.x_range, g.x_range) and np.array_equal(a.norm.mean, g.norm.mean)
    m = AESolvers.load(ae_path())
    a, b = NumpyAESolvers.load(ae_path(), mini.skeleton), m.compile()
    assert a.n_parameters(["hands"]) == m.n_parameters(["hands"]) and set(a.chained) == set(m.chained)
    za, zb = a.encode(x), b.encode(x)
    assert np.array_equal(za, zb) and np.array_equal(a.decode(za), b.decode(zb))
    t = {"hands": rng.normal(size=(4, 6)).astype(np.float32), "head": rng.normal(size=(4, 3)).astype(np.float32)}
    assert np.array_equal(a.latent(za, t), b.latent(zb, t))


def test_a_checkpoint_missing_a_weight_is_refused_by_name(tmp_path, mini):
    from posekit.learn.checkpoint import load_checkpoint, save_checkpoint
    from posekit.models.protores.fast import KIND, NumpyPosingNet, weights_path

    ck = load_checkpoint(weights_path("protores"))
    state = {k: v for k, v in ck["state"].items() if k != "ikd.blocks.1.skip.weight"}
    save_checkpoint(tmp_path / "cut.pt", state, kind=KIND, config=ck["config"], skeleton=ck["skeleton"])
    with pytest.raises(ValueError, match="weights do not match its config.*ikd.blocks.1.skip.weight"):
        NumpyPosingNet.load(tmp_path / "cut.pt")
    from posekit.data.sources import load_sample

    with pytest.raises(ValueError, match="trained for skeleton"):  # the DeepMimic humanoid: another skeleton
        NumpyPosingNet.load(weights_path("protores"), load_sample().skeleton)
