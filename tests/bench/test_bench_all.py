"""``posekit bench all``: every registered solver once per start condition and effector set, and the report files
that say so.

One tiny run (3 cases, one start, effector sets 5 and random) is shared by the tests; most of its ~50 s is compiling the solvers'
numba kernels, which the later runs in this file reuse.
"""

import json
import math
import re

import numpy as np
import pytest
from PIL import Image

from posekit.bench import all as bench_all
from posekit.bench.ik import resolve_solvers
from posekit.bench.plugin import benchmark_names
from posekit.cli import main
from posekit.ik import make_solver

CASES = 3
START = "rest"
SETS = ("5", "random")
NEURAL = ("neural", "neural-raw", "neural-chained", "neural-chained-raw", "neural-fabrik", "neural+dls")
"""Lesson 03's networks exist for their trained joint sets only: they refuse the random set's effectors."""


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench_all")
    rows = bench_all.run(n_cases=CASES, starts=(START,), effectors=",".join(SETS), seed=0, out=out, progress=False)
    return rows, out


def test_every_registered_solver_appears_once_per_start_and_set(report):
    rows, _ = report
    names = resolve_solvers("all")
    assert len(names) >= 16 and set(NEURAL) <= set(names)
    five = [r for r in rows if r["effectors"] == "5"]
    assert sorted(r["method"] for r in five) == sorted(names)  # once each
    rand = [r for r in rows if r["effectors"] == "random"]
    assert sorted(r["method"] for r in rand) == sorted(set(names) - set(NEURAL))  # the refusals are left out
    assert [r["effectors"] for r in rows] == ["5"] * len(five) + ["random"] * len(rand)
    for r in rows:
        assert set(r) == set(bench_all.KEYS)
        assert r["start"] == START and r["cases"] == CASES and r["data"] == "bandai-mini"
        assert re.fullmatch(r"\d\d", r["lesson"]) and "position" in r["kinds"]
        assert r["latency_ms_median"] > 0 and 0 <= r["converged_fraction"] <= 1
        for k in ("mpjpe_mm_median", "effector_error_mm_median", "natural_mm_median", "bone_length_error_mm_max"):
            assert math.isfinite(r[k]) and r[k] >= 0, (r["method"], k)
    for cell in (five, rand):
        assert [r["mpjpe_mm_median"] for r in cell] == sorted(r["mpjpe_mm_median"] for r in cell)
    assert all(r["effector_error_deg_median"] is None for r in five)
    by_name = {r["method"]: r for r in five}
    assert by_name["fabrik"]["lesson"] == "01" and by_name["protores"]["lesson"] == "05"
    assert by_name["fabrik"]["converged_fraction"] == 1.0  # FABRIK reaches 5 reachable targets within 1 mm
    by_name = {r["method"]: r for r in rand}
    for name in ("dls", "protores+dls", "latent-opt+dls"):  # every kind honoured and met
        assert by_name[name]["converged_fraction"] == 1.0 and by_name[name]["effector_error_deg_median"] <= 1.0
    assert by_name["fabrik"]["converged_fraction"] < 1.0  # positions only: its rotations and look-ats count
    assert by_name["fabrik"]["effector_error_deg_median"] is None  # no rotations returned: not judged met


def test_the_random_set_is_lesson_05s_rule_drawn_on_the_cases(mini):
    from posekit.bench.ik import case_effectors
    from posekit.data.cases import build_cases
    from posekit.evaluation.effector_cases import ZONES

    cases = build_cases(mini, 20, 0, START)
    effs = case_effectors(cases, "random")
    assert effs == case_effectors(cases, "random") or all(  # the same seed, the same effectors
        [(e.joint, e.kind) for e in a] == [(e.joint, e.kind) for e in b]
        for a, b in zip(effs, case_effectors(cases, "random")))
    s = cases.skeleton
    kinds = set()
    for i, case in enumerate(effs):
        assert 6 <= len(case) <= 12
        pos = {s.index(e.joint) for e in case if e.kind == "position"}
        assert all(pos & set(s.indices(z)) for z in ZONES.values())  # a position on every main zone
        kinds |= {e.kind for e in case}
        errs = make_solver("dls", s).resolve(case)  # the true pose meets every effector
        assert len(errs) == len(case)
    assert kinds == {"position", "rotation", "look_at"}


