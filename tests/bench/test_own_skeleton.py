"""Benchmarks on a skeleton they have never seen (issue 45, item 2): a CMU-style folder whose zero-length bones put
two joints on one point (Hips and LHipJoint). ``bench all`` with its default effector sets runs to the end, and a
solver that refuses some cases is counted as refusing them, with its reason, in the table and the JSON."""

import json

import numpy as np
import pytest

from posekit.bench import all as bench_all
from posekit.bench.ik import case_effectors
from posekit.cli import main
from posekit.data import open_dataset
from posekit.data.cases import build_cases
from posekit.ik import registry
from posekit.ik.api import IKResult
from tests.data.own_mocap import cmu_folder


@pytest.fixture(scope="module")
def cmu(tmp_path_factory):
    return cmu_folder(tmp_path_factory.mktemp("cmu"))


def test_random_effectors_are_drawn_on_points_a_solver_can_tell_apart(cmu):
    with pytest.warns(UserWarning, match="cmu"):
        ms = open_dataset(cmu)
    cases = build_cases(ms, 40, 0, "rest")
    hips, hip_joint = ms.skeleton.index("Hips"), ms.skeleton.index("LHipJoint")
    assert np.allclose(cases.target_pos[:, hips], cases.target_pos[:, hip_joint])  # one point: a zero-length bone
    for case in case_effectors(cases, "random"):
        points = [e.target for e in case if e.kind == "position"]
        assert 4 <= len(points) and len(case) >= 4
        gaps = [np.linalg.norm(a - b) for i, a in enumerate(points) for b in points[:i]]
        assert min(gaps) > 1e-6  # no two position effectors on one point


def test_bench_all_with_the_default_sets_runs_to_the_end(cmu, tmp_path, capsys):
    out = tmp_path / "report"
    with pytest.warns(UserWarning):
        assert main(["bench", "all", "--data", str(cmu), "--cases", "6", "--out", str(out), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert {r["effectors"] for r in rows} == {"2", "5", "random"} and {r["start"] for r in rows} == {"rest", "other-clip"}
    for name in ("fabrik", "dls", "ccd"):
        assert {(r["effectors"], r["start"]) for r in rows if r["method"] == name} == \
            {(e, s) for e in ("2", "5", "random") for s in ("rest", "other-clip")}
    meta = json.loads((out / "bench_all.json").read_text())
    assert meta["rows"] == rows and (out / "bench_all.md").is_file()
    assert all(r["refused_cases"] == 0 for r in rows if r["method"] in ("fabrik", "dls"))


class _Picky:
    """A 'solver' that refuses about half the cases (by the first effector's target), else stays."""

    name = "test-picky"
    kinds = ("position",)
    needs_start = True

    def __init__(self, skeleton):
        self.skeleton = skeleton

    def solve(self, start, effectors):
        if int(abs(effectors[0].target[1]) * 1e4) % 2:
            raise ValueError("an odd target: this solver takes even ones only")
        err = np.array([np.linalg.norm(start.global_pos[self.skeleton.index(e.joint)] - e.target) for e in effectors])
        return IKResult(start.copy(), False, 0, err)


def test_a_solver_that_refuses_some_cases_is_counted_not_fatal(cmu, tmp_path):
    registry.register("test-picky", _Picky, description="refuses some cases", replace=True)
    try:
        with pytest.warns(UserWarning, match="cases refused"):
            rows = bench_all.run(n_cases=12, starts=("rest",), effectors="2", out=tmp_path, progress=False,
                                 data=str(cmu))
    finally:
        registry.unregister("test-picky")
    (row,) = [r for r in rows if r["method"] == "test-picky"]
    assert 0 < row["refused_cases"] < 12 and "even ones only" in row["refused_reason"]
    assert row["cases"] == 12 and np.isfinite(row["mpjpe_mm_median"])
    (fabrik,) = [r for r in rows if r["method"] == "fabrik"]
    assert fabrik["refused_cases"] == 0 and fabrik["refused_reason"] is None
    meta = json.loads((tmp_path / "bench_all.json").read_text())
    assert meta["refused_cases"]["test-picky / 2 / rest"]["cases"] == row["refused_cases"]
    md = (tmp_path / "bench_all.md").read_text()
    assert f"{row['refused_cases']} of 12" in md and "even ones only" in md and "| refused |" in md


def test_a_model_made_for_another_skeleton_is_refused_in_one_short_line(cmu, capsys):
    """Issue 45, item 6: the counts and the first differences, never both whole joint lists."""
    capsys.readouterr()
    with pytest.warns(UserWarning, match="cmu"):
        assert main(["bench", "ik", "--solvers", "neural", "--data", str(cmu), "--cases", "2"]) == 2
    err = capsys.readouterr().err
    line = next(ln for ln in err.splitlines() if ln.startswith("posekit: error:"))
    assert "trained for skeleton joints" in line and "22 joints there, 31 here" in line
    assert "LHipJoint" in line and "'joint_Root', 'Hips', 'Spine'" not in line and len(line) < 400
