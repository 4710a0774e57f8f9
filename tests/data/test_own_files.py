"""Every file a posekit command writes is read by every posekit command that takes that kind of file (issue 45,
item 1): ``data convert`` of a user's BVH dialects (a CMU-style folder with zero-length bones in CMU units, a
21-joint folder in centimetres) writes an ``.npz`` that ``data inspect``, ``bench ik --data`` and ``train --data``
read; a foreign or broken ``.npz`` gets one sentence that names the file."""

import json
import warnings

import numpy as np
import pytest

from posekit.cli import main
from posekit.data import open_dataset
from tests.data.own_mocap import cmu_folder, holden_folder


@pytest.fixture(scope="module")
def converted(tmp_path_factory):
    root = tmp_path_factory.mktemp("own_files")
    out = {}
    for name, make in (("cmu", cmu_folder), ("holden21", holden_folder)):
        folder = make(root / name, clips=20, frames=12)
        npz = root / f"{name}.npz"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the unit warning: tested in tests/io
            assert main(["data", "convert", str(folder), str(npz)]) == 0
            bvh = open_dataset(folder)
        out[name] = (folder, npz, bvh)
    return out


@pytest.mark.parametrize("name", ["cmu", "holden21"])
def test_convert_then_inspect_reads_the_same_motion(converted, name, capsys):
    folder, npz, bvh = converted[name]
    capsys.readouterr()
    assert main(["data", "inspect", str(npz), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["joints"] == bvh.skeleton.n_joints and info["frames"] == bvh.n_frames and info["clips"] == 20
    assert info["names"] == list(bvh.skeleton.names) and info["roles"] == bvh.skeleton.roles
    again = open_dataset(npz)
    np.testing.assert_allclose(again.global_pos, bvh.global_pos, atol=1e-9)
    np.testing.assert_allclose(again.local_rot, bvh.local_rot, atol=1e-12)
    with np.load(npz) as z:  # positions for readers that want positions only, as before
        assert list(z["names"]) == list(bvh.skeleton.names)
        np.testing.assert_allclose(z["positions"], bvh.global_pos, atol=1e-9)


def test_bench_ik_reads_a_converted_file(converted, capsys):
    _, npz, _ = converted["cmu"]
    capsys.readouterr()
    assert main(["bench", "ik", "--data", str(npz), "--solvers", "fabrik,dls", "--effectors", "5", "--cases", "3",
                 "--start", "rest", "--methods", "none", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert {r["method"] for r in rows} == {"fabrik", "dls"} and all(r["data"] == str(npz) for r in rows)


def test_train_reads_a_converted_file(converted, tmp_path, capsys):
    _, npz, _ = converted["holden21"]
    out = tmp_path / "mine.pt"
    assert main(["train", "ae-solvers", "--data", str(npz), "--ae-epochs", "1", "--solver-epochs", "1",
                 "--chain-epochs", "1", "--pairs", "300", "--latent", "8", "--out", str(out)]) == 0
    assert out.is_file()
    err = capsys.readouterr().err  # not a terminal: progress as whole lines, never silent
    assert "autoencoder: 100%" in err and "\r" not in err


def _positions_only(path):
    """What ``posekit data convert`` wrote before it kept the rotations."""
    np.savez_compressed(path, names=np.array(["a", "b"]), parents=np.array([-1, 0]), positions=np.zeros((3, 2, 3)),
                        frame_time=np.array(1 / 30))


@pytest.mark.parametrize("make, says", [
    (lambda p: p.write_bytes(np.random.default_rng(0).bytes(3000)), "not a posekit .npz"),
    (lambda p: np.savez(p, weights=np.zeros(3)), "lacks"),
    (_positions_only, "joint positions only"),
    (lambda p: p.write_bytes(b"PK\x03\x04" + bytes(200)), "broken .npz"),
])
def test_a_foreign_or_broken_npz_gets_a_sentence_naming_it(tmp_path, capsys, make, says):
    path = tmp_path / "clips.npz"
    make(path)
    for argv in (["data", "inspect", str(path)], ["bench", "ik", "--data", str(path), "--cases", "2"],
                 ["train", "ae-solvers", "--data", str(path), "--out", str(tmp_path / "mine.pt")]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.startswith(f"posekit: error: {path}: ") and says in err, err
        assert "allow_pickle" not in err and "Traceback" not in err and len(err.splitlines()) == 1
