"""Markdown never states a figure that no output shows (it drifts): every number with a unit in a lesson's
markdown appears in an output of the same notebook or in the shipped results it loads
(those of ``data_samples/results/*`` its code names), or is on the reviewed allow-list below with its reason.

A prose number matches an output number when they are equal after rounding the output to the prose's
decimals ("29 mm" matches a printed 28.9; "1,542" matches 1542). A range "12.9–13.9 µs" is two numbers.
"""

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
RESULTS = sorted((ROOT / "data_samples" / "results").glob("*.json")) + sorted(
    (ROOT / "data_samples" / "results").glob("*.md"))

UNITS = r"(?:mm|cm|ms|µs|us|s|min|minutes?|seconds?|%|poses/s|solves/s|(?:poses|solves)\s+(?:per|a)\s+second|kB|MB)"
NUM = r"\d{1,3}(?:,\d{3})+(?:\.\d+)?|\d+(?:\.\d+)?"
# a number, optionally a range's lower end ("12.9–13.9", "2 / 5"), then a unit
PROSE = re.compile(rf"(?<![\w.$^{{])(?P<a>{NUM})(?:\s*(?:–|-|to|/)\s*(?P<b>{NUM}))?\s{{0,3}}(?P<unit>{UNITS})(?![\w/])")
OUTPUT_NUM = re.compile(r"-?\d+(?:,\d{3})*(?:\.\d+)?(?:e-?\d+)?")

# Reviewed: figures a lesson may state that no output shows, each with its reason. (lesson, text as written)
ALLOWED = {
    # goals the lessons judge the solvers by (introduced in each Aim)
    ("03", "0.1 ms"): "goal: one solve", ("03", "5 µs"): "goal: per pose, batched", ("03", "3 cm"): "goal: effectors",
    ("04", "10 ms"): "goal: one solve", ("04", "2,000 solves per second"): "goal: batched, one thread", ("04", "2 cm"): "goal: the generator's pose, two targets",
    ("05", "2 ms"): "goal: one pose", ("05", "20,000 poses/s"): "goal: batched, one thread",
    ("05", "20,000 poses per second"): "goal: batched, one thread",
    ("06", "100 ms"): "goal: browser p95, FABRIK", ("06", "150 ms"): "goal: browser p95, a learned solver",
    # definitions, not measurements
    ("04", "50 %"): "a discriminator's accuracy when it cannot tell (a definition)",
    ("04", "100 %"): "a discriminator's accuracy when it has won (a definition)",
    ("05", "45 seconds"): "exercise 4's time budget (its instructor notes: seconds=45)",
    ("04", "20 seconds"): "the live demo's time budget, seconds=20 in its code",
    ("05", "20 seconds"): "the live demo's time budget, seconds=20 in its code",
    # the papers' own figures
    ("01", "6.56 / 6.74 ms"): "Victor et al. 2021, Table 1 (FABRIK, 2 / 5 effectors)",
    ("03", "6.56 / 6.74 ms"): "Victor et al. 2021, Table 1 (FABRIK, 2 / 5 effectors)",
    ("05", "10 ms"): "Oreshkin et al. 2022: about 10 ms per pose in Unity",
    # fixed facts of the method or the data, not measurements
    ("03", "1 cm"): "the std floor of the z-score (posekit.data.pose_vectors.STD_FLOOR)",
    ("03", "1 s"): "training pairs at most 1 s apart (PAIR_MAX_S)",
    ("03", "5 s"): "an exercise's suggested setting",
    ("03", "40 cm"): "a suggested target for the reader to try",
}


def _numbers_in(text):
    return [m.group(0).replace(",", "") for m in OUTPUT_NUM.finditer(text)]


def _output_text(nb):
    parts = []
    for c in nb["cells"]:
        for o in c.get("outputs", []):
            parts.append("".join(o.get("text", "")))
            data = o.get("data", {})
            for kind in ("text/plain", "text/markdown", "text/html"):
                parts.append("".join(data.get(kind, "")))
    return "\n".join(parts)


def _results_loaded(nb):
    """The shipped results the notebook's code names (``bench_all.md``, ``f"ae_scale_{proto}.json"``)."""
    code = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")
    named = [p for p in RESULTS if p.stem in code or p.stem.rsplit("_", 1)[0] + "_{" in code]
    named += [p for p in RESULTS if p.name in LOADED_BY_HELPER and LOADED_BY_HELPER[p.name] in code]
    return named


# results a lesson loads through a helper rather than by name: file -> the helper its code calls
LOADED_BY_HELPER = {"protores_ablation.json": "posekit.models.protores.studies import studies_path"}


def _known_values(nb):
    values = set()
    sources = [_output_text(nb)] + [p.read_text(encoding="utf-8") for p in _results_loaded(nb)]
    for text in sources:
        for s in _numbers_in(text):
            try:
                v = float(s)
            except ValueError:
                continue
            for d in range(0, 5):
                values.add((d, round(v, d)))
                values.add((d, float(f"{v:.{d}f}")))
    return values


def _decimals(s):
    return len(s.split(".")[1]) if "." in s else 0


def _matches(s, known):
    s = s.replace(",", "")
    return (_decimals(s), round(float(s), _decimals(s))) in known


def _markdown_without_code(nb):
    """Markdown cells minus code spans and maths (numbers there are code or symbols, not figures)."""
    text = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "markdown")
    text = re.sub(r"```.*?```", " ", text, flags=re.S)
    text = re.sub(r"`[^`]*`", " ", text)
    return re.sub(r"\$\$.*?\$\$|\$[^$]*\$", " ", text, flags=re.S)


def unbacked_figures(path):
    nb = json.loads(path.read_text(encoding="utf-8"))
    known = _known_values(nb)
    lesson = path.name[:2]
    bad = []
    for m in PROSE.finditer(_markdown_without_code(nb)):
        if (lesson, m.group(0)) in ALLOWED:
            continue
        nums = [m.group("a")] + ([m.group("b")] if m.group("b") else [])
        if not all(_matches(n, known) for n in nums):
            bad.append(m.group(0))
    return bad


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_every_figure_in_the_prose_is_an_output(path):
    bad = unbacked_figures(path)
    assert bad == [], (f"{path.name}: figures in the markdown that no output of the notebook (nor "
                       f"data_samples/results) shows — quote an output, drop the figure, or allow-list it "
                       f"with a reason: {bad}")


def test_the_matcher():
    known = set()
    for v in (1542.0, 28.9, 0.241):
        for d in range(5):
            known |= {(d, round(v, d)), (d, float(f"{v:.{d}f}"))}
    assert _matches("1,542", known) and _matches("29", known) and _matches("0.24", known)
    assert not _matches("0.15", known) and not _matches("1,400", known)
    found = [m.group(0) for m in PROSE.finditer("took 12.9–13.9 µs, 1,542 poses/s, 5 % and 3 cm; Eq. 2; 10⁻⁴; "
                                                "896–938 solves per second")]
    assert found == ["12.9–13.9 µs", "1,542 poses/s", "5 %", "3 cm", "896–938 solves per second"]


def test_every_allowed_figure_is_still_in_its_lesson():
    """A stale allow-list entry would hide the next figure written the same way: each must still be used."""
    texts = {p.name[:2]: _markdown_without_code(json.loads(p.read_text(encoding="utf-8"))) for p in NOTEBOOKS}
    assert [k for k in ALLOWED if k[1] not in texts.get(k[0], "")] == []
