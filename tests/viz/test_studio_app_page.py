"""The studio app's page with bad input (issue 45, item 5): a missing or broken data set, a weights folder that is
not one, an unknown solver name each give a sentence on the page, not Voila's "error when executing cell" with the
reason on the server's console; the page's first line names the data and its licence as the user gave them; and
``make studio`` reads a relative STUDIO_DATA / STUDIO_WEIGHTS from the folder it was typed in."""

import html
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from posekit.viz import studio_app


@pytest.fixture
def shown(monkeypatch):
    """What app_page displays, as text."""
    import IPython.display

    out = []
    monkeypatch.setattr(IPython.display, "display", lambda obj, **kw: out.append(getattr(obj, "data", obj)))
    for var in ("POSEKIT_STUDIO_DATA", "POSEKIT_STUDIO_SOLVERS", "POSEKIT_WEIGHTS_DIR", "POSEKIT_STUDIO_LICENCE"):
        monkeypatch.delenv(var, raising=False)
    return out


def _broken(tmp_path):
    path = tmp_path / "clips.npz"
    path.write_bytes(np.random.default_rng(0).bytes(500))
    return path


@pytest.mark.parametrize("env, says", [
    ({"POSEKIT_STUDIO_DATA": "{tmp}/no_such_folder"}, "no_such_folder' is neither a dataset name"),
    ({"POSEKIT_STUDIO_DATA": "{broken}"}, "clips.npz: not a posekit .npz"),
    ({"POSEKIT_STUDIO_DATA": "sample", "POSEKIT_STUDIO_SOLVERS": "fabrik,nope"}, "unknown solver(s) 'nope'"),
    ({"POSEKIT_STUDIO_DATA": "sample", "POSEKIT_WEIGHTS_DIR": "{tmp}/no_weights"}, "STUDIO_WEIGHTS "),
])
def test_bad_input_is_a_sentence_on_the_page(shown, monkeypatch, tmp_path, env, says):
    fill = {"tmp": tmp_path, "broken": _broken(tmp_path)}
    for k, v in env.items():
        monkeypatch.setenv(k, v.format(**fill))
    assert studio_app.app_page() is None
    text = html.unescape(" ".join(map(str, shown)))
    assert "The studio could not start." in text and says in text and "Traceback" not in text


def test_the_page_names_the_users_data_and_licence(shown, monkeypatch, tmp_path):
    assert studio_app.data_line() == "Data: Bandai mini set (Bandai Namco Research Inc.), CC BY-NC 4.0"
    monkeypatch.setenv("POSEKIT_STUDIO_DATA", "/home/me/boxing")
    assert studio_app.data_line() == "Data: your data, /home/me/boxing"
    monkeypatch.setenv("POSEKIT_STUDIO_LICENCE", "CC BY 4.0, Jo Smith")
    monkeypatch.setenv("POSEKIT_WEIGHTS_DIR", "/home/me/weights")
    line = studio_app.data_line()
    assert line == "Data: your data, /home/me/boxing (licence: CC BY 4.0, Jo Smith); models: yours, from /home/me/weights"
    assert "Bandai" not in line


def test_a_good_page_shows_the_data_line_then_the_studio(shown, monkeypatch, tmp_path):
    monkeypatch.setenv("POSEKIT_STUDIO_DATA", "sample")
    monkeypatch.setenv("POSEKIT_STUDIO_SOLVERS", "fabrik,dls")
    monkeypatch.chdir(tmp_path)  # the session folder is created only when a page writes, but never in the checkout
    studio = studio_app.app_page()
    assert studio is not None and list(studio.editor.solvers) == ["fabrik", "dls"]
    assert "DeepMimic humanoid sample" in str(shown[0]) and shown[-2] is studio and shown[-1].value == ""


def test_make_studio_reads_relative_paths_from_the_folder_they_were_typed_in(tmp_path):
    if shutil.which("make") is None:
        pytest.skip("make is not installed")
    root = Path(__file__).resolve().parents[2]
    (tmp_path / "clips").mkdir()
    run = lambda *extra: subprocess.run(["make", "-n", "-C", str(root), "studio", *extra], cwd=tmp_path,
                                        env={"PATH": "/usr/bin:/bin", "PWD": str(tmp_path)}, capture_output=True,
                                        text=True, check=True).stdout
    out = run("STUDIO_DATA=clips", "STUDIO_WEIGHTS=weights/", "STUDIO_LICENCE=CC BY 4.0")
    assert f'POSEKIT_STUDIO_DATA="{tmp_path}/clips"' in out and f'POSEKIT_WEIGHTS_DIR="{tmp_path}/weights"' in out
    assert 'POSEKIT_STUDIO_LICENCE="CC BY 4.0"' in out
    assert 'POSEKIT_STUDIO_DATA="bandai-mini"' in run("STUDIO_DATA=bandai-mini")  # a data set name stays a name
    assert 'POSEKIT_STUDIO_DATA=""' in run()


def test_the_page_counts_how_often_the_exact_finish_kept_the_learned_pose(shown, monkeypatch, tmp_path):
    """Issue 45, item 3: a +dls solver that finished from the start pose discarded its learned pose; the page says
    how often that happened."""
    monkeypatch.setenv("POSEKIT_STUDIO_SOLVERS", "fabrik,protores+dls")
    monkeypatch.chdir(tmp_path)
    studio = studio_app.app_page()
    label = shown[-1]
    ed = studio.editor
    first = label.counts["protores+dls"]
    assert list(label.counts) == ["protores+dls"] and first[1] == 1 and "kept the learned pose in" in label.value
    ed.move_target(0, np.asarray(ed.rows[0]["target"]) + [0.05, 0, 0])
    kept, total = label.counts["protores+dls"]
    assert total == 2 and 0 <= kept <= 2
    assert f"protores+dls kept the learned pose in {kept} of 2 solves" in label.value


def test_a_solver_left_out_for_another_reason_is_not_called_made_for_another_skeleton():
    assert studio_app.refused_note({"neural": "checkpoint a.pt was trained for skeleton joints other than this "
                                              "skeleton's: 22 joints there, 31 here"}).startswith(
        "left out (made for another skeleton): neural")
    note = studio_app.refused_note({"neural": "/w/ae.pt: a broken checkpoint (truncated)"})
    assert "another skeleton" not in note and "broken checkpoint" in note


def test_the_kept_line_claims_a_naturalness_comparison_only_where_one_ran():
    """Issue 58: a finish without training poses of the skeleton (choose "learned") compared no naturalness."""
    from types import SimpleNamespace

    res = SimpleNamespace(info={"learned_ms": 1.0, "kept": "start"})
    for choose, says, never in (("natural", "the more natural answer", "no naturalness"),
                                ("learned", "neural+dls: no naturalness comparison", "more natural")):
        editor = SimpleNamespace(solvers={"neural+dls": SimpleNamespace(choose=choose)},
                                 results={"neural+dls": res}, on_change=lambda fn: None)
        value = studio_app.kept_label(editor).value
        assert "neural+dls kept the learned pose in 0 of 1 solves" in value
        assert says in value and never not in value