def test_the_json_parses_and_agrees_with_the_rows(report):
    rows, out = report
    assert sorted(p.name for p in out.iterdir()) == sorted(bench_all.FILES)
    text = (out / "bench_all.json").read_text()
    d = json.loads(text)
    assert d["rows"] == rows
    assert d["command"] == f"posekit bench all --cases {CASES} --start {START} --effectors 5,random --seed 0"
    assert (d["cases"], d["starts"], d["effectors"], d["seed"], d["data"]) == (CASES, [START], list(SETS), 0,
                                                                                "bandai-mini")
    assert d["machine"]["cpu_count"] >= 1 and d["machine"]["platform"]
    assert d["skipped"] == [] and d["solvers"] == list(resolve_solvers("all"))
    assert sorted(d["refused"]) == sorted(f"{n} / random" for n in NEURAL)
    assert all("has solvers for these joint sets" in why for why in d["refused"].values())
    assert re.fullmatch(r"20\d\d-\d\d-\d\d", d["date"])  # the run's provenance: command, machine, date
    assert not re.search(r"\d+\.\d+\.\d+-", json.dumps(d["machine"]))  # no kernel build string


def test_the_markdown_has_a_sorted_table_per_set_and_start_with_every_solver(report):
    rows, out = report
    md = (out / "bench_all.md").read_text()
    assert md.startswith("# ") and f"{CASES} held-out cases" in md and "one thread" in md
    assert "Not measured on a set (the solver refused its effectors): `random`: `neural`" in md
    sections = re.split(r"^## ", md, flags=re.M)
    tables = [s for s in sections if s.startswith("Effectors ")]
    assert [t.split(" —")[0] for t in tables] == [f"Effectors {e}, start {START}" for e in SETS]
    heads = ["| solver | lesson | ms per solve | MPJPE mm | effector mm | natural mm | converged | learned kept |",
             "| solver | lesson | ms per solve | MPJPE mm | effector mm | effector deg | natural mm | converged | "
             "learned kept |"]
    assert "| n/a |" in tables[1]  # positions-only solvers are not judged on the angular effectors
    for e, table, head in zip(SETS, tables, heads):
        lines = [ln for ln in table.splitlines() if ln.startswith("|")]
        assert lines[0] == head
        body = [[c.strip() for c in ln.strip("|").split("|")] for ln in lines[2:]]
        mine = [r for r in rows if r["effectors"] == e]
        assert [c[0].strip("`") for c in body] == [r["method"] for r in mine]  # every solver, by MPJPE
        assert [float(c[3]) for c in body] == [round(r["mpjpe_mm_median"], 1) for r in mine]
        assert all(c[-2].endswith("%") for c in body)  # converged
        kept = {c[0].strip("`"): c[-1] for c in body}  # learned kept: a share for the exact finishes only
        assert all(kept[n].endswith("%") if n.endswith("+dls") else kept[n] == "" for n in kept)
    wins = next(s for s in sections if s.startswith("Who wins where"))
    cells = [ln for ln in wins.splitlines() if ln.startswith("| `")]
    assert [c.split("|")[1].strip() for c in cells] == [f"`{e}`" for e in SETS]
    for e, line in zip(SETS, cells):
        best = min((r for r in rows if r["effectors"] == e), key=lambda r: r["mpjpe_mm_median"])
        assert f"`{best['method']}` {best['mpjpe_mm_median']:.1f} mm" in line.split("|")[3]
    assert any(s.startswith("Reading the scatter") for s in sections) and "(bench_all.png)" in md


def test_the_png_is_a_valid_figure(report):
    _, out = report
    path = out / "bench_all.png"
    with Image.open(path) as im:
        im.verify()
    with Image.open(path) as im:
        assert im.format == "PNG"
        assert (im.width, im.height) == (1080, 840 * len(SETS))  # a 7.2 x 5.6 in panel per set and start at 150 dpi
        pixels = np.asarray(im.convert("L"))
    assert pixels.std() > 5 and (pixels < 128).mean() > 0.002  # drawn on, not blank


def test_the_pareto_edge_is_the_rows_nothing_beats():
    rows = [{"method": m, "latency_ms_median": t, "mpjpe_mm_median": e}
            for m, t, e in (("a", 1.0, 30.0), ("b", 2.0, 20.0), ("c", 3.0, 25.0), ("d", 0.5, 40.0))]
    assert [r["method"] for r in bench_all.pareto(rows)] == ["d", "a", "b"]


@pytest.mark.parametrize("kwargs, message", [
    ({"n_cases": 0}, "at least 1"),
    ({"starts": ("same-clip", "sideways")}, "unknown start condition 'sideways'; valid: same-clip"),
    ({"starts": ""}, "no start condition"),
    ({"effectors": "7"}, "unknown effector set '7'.*valid: 2, 5, 5point, random"),
    ({"effectors": ","}, "no effector set given"),
])
def test_bad_input_is_refused_with_a_sentence(kwargs, message):
    with pytest.raises(ValueError, match=message):
        bench_all.run(**kwargs, out=None, progress=False)


