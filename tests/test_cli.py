import json
import subprocess
import sys

import numpy as np
import pytest

from posekit.cli import main

from .bench.test_bench import ensure_classical_solvers
from .io.test_bvh import SIMPLE


def run(*args):
    return subprocess.run([sys.executable, "-m", "posekit.cli", *args], capture_output=True, text=True, timeout=300)


def test_inspect_sample_json(capsys):
    assert main(["data", "inspect", "sample", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["joints"] == 18 and info["frames"] == 1620 and info["clips"] == 15
    assert info["parents"][0] == -1 and info["names"][0] == "root"


def test_inspect_text_lists_hierarchy(capsys):
    assert main(["data", "inspect", "sample"]) == 0
    out = capsys.readouterr().out
    assert "frames      1620" in out and "left_wrist" in out


def test_convert_writes_positions(tmp_path, capsys):
    src = tmp_path / "m.bvh"
    src.write_text(SIMPLE)
    assert main(["data", "convert", str(src), str(tmp_path / "o.npz"), "--scale", "0.01"]) == 0
    with np.load(tmp_path / "o.npz") as z:
        assert list(z["names"]) == ["Hips", "Spine", "Head", "Leg"]
        assert z["positions"].shape == (2, 4, 3) and list(z["parents"]) == [-1, 0, 1, 0]
        np.testing.assert_allclose(z["positions"][0, 3], [0.11, 0.9, 0])
        assert float(z["frame_time"]) == pytest.approx(0.0333333)


def test_convert_writes_metres_like_every_loader(tmp_path, capsys):
    """A centimetre file comes out in metres, as `data inspect` and the loaders read it (issue 21)."""
    from posekit.data import open_dataset

    from .io.test_rigs import mixamo_rig, write_rig

    src = write_rig(tmp_path / "cm.bvh", mixamo_rig(), np.random.default_rng(0))
    with pytest.warns(UserWarning, match="lengths look like cm.*converted to metres"):
        assert main(["data", "convert", str(src), str(tmp_path / "o.npz")]) == 0
    assert "positions in metres (cm" in capsys.readouterr().out
    with pytest.warns(UserWarning):
        loaded = open_dataset(src)
    with np.load(tmp_path / "o.npz") as z:
        np.testing.assert_allclose(z["positions"], loaded.global_pos, atol=1e-9)
        assert 1.0 < z["positions"][..., 1].max() - z["positions"][..., 1].min() < 2.5  # a person, not 146 "m"
    assert main(["data", "convert", str(src), str(tmp_path / "k.npz"), "--scale", "1"]) == 0  # keep the numbers
    with np.load(tmp_path / "k.npz") as z:
        np.testing.assert_allclose(z["positions"], loaded.global_pos * 100, atol=1e-6)


def test_warnings_print_as_one_line_without_source(tmp_path):
    from .io.test_rigs import mixamo_rig, write_rig

    src = write_rig(tmp_path / "cm.bvh", mixamo_rig(), np.random.default_rng(0))
    for args in (("data", "inspect", str(src)), ("data", "convert", str(src), str(tmp_path / "o.npz"))):
        r = run(*args)
        assert r.returncode == 0
        lines = r.stderr.splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"posekit: warning: {src}: lengths look like cm")
        assert "warnings.warn" not in r.stderr and "UserWarning" not in r.stderr


def test_malformed_file_exits_nonzero_with_file_and_line(tmp_path):
    bad = tmp_path / "bad.bvh"
    bad.write_text(SIMPLE.replace("Frames: 2", "Frames: 5"))
    r = run("data", "inspect", str(bad))
    assert r.returncode == 2
    assert f"{bad}:33: Frames: says 5 frames" in r.stderr and "Traceback" not in r.stderr
    r = run("data", "convert", str(bad), str(tmp_path / "x.npz"))
    assert r.returncode == 2 and "bad.bvh:33" in r.stderr and not (tmp_path / "x.npz").exists()


@pytest.mark.shared_data
def test_inspect_bandai_folder(shared_data, capsys):
    folder = shared_data / "bandai-namco-1" / "data"
    assert main(["data", "inspect", str(folder), "--json", "--scale", "0.01"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["joints"] == 22 and info["clips"] == 174 and info["frames"] == 31914
    assert info["frame_time"] == pytest.approx(1 / 30, rel=1e-4)


def test_bench_fk_json():
    r = run("bench", "fk", "--json", "--poses", "2000", "--repeats", "1")
    assert r.returncode == 0, r.stderr
    rows = json.loads(r.stdout)
    methods = [row["method"] for row in rows]
    assert "baseline: np.matmul per joint" in methods and "load shipped sample" in methods
    timed = [row for row in rows if "poses_per_s" in row]
    assert len(timed) == 4 and all(row["poses"] == 2000 and row["joints"] == 22 for row in timed)
    # a method that computed something else than FK would make its rate meaningless
    assert all(row["max_diff_vs_baseline_m"] < 1e-9 for row in timed)
    load = next(row for row in rows if row["method"] == "load shipped sample")
    assert load["poses"] == 1620 and load["joints"] == 18


def _bench_ik(capsys, *args):
    ensure_classical_solvers()  # in-process: solvers a test registers count too
    code = main(["bench", "ik", *args])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_bench_ik_json_keys(capsys):
    code, out, err = _bench_ik(capsys, "--solvers", "fabrik,dls", "--effectors", "2,5", "--cases", "20", "--json")
    assert code == 0, err
    rows = json.loads(out)
    keys = {"method", "effectors", "cases", "latency_ms_median", "effector_error_mm_median", "mpjpe_mm_median",
            "bone_length_error_mm_max", "converged_fraction", "natural_mm_median", "natural_floor_mm_median", "start"}
    solved = [row for row in rows if row["method"] in ("fabrik", "dls")]
    assert {(row["method"], row["effectors"]) for row in solved} == {("fabrik", "2"), ("fabrik", "5"), ("dls", "2"), ("dls", "5")}
    for row in solved:
        assert keys <= set(row) and row["cases"] == 20 and row["bone_length_error_mm_max"] < 1e-3
        assert row["start"] == "same-clip"
    assert all(row["start"] == "same-clip" for row in rows)
    import ikpy  # a dev dependency: the peer row must be a real run, not a placeholder

    peer = next(row for row in rows if row["method"].startswith("ikpy"))
    assert peer["method"].startswith(f"ikpy {ikpy.__version__} ") and peer["cases"] == 20
    assert peer["latency_ms_median"] > 0 and np.isfinite(peer["effector_error_mm_median"])
    assert not any("note" in row or "pyfabrik" in row["method"] for row in rows)
    assert any(row["method"] == "fabrik batched" and row["solves_per_s"] > 0 for row in rows)
    assert next(row for row in rows if row["method"] == "fabrik" and row["effectors"] == "2")["paper_latency_ms"] == 6.56


def test_bench_ik_rejects_unknown_solver_and_set(capsys):
    code, _, err = _bench_ik(capsys, "--solvers", "magic", "--cases", "5", "--no-peers")
    assert code == 2 and "unknown solver 'magic'" in err
    code, _, err = _bench_ik(capsys, "--effectors", "7", "--cases", "5", "--no-peers")
    assert code == 2 and "unknown effector set '7'" in err


@pytest.mark.slow
def test_bench_invrig_json():
    r = run("bench", "invrig", "--json", "--budget", "200")
    assert r.returncode == 0, r.stderr
    rows = json.loads(r.stdout)
    t1 = {row["method"]: row for row in rows if row["table"] == 1}
    assert set(t1) == {"heuristic script", "GPR", "GPR + learned Jacobian", "GPR + computed Jacobian", "NN",
                       "NN + computed Jacobian"}
    for row in t1.values():
        assert {"joint_error", "ground_truth_error", "frames_per_s"} <= set(row) and row["frames"] == 1000
    assert len([row for row in rows if row["table"] == 2]) == 5
    assert len([row for row in rows if row["table"] == 3]) == 2


def test_bench_ik_table_fits_100_columns_and_help_gives_defaults(capsys):
    code, out, err = _bench_ik(capsys, "--solvers", "fabrik,dls", "--effectors", "2,5point", "--cases", "10")
    assert code == 0, err
    lines = out.splitlines()
    assert max(len(line) for line in lines) <= 100, max(lines, key=len)
    for title in ("Start: same-clip", "Speed", "Accuracy", "Pose"):
        assert sum(line.startswith(title) for line in lines) == 1, title
    assert "baseline: numpy per-joint FABRIK" in out and "fabrik batched" in out
    code, wide, _ = _bench_ik(capsys, "--solvers", "fabrik", "--effectors", "2", "--cases", "5", "--no-peers", "--wide")
    header = next(line for line in wide.splitlines() if line.startswith("method"))
    assert code == 0 and "MPJPE mm" in header and "ms" in header.split()  # speed and accuracy in one table
    with pytest.raises(SystemExit):
        main(["bench", "ik", "--help"])
    h = " ".join(capsys.readouterr().out.split())
    for arg, default in (("--cases", "1000"), ("--start", "same-clip"), ("--seed", "0")):
        assert arg in h and f"(default: {default})" in h
    assert "(default: the data the learned solvers of the run were trained on, e.g. bandai-mini for neural; " \
           "else sample)" in h


def test_missing_shared_data_names_only_real_options(monkeypatch, capsys):
    monkeypatch.delenv("POSEKIT_DATA_DIR", raising=False)
    assert main(["data", "inspect", "bandai1"]) == 2
    err = capsys.readouterr().err
    assert "POSEKIT_DATA_DIR" in err and "--data" not in err


def test_a_name_is_registered_once_unless_replace_is_asked_for():
    from posekit.plugins import Registry

    r = Registry("thing", modules=())
    r.add("a", 1, owner="lesson_a")
    with pytest.raises(ValueError, match="a thing named 'a' is already registered \\(by lesson_a\\); pass replace=True"):
        r.add("a", 3, owner="lesson_b")
    r.add("a", 4, owner="lesson_b", replace=True)
    assert r.get("a") == 4


def test_only_the_train_commands_build_the_trainers_and_import_torch():
    """``posekit course ...`` (an instructor's autograde, once per lesson) starts without importing torch; ``posekit
    train`` still parses every trainer."""
    from posekit.cli import build_parser

    code = "import sys; from posekit.cli import build_parser; build_parser(sys.argv[1]); print('torch' in sys.modules)"
    for group, imports_torch in (("course", "False"), ("train", "True")):
        r = subprocess.run([sys.executable, "-c", code, group], capture_output=True, text=True, check=True)
        assert r.stdout.strip() == imports_torch, (group, r.stdout, r.stderr)
    assert build_parser("train").parse_args(["train", "protores"]).trainer == "protores"
    with pytest.raises(SystemExit) as done:  # an unknown trainer is refused, as before
        main(["train", "no-such-model"])
    assert done.value.code == 2
