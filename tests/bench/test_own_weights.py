"""Your own mocap end to end (issue 25, item 5): a folder of BVH clips, models trained on it with ``posekit train
... --data FOLDER --out DIR/FILE.pt``, then ``posekit bench ik`` / ``bench all`` with ``--weights DIR --data FOLDER``
measure them beside every classical solver, with no code. The clips are written here from the DeepMimic sample (a
skeleton the shipped learned models were not made for), so every shipped learned model must be skipped and the
user's own measured."""

import json

import numpy as np
import pytest

from posekit import paths
from posekit.cli import main
from posekit.data import load_sample
from posekit.io.bvh import write_bvh


@pytest.fixture(scope="module")
def own(tmp_path_factory):
    root = tmp_path_factory.mktemp("own")
    bvh, weights = root / "clips", root / "weights"
    bvh.mkdir()
    m = load_sample()
    for c in range(8):
        idx = np.nonzero(m.clip_id == c)[0]
        write_bvh(bvh / f"clip{c}.bvh", m.skeleton, m.local_rot[idx], float(m.frame_time[c]), root_pos=m.root_pos[idx])
    code = main(["train", "ae-solvers", "--data", str(bvh), "--ae-epochs", "2", "--solver-epochs", "1",
                 "--chain-epochs", "1", "--pairs", "2000", "--latent", "16", "--out", str(weights / "ae_solvers.pt")])
    assert code == 0 and (weights / "ae_solvers.pt").is_file()
    return bvh, weights