def test_the_cli(report, capsys, monkeypatch):
    assert "all" in benchmark_names()
    with pytest.raises(SystemExit):
        main(["bench", "all", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "(default: 200)" in help_text and "(default: rest,other-clip)" in help_text
    assert "(default: 2,5,random)" in help_text
    assert main(["bench", "all", "--cases", "0"]) == 2
    assert "posekit: error: cases must be a whole number of at least 1" in capsys.readouterr().err
    assert main(["bench", "all", "--start", "sideways"]) == 2
    assert "unknown start condition 'sideways'" in capsys.readouterr().err
    assert bench_all._out(None) == bench_all.default_out() and bench_all.default_out().parts[-2:] == (
        "data_samples", "results")
    assert bench_all._out("") is None and bench_all._out("none") is None

    def no_files(*a, **k):
        raise AssertionError("--out none must write nothing")

    monkeypatch.setattr(bench_all, "write_report", no_files)
    assert main(["bench", "all", "--cases", "2", "--start", START, "--effectors", "5", "--out", "none"]) == 0
    out = capsys.readouterr().out
    assert "report: not written" in out and f"Start: {START}" in out
    assert max(map(len, out.splitlines())) <= 100
    table = out.split("Speed and quality")[1].split("\n\n")[0].splitlines()[3:]
    assert sorted(ln.split()[0] for ln in table if ln.strip()) == sorted(resolve_solvers("all"))
    finish = out.split("the exact finish")[1].split("\n\n")[0].splitlines()[3:]  # learned kept: the +dls rows
    assert sorted(ln.split()[0] for ln in finish) == sorted(n for n in resolve_solvers("all") if n.endswith("+dls"))


def _cell_rows(start, effectors, **mpjpe):
    return [{"method": m.replace("_", "-").replace("-dls", "+dls"), "start": start, "effectors": effectors,
             "mpjpe_mm_median": v, "learned_kept_fraction": 0.02 if m.endswith("_dls") else None,
             "converged_fraction": 1.0, "latency_ms_median": 1.0, "effector_error_mm_median": 0.1,
             "natural_mm_median": 30.0, "lesson": "06"} for m, v in mpjpe.items()]


def test_each_cell_says_whether_a_learned_solver_beats_dls_and_fabrik():
    from posekit.bench.verdicts import verdicts

    rows = (_cell_rows("rest", "2", dls=54.8, fabrik=60.0, neural_dls=99.4, protores=108.5)  # learned all lose
            + _cell_rows("rest", "5", dls=20.01, fabrik=39.2, neural_dls=20.04)  # a tie to 0.1 mm is not closer
            + _cell_rows("other-clip", "2", dls=54.8, fabrik=60.0, protores=40.1, neural_dls=70.0)
            + _cell_rows("other-clip", "5", fabrik=50.0, dls=23.8))  # no learned solver: no sentence
    said = verdicts(rows)
    assert len(said) == 3
    assert said[0] == ("Effectors `2` from rest: no learned solver lands closer to the true pose than `dls` (54.8 mm) "
                       "and `fabrik` (60.0 mm); the closest learned one is `neural+dls`, 99.4 mm, keeping its learned "
                       "pose in 2% of the cases.")
    assert said[1].startswith("Effectors `2` from other-clip: 1 of 2 learned solvers lands closer") and \
        "the closest is `protores`, 40.1 mm." in said[1]
    assert said[2].startswith("Effectors `5` from rest: no learned solver lands closer")
    md = bench_all.markdown(rows, {"command": "posekit bench all", "cases": 3, "starts": ["rest", "other-clip"],
                                   "effectors": ["2", "5"], "data": "mine", "machine": {
                                       "platform": "p", "processor": "c", "cpu_count": 2}, "seconds": 1.0})
    assert all(f"- {v}" in md for v in said)
    from posekit.bench.plugin import get_benchmark

    for name in ("ik", "all"):  # the printed text says it too
        assert said[0] in " ".join(get_benchmark(name).footer(rows).split())


@pytest.mark.parametrize("rule, says, never", [
    ("natural", "the more natural of two exact answers: nearer a training pose of `mine`", "no naturalness"),
    ("learned", "no naturalness comparison ran", "more natural"),
    (None, "gave the answer kept", "natural answer")])
def test_the_report_claims_a_naturalness_comparison_only_where_one_ran(rule, says, never):
    rows = [dict(r, finish_rule=rule if r["method"].endswith("+dls") else None)
            for r in _cell_rows("rest", "5", dls=20.0, fabrik=39.0, neural_dls=21.0)]
    md = bench_all.markdown(rows, {"command": "posekit bench all", "cases": 3, "starts": ["rest"], "effectors": ["5"],
                                   "data": "mine", "machine": {"platform": "p", "processor": "c", "cpu_count": 2},
                                   "seconds": 1.0})
    columns = md.split("**Columns**")[1].split("\n")[0]
    assert says in columns and never not in columns
