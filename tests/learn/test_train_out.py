"""``posekit train NAME --out``: nothing shipped is overwritten by a default, and a place that cannot take the model
is refused before any training (issue 58). Every refusal here must come before the device is set up, so the tests
make the training itself fail loudly if it is ever reached."""

import os

import pytest
import torch

from posekit.cli import main


@pytest.fixture(autouse=True)
def no_training(monkeypatch):
    """Training starts with the device (posekit.learn.distributed.start): reaching it fails the test."""
    from posekit.learn import distributed

    def start(*a, **k):
        raise AssertionError("training started: the command line should have been refused before")

    monkeypatch.setattr(distributed, "start", start)


def _refused(argv, capsys, *expected):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("posekit: error: posekit train "), err
    for e in expected:
        assert e in err, err
    return err


@pytest.mark.parametrize("trainer, shipped", [("aegan", "data_samples/weights/aegan.pt"),
                                              ("ae-solvers", "data_samples/weights/ae_solvers.pt"),
                                              ("protores", "data_samples/weights/protores.pt")])
def test_other_data_without_out_names_the_shipped_file_and_how_to_replace_it(trainer, shipped, tmp_path, capsys):
    data = tmp_path / "boxing.npz"
    data.write_bytes(b"")
    _refused(["train", trainer, "--data", str(data)], capsys, f"would replace the shipped {shipped}",
             f"--out my_weights/{shipped.rsplit('/', 1)[1]}", f"--out {shipped} to replace the shipped file on purpose")


def test_protores_names_the_file_of_its_arch(tmp_path, capsys):
    _refused(["train", "protores", "--data", "bandai1", "--arch", "masked-fcr"], capsys,
             "the shipped data_samples/weights/protores_masked_fcr.pt")


@pytest.mark.parametrize("trainer", ["aegan", "ae-solvers", "protores"])
def test_a_folder_is_refused_with_the_file_expected(trainer, tmp_path, capsys):
    folder = tmp_path / "my_weights"
    folder.mkdir()
    for out in (str(folder), str(tmp_path / "new") + "/"):
        _refused(["train", trainer, "--out", out], capsys, f"--out {out}: a folder; expected a .pt file to write")
    assert not list(tmp_path.rglob("*.tmp")) and not (tmp_path / "new").exists()


def test_the_data_file_itself_is_refused(tmp_path, capsys):
    data = tmp_path / "clips.npz"
    data.write_bytes(b"motion")
    _refused(["train", "aegan", "--data", str(data), "--out", str(data)], capsys,
             "that is the --data file, which training would overwrite")
    assert data.read_bytes() == b"motion"


@pytest.mark.parametrize("name", ["other.npz", "take.bvh", "weights.json", "weights"])
def test_a_data_name_or_another_ending_is_refused(name, tmp_path, capsys):
    err = _refused(["train", "ae-solvers", "--out", str(tmp_path / name)], capsys, "expected a .pt file")
    assert ("motion data" in err) == name.endswith((".npz", ".bvh"))


def test_an_existing_file_that_is_not_a_checkpoint_is_kept(tmp_path, capsys):
    junk = tmp_path / "notes.pt"
    junk.write_text("my notes")
    _refused(["train", "aegan", "--out", str(junk)], capsys, "exists and is not a posekit checkpoint")
    assert junk.read_text() == "my notes"


def test_an_unwritable_place_is_refused(tmp_path, capsys):
    a_file = tmp_path / "a_file"
    a_file.write_text("")
    _refused(["train", "aegan", "--out", str(a_file / "sub" / "aegan.pt")], capsys,
             f"{a_file} is a file, so nothing can be written under it")
    if os.geteuid() != 0:  # root writes anywhere: the permission check is only testable as a user
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        _refused(["train", "aegan", "--out", str(locked / "aegan.pt")], capsys, "is not writable")


def test_the_other_trainers_check_their_own_kind_of_out(tmp_path, capsys):
    a_file = tmp_path / "x.npz"
    a_file.write_text("")
    _refused(["train", "invrig", "--out", str(a_file)], capsys, "a file, not a folder")
    _refused(["train", "ae-studies", "--out", str(tmp_path)], capsys, "a folder; expected a .json file")
    _refused(["train", "protores-studies", "--out", str(tmp_path / "s.pt")], capsys, "expected a .json file")


def test_the_default_data_and_a_named_out_pass_the_check(tmp_path):
    from posekit.learn.trainers import check_out, get_trainer

    t = get_trainer("aegan")
    check_out(t, t_args(t, out=None))  # the shipped data, the shipped file: the documented remake
    check_out(t, t_args(t, data="bandai1", out=str(tmp_path / "new" / "aegan.pt")))
    check_out(t, t_args(t, data="bandai1", out="data_samples/weights/aegan.pt"))  # asked for by name


def t_args(trainer, **values):
    import argparse

    p = argparse.ArgumentParser()
    for a in trainer.args:
        p.add_argument(*a.flags, **a.kwargs)
    ns = p.parse_args([])
    for k, v in values.items():
        setattr(ns, k, v)
    return ns


def test_a_failed_checkpoint_write_leaves_no_tmp(tmp_path):
    from posekit.learn.checkpoint import save_checkpoint

    target = tmp_path / "taken"
    target.mkdir()  # os.replace cannot put a file where a folder is
    with pytest.raises(OSError):
        save_checkpoint(target, kind="test", config={}, model_state={"w": torch.zeros(2)})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["taken"]