def test_bench_ik_measures_the_users_own_models(own, capsys):
    bvh, weights = own
    capsys.readouterr()
    assert main(["bench", "ik", "--solvers", "fabrik,neural,neural+dls", "--weights", str(weights), "--data", str(bvh),
                 "--cases", "5", "--effectors", "2,5", "--methods", "none", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert {(r["method"], r["effectors"]) for r in rows} == {(m, e) for m in ("fabrik", "neural", "neural+dls")
                                                            for e in ("2", "5")}
    assert all(np.isfinite(r["mpjpe_mm_median"]) for r in rows)
    assert all(r["converged_fraction"] == 1.0 for r in rows if r["method"] == "neural+dls")
    assert {r["finish_rule"] for r in rows if r["method"] == "neural+dls"} == {"natural"}  # judged on --data
    assert {r["finish_rule"] for r in rows if r["method"] != "neural+dls"} == {None}
    # without --weights the shipped (Bandai) networks are refused for this skeleton, by name (named in --solvers)
    assert main(["bench", "ik", "--solvers", "neural", "--data", str(bvh), "--cases", "5"]) == 2
    err = capsys.readouterr().err
    assert "trained for skeleton" in err and "named in --solvers" in err and "--solvers all to skip" in err
    assert paths.user_weights_dir() is None  # the folder was in use for that command only


def test_bench_all_measures_them_and_skips_the_shipped_ones(own, capsys):
    bvh, weights = own
    capsys.readouterr()
    with pytest.warns(UserWarning, match="skipping solver"):
        assert main(["bench", "all", "--weights", str(weights), "--data", str(bvh), "--cases", "3", "--start", "rest",
                     "--effectors", "5", "--out", "none", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    names = {r["method"] for r in rows}
    assert {"fabrik", "dls", "neural", "neural-fabrik", "neural+dls"} <= names  # the user's network, every variant
    assert not names & {"latent-opt", "protores", "protores+dls"}  # shipped for the Bandai skeleton: skipped
    assert all(r["data"] == str(bvh) for r in rows)


@pytest.mark.parametrize("args, message", [
    (["--weights", "{weights}"], "name the data those weights were trained on with --data"),
    (["--weights", "{missing}", "--data", "{bvh}"], "not a folder"),
    (["--weights", "{bvh}", "--data", "{bvh}"], "holds no .pt file"),
])
def test_a_bad_weights_folder_is_refused_before_any_work(own, tmp_path, capsys, args, message):
    bvh, weights = own
    fill = {"weights": weights, "bvh": bvh, "missing": tmp_path / "nowhere"}
    for bench in ("ik", "all"):
        assert main(["bench", bench, *[a.format(**fill) for a in args], "--cases", "2"]) == 2
        assert message in capsys.readouterr().err


def test_weights_path_prefers_the_users_file_and_falls_back_to_the_shipped_one(own):
    _, weights = own
    shipped = paths.weights_path("protores.pt")
    with paths.use_weights(weights):
        assert paths.weights_path("ae_solvers.pt") == weights / "ae_solvers.pt"
        assert paths.weights_path("protores.pt") == shipped  # a file the folder lacks: the shipped one
    assert paths.weights_path("ae_solvers.pt") == paths.samples_dir() / "weights" / "ae_solvers.pt"


def test_the_studio_app_poses_with_the_users_own_models(own, tmp_path, monkeypatch):
    """make studio STUDIO_DATA=clips/ STUDIO_WEIGHTS=weights/: the user's network is offered and poses; the shipped
    Bandai models are left out by name."""
    from posekit.viz.studio_app import app_studio

    bvh, weights = own
    monkeypatch.setenv("POSEKIT_WEIGHTS_DIR", str(weights))
    studio, refused = app_studio(str(bvh), "fabrik,neural+dls", export_dir=tmp_path)
    assert list(studio.editor.solvers) == ["fabrik", "neural+dls"]
    assert studio.editor.results["neural+dls"].converged
    assert {"neural", "neural-fabrik"} <= set(studio.available) and "protores" in refused


def test_weights_are_found_by_what_the_checkpoint_says_not_by_file_name(own, tmp_path, capsys):
    """Issue 45, item 4: a checkpoint saved as cmu_ae.pt is the user's ae-solvers model; two of one model and
    nothing to choose between them are refused by name; a folder without the model says what it holds."""
    import shutil

    bvh, weights = own
    mine = tmp_path / "mine"
    mine.mkdir()
    shutil.copy(weights / "ae_solvers.pt", mine / "cmu_ae.pt")
    assert paths.find_checkpoint("ae_solvers.pt", mine) == mine / "cmu_ae.pt"
    assert paths.find_checkpoint("protores.pt", mine) is None
    with paths.use_weights(mine):
        assert paths.weights_path("ae_solvers.pt") == mine / "cmu_ae.pt"
        assert paths.weights_path("aegan.pt") == paths.samples_dir() / "weights" / "aegan.pt"
    capsys.readouterr()
    assert main(["bench", "ik", "--solvers", "neural", "--weights", str(mine), "--data", str(bvh), "--cases", "3",
                 "--effectors", "5", "--methods", "none", "--json"]) == 0
    (row,) = json.loads(capsys.readouterr().out)
    assert row["method"] == "neural" and np.isfinite(row["mpjpe_mm_median"])
    shutil.copy(weights / "ae_solvers.pt", mine / "subject2.pt")
    with pytest.raises(ValueError, match=r"2 checkpoints are ae_solvers models \(cmu_ae.pt, subject2.pt\)"):
        paths.find_checkpoint("ae_solvers.pt", mine)
    other = tmp_path / "other"
    other.mkdir()
    shutil.copy(paths.samples_dir() / "weights" / "aegan.pt", other / "gan.pt")
    with pytest.warns(UserWarning, match=r"other holds gan.pt \(aegan \(structured True\)\)"):
        assert main(["bench", "all", "--weights", str(other), "--data", str(bvh), "--cases", "2", "--start", "rest",
                     "--effectors", "5", "--out", "none", "--json"]) == 0


def test_a_finish_on_your_skeleton_is_judged_on_your_data(own):
    """The exact finish of a model trained on your clips compares its two answers with the training poses of your
    data (judged_on, as posekit bench ik --data sets it up); without them there is no judge, and it says so."""
    from posekit.data import open_dataset
    from posekit.data.cases import build_cases
    from posekit.ik import effector_set, make_solver
    from posekit.ik.finish import judged_on

    bvh, weights = own
    motions = open_dataset(str(bvh))
    cases = build_cases(motions, 6, seed=0, start="same-clip")
    with paths.use_weights(weights):
        unjudged = make_solver("neural+dls", motions.skeleton)
        with judged_on(motions, cases.train_frames):
            judged = make_solver("neural+dls", motions.skeleton)
    assert unjudged.choose == "learned" and unjudged.judge is None  # the Bandai poses cannot judge this skeleton
    assert judged.choose == "natural" and judged.judged_on == motions.source
    infos = [judged.solve(cases.pose(i), effector_set(motions.skeleton, "5", cases.target_pos[i])).info
             for i in range(len(cases))]
    assert any("natural_mm" in info for info in infos)  # both answers exact: the judge compared them


def test_a_junk_pt_in_your_folder_is_blamed_on_that_file(own, tmp_path, capsys):
    bvh, weights = own
    mine = tmp_path / "w"
    mine.mkdir()
    (mine / "ae_solvers.pt").write_bytes((weights / "ae_solvers.pt").read_bytes())
    (mine / "aegan.pt").write_bytes(b"not a checkpoint")
    capsys.readouterr()
    for cmd in (["bench", "ik", "--solvers", "latent-opt", "--methods", "none"], ["bench", "all", "--out", "none"]):
        assert main(cmd + ["--weights", str(mine), "--data", str(bvh), "--cases", "3"]) == 2
        err = capsys.readouterr().err
        assert f"--weights {mine}: aegan.pt is not a posekit checkpoint" in err and "data_samples" not in err, err


def test_bench_all_on_one_clip_falls_back_to_same_clip(own, tmp_path, mini):
    """With one clip the held-out frames are the end of that clip: the other-clip start cannot be drawn, and bench all
    measures from same-clip instead, saying so (as the command line --start rest,same-clip would)."""
    from posekit.bench.all import _fall_back
    from posekit.data import open_dataset

    bvh, _ = own
    one = tmp_path / "one"
    one.mkdir()
    (one / "clip0.bvh").write_bytes((bvh / "clip0.bvh").read_bytes())
    motions = open_dataset(str(one))
    with pytest.warns(UserWarning, match=r"1 held-out clip\(s\), too few for the other-clip start.*"
                                         r"--start rest,same-clip"):
        assert _fall_back(motions, str(one), ("rest", "other-clip"), 0) == ("rest", "same-clip")
    with pytest.warns(UserWarning, match="--start same-clip,rest"):
        assert _fall_back(motions, str(one), ("same-clip", "other-clip", "rest"), 0) == ("same-clip", "rest")
    assert _fall_back(mini, "bandai-mini", ("rest", "other-clip"), 0) == ("rest", "other-clip")  # many test clips
