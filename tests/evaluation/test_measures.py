"""One meaning per measure: the glossary (posekit.evaluation.measures) renders docs/measures.md, and every table
header of the lessons and the benchmark reports that names a measure is one of the glossary's headers."""

import json
import re
from pathlib import Path

import pytest

from posekit.evaluation import measures
from posekit.evaluation.measures import (MEASURES, docs_page, glossary_markdown, header_names, measure, ordering,
                                         run_spread, verdict_table)

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
# words that say a column shows one of the glossary's measures
MEASURE_WORDS = re.compile(r"MPJPE|natural|L_ikd|L_loc|L_gpd|\beffector\b|converged|all met|world joint|GT error|"
                           r"ground-truth|joint error|joint cm")


def test_docs_page_is_what_the_glossary_writes():
    assert (ROOT / "docs" / "measures.md").read_text(encoding="utf-8") == docs_page(), \
        "docs/measures.md is stale: python -m posekit.evaluation.measures > docs/measures.md"


def test_every_measure_has_frame_reduction_and_unit():
    names = [m.name for m in MEASURES]
    assert len(set(names)) == len(names)
    for m in MEASURES:
        assert m.headers and m.frame and m.per_case and m.reduction and m.unit and m.code, m.name
        assert re.search(r"\b(mean|median)\b", m.reduction), m.name
    # the two joint errors are two measures with two names, never one header for both
    assert measure("MPJPE").reduction != measure("world joint error").reduction
    assert measure("MPJPE").frame != measure("world joint error").frame
    assert not set(measure("MPJPE").headers) & set(measure("world joint error").headers)
    assert all(line.count("|") == 7 for line in glossary_markdown().splitlines())    # no "|" inside a cell


def test_measure_refuses_an_unknown_name():
    with pytest.raises(ValueError, match="no measure 'MPJPE-world'; the glossary has: MPJPE, world joint error"):
        measure("MPJPE-world")


def test_verdict_table():
    out = verdict_table([("one solve <= 2 ms", "1.49 ms", True), ("batched", "4,387 poses/s", False),
                         ("browser p95", "-", None)])
    lines = out.splitlines()
    assert lines[0].split() == ["goal", "measured", "verdict"]
    assert lines[1].endswith("  met") and lines[2].endswith("  not met") and lines[3].endswith("not judged here")
    assert lines[0].index("measured") == lines[1].index("1.49 ms") == lines[2].index("4,387")
    import numpy as np
    assert verdict_table([("g", "v", np.bool_(True))]).splitlines()[1].endswith("  met")   # numpy's bool too
    with pytest.raises(ValueError, match="at least one"):
        verdict_table([])


def test_a_verdict_in_words_is_printed_as_given_and_never_empty():
    out = verdict_table([("ahead of the baseline", "2.91 vs 2.98", "not shown: within the noise"), ("g", "v", True)])
    assert out.splitlines()[1].endswith("  not shown: within the noise") and out.splitlines()[2].endswith("  met")
    with pytest.raises(ValueError, match="must say something"):
        verdict_table([("g", "v", " ")])


def _header_literals(code):
    """Column headers a cell prints: the string literals of f-string fields with a width ("{'MPJPE mm':>10}")."""
    return re.findall(r"\{'([^'{}]+)':[<>^]?\d+\}|\{\"([^\"{}]+)\":[<>^]?\d+\}", code)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_lesson_table_headers_name_glossary_measures(path):
    """A header naming a measure is the glossary's; in a lesson that scores with lesson 05's world-frame code
    (posekit.evaluation.effector_scores), an MPJPE column reads the pelvis-relative median."""
    nb = json.loads(path.read_text(encoding="utf-8"))
    headers = header_names()
    cells = ["".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code"]
    world = any("effector_scores" in c for c in cells)
    bad = []
    for code in cells:
        for a, b in _header_literals(code):
            h = (a or b).strip()
            if not MEASURE_WORDS.search(h):
                continue
            if h not in headers:
                bad.append(h)
            elif world and headers[h].name == "MPJPE" and not any(s in code for s in headers[h].sources):
                bad.append(f"{h} (this cell computes no pelvis-relative MPJPE)")
    assert bad == [], f"{path.name}: headers not in posekit.evaluation.measures (or meaning another quantity): {bad}"


def test_benchmark_report_headers_name_glossary_measures():
    from posekit.bench import ae_scale, all as bench_all, ik, invrig, protores

    headers = header_names()
    labels = {**ik.TABLE_LABELS, **invrig.TABLE_LABELS, **protores.LABELS, **ae_scale.TABLE_LABELS}
    bad = [(k, v) for k, v in labels.items() if MEASURE_WORDS.search(v) and v not in headers]
    assert bad == []
    assert protores.LABELS["mpjpe_mm"] in measure("world joint error").headers   # world-frame mean, not MPJPE
    shipped = (ROOT / "data_samples" / "results" / "bench_all.md").read_text(encoding="utf-8")
    cols = {c.strip() for line in shipped.splitlines() if line.startswith("| solver |") for c in line.strip("|").split("|")}
    assert [c for c in cols if MEASURE_WORDS.search(c) and c not in headers] == []
    assert bench_all is not None and measures.__doc__


def test_lesson_01_shows_the_glossary_as_it_is_now():
    """Lesson 01 renders the glossary where the measures first appear; its stored output is the current one
    (re-execute lesson 01 after changing the glossary)."""
    nb = json.loads(next(p for p in NOTEBOOKS if p.name.startswith("01_")).read_text(encoding="utf-8"))
    shown = ["".join(o["data"]["text/markdown"]) for c in nb["cells"] if c["cell_type"] == "code"
             and "glossary_markdown()" in "".join(c["source"]) for o in c.get("outputs", []) if "text/markdown" in o.get("data", {})]
    assert shown == [glossary_markdown()]


def test_the_run_to_run_yardstick_is_the_largest_relative_gap_of_two_runs():
    assert run_spread((9.422, 11.741), (17.725, 17.977)) == pytest.approx(11.741 / 9.422 - 1)
    assert run_spread((2.0, 2.0)) == 0.0
    with pytest.raises(ValueError, match="at least one"):
        run_spread()
    with pytest.raises(ValueError, match="two positive errors"):
        run_spread((0.0, 1.0))


def test_one_rule_reads_every_ordering_learned_or_classical():
    # lesson 05's readings: a 2 % lead and a 24 % lead are level against a 25 % spread; a 130 % lead is ahead
    assert ordering(2.91, 2.98, 0.25) == "level" and ordering(1.23, 1.52, 0.25) == "level"
    assert ordering(1.52, 3.49, 0.25) == "ahead" and ordering(3.49, 1.52, 0.25) == "behind"
    # the rule is symmetric: a pair read either way round gives the mirrored answer
    for a, b in ((1.0, 1.3), (1.3, 1.0), (1.0, 1.2)):
        flip = {"ahead": "behind", "behind": "ahead", "level": "level"}
        assert ordering(b, a, 0.25) == flip[ordering(a, b, 0.25)]
    assert ordering(1.0, 1.01, 0.0) == "ahead"           # no spread: any gap orders
    for bad in ((0.0, 1.0, 0.1), (1.0, float("nan"), 0.1), (1.0, 2.0, -0.1)):
        with pytest.raises(ValueError, match="positive errors"):
            ordering(*bad)
