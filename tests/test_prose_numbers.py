"""Every measured figure in prose names its source, and is that source's value.

Prose never states a figure that no output shows (it drifts), and a figure is checked against *the same
quantity*, not against any output of its unit. A figure in ``README.md``, ``data_samples/README.md`` or
``docs/*.md`` carries, right after it, a source marker — an HTML comment, which GitHub does not render and the raw
text shows. A lesson's markdown (``notebooks/0*_*.ipynb``) holds words, maths and links only: each markdown cell
keeps its figures' bindings in its metadata, ``cell.metadata["posekit"]["sources"]``, a list of
``{"figure": "28–29 mm", "occurrence": 1, "sources": ["out: ...", "out: ..."]}`` (the figure as written, which of
the cell's places writing it, one source per number in the syntax of a marker's body below); a binding whose figure
the cell no longer writes is stale and fails, and so does a marker left in a lesson's text
(``python tools/mark_prose_sources.py --migrate NOTEBOOK`` moves markers into the metadata). This test reads the
marker or binding, fetches the value it names, converts it to the prose's unit, rounds it to the prose's decimals
and compares.

The markers (a binding's sources are their bodies)
--------------------------------------------------
``<!-- out: "TEXT" -->``
    A notebook's output (lesson markdown only): the first number after ``TEXT`` in the text outputs of the
    notebook's code cells. ``TEXT`` must occur once in all of them (white space matches any white space); more
    quoted texts narrow it down, each searched after the one before in the same cell's output
    (``<!-- out: "random benchmark" "fabrik" col "converged" -->``). After the texts, optionally:
    ``col "HEADER"`` — the number on the line of the last text under that column (fixed-width tables, right- or
    left-aligned, and Markdown tables); ``#N`` — the N-th number after it; ``unit U`` — the value's unit when
    the output does not print it; ``scale N`` — the value times N, when the prose states it in other units than
    the output prints (``5.3`` for an output's ``5.3e-3``, the prose's unit being 10⁻³ m²).
``<!-- data: FILE PATH -->``
    A results file's key: ``FILE`` under ``data_samples/results``, ``PATH`` keys joined by ``.``, ``[i]`` a
    list's element, ``[k=v,k2=v2]`` the one element with those values (``unit`` and ``scale`` as above)
    (``<!-- data: bench_all.json rows[method=dls,effectors=2,start=rest].mpjpe_mm_median -->``).
``<!-- goal: REASON -->``, ``<!-- paper: REASON -->``, ``<!-- definition: REASON -->``, ``<!-- setting: REASON -->``
    A figure that is not measured here: a goal, a paper's figure, a definition, a setting — with its reason.

The marker binds the number (or the number and its unit) that ends right before it, on the same line (a line that
*starts* with a comment is an HTML block in CommonMark and the rest of the line would not render as Markdown). A
list or range takes a marker after each number, or one marker after the whole figure with one source per number,
separated by ``;`` (``71 / 56 / 80 mm<!-- out: "fabrik" col "mm"; out: "dls" col "mm"; out: "ccd" col "mm" -->``);
an exemption after a list covers all of it. A marker after a number that is no figure (a count: "in 34 of 100
cases") makes it one, checked like the others.

The unit of the value: the one the marker states, else the one printed right after the number, else the column
header's, else the JSON key's (``mpjpe_mm_median`` mm, ``seconds`` s, ``train_min`` min, ``converged_fraction`` a
share: 0.92 is 92 %); a value without one is read in the prose's unit. A time never backs a length.

Which figures need a marker
---------------------------
* **Numbers with a unit**, each number of a list or range ("71 / 56 / 80 mm", "12.9–13.9 µs", "28 and 29 mm"):
  length, time (also per pose or solve: "µs/pose", "ms per solve"), ratio (×, x, times), angle, rates
  (poses/s, solves per second, poses/second, updates/s, frames/s, GMAC/s), steps, core-hours, %, sizes (B to GB,
  KiB to GiB), parameters ("442k parameters"), multiply-adds.
* **Scientific notation**: "3 × 10⁻⁴", "3e-4", "10⁻³".
* **Bare decimals** ("0.473", "1.52"), except after "Sec.", "Eq.", "Table", "version", "lesson" and the like.
* **Bare integers of a list that ends in a figure**: "FABRIK 71, DLS 56 and CCD 80 mm" (71 and 56).
* **Digits for measured durations and ratios**: "about a minute", "ten to thirty times", "about ten
  microseconds" are refused (a number in words escapes every check); write the digits an output shows.

Other bare integers (counts, indices, equation numbers) need no marker. :data:`ALLOWED` lists, per page, the
reviewed figures a page may state without a marker, each with its reason; a marker is the better place for a
new one. The reading is :mod:`posekit.docs.prose`; ``posekit docs build`` writes the markers of the pages it
generates.
"""

import copy
import importlib.util
import json
import re
from pathlib import Path

import nbformat
import pytest

from posekit.docs import prose
from posekit.docs.prose import Outputs, agrees, cell_bindings, check_cell, check_text, figures

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb")) + sorted((ROOT / "notebooks").glob("[0-9][0-9]x_*.ipynb"))
RESULTS_DIR = ROOT / "data_samples" / "results"
PAGES = [p for p in [ROOT / "README.md", ROOT / "data_samples" / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
         if p.exists()]

# Reviewed: figures a page may state without a marker, each with its reason. (page, text as written)
ALLOWED = {
}


def _allowed(page):
    return {w for p, w in ALLOWED if p == page}


def _rel(p):
    return str(p.relative_to(ROOT))


def notebook_problems(nb, allowed=(), results_dir=RESULTS_DIR):
    """``["cell N line L: message"]`` for a notebook's markdown cells, whose bindings are in their metadata."""
    outputs = Outputs(nb)
    bad = []
    for i, c in enumerate(nb["cells"]):
        if c["cell_type"] != "markdown":
            continue
        for line, msg in check_cell("".join(c["source"]), cell_bindings(c), results_dir=results_dir,
                                    outputs=outputs, allowed=allowed):
            bad.append(f"cell {i} line {line}: {msg}")
    return bad


def lesson_problems(path):
    """``["cell N line L: message"]`` for one lesson's markdown cells."""
    return notebook_problems(json.loads(path.read_text(encoding="utf-8")), allowed=_allowed(path.name[:2]))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_every_figure_of_a_lesson_is_its_source(path):
    bad = lesson_problems(path)
    assert bad == [], (f"{_rel(path)}: figures in the markdown without a source, or not their source's value "
                       "(syntax: tests/test_prose_numbers.py, docs/testing.md):\n" + "\n".join(bad))


@pytest.mark.parametrize("page", PAGES, ids=_rel)
def test_every_figure_of_a_page_is_its_source(page):
    """README.md, data_samples/README.md and docs/*.md (the generated pages too): ``data:`` sources only."""
    bad = [f"line {line}: {msg}" for line, msg in
           check_text(page.read_text(encoding="utf-8"), results_dir=RESULTS_DIR, allowed=_allowed(_rel(page)))]
    assert bad == [], (f"{_rel(page)}: figures without a source, or not their source's value (syntax: "
                       "tests/test_prose_numbers.py, docs/testing.md):\n" + "\n".join(bad))


def test_every_allowed_figure_is_still_on_its_page():
    """A stale allow-list entry would hide the next figure written the same way: each must still be used."""
    texts = {p.name[:2]: prose.blank_non_prose("\n".join("".join(c["source"]) for c in json.loads(
        p.read_text(encoding="utf-8"))["cells"] if c["cell_type"] == "markdown")) for p in NOTEBOOKS}
    texts.update({_rel(p): prose.blank_non_prose(p.read_text(encoding="utf-8")) for p in PAGES})
    stale = [k for k in ALLOWED if k[1] not in texts.get(k[0], "")]
    assert stale == [], f"allow-list entries no page uses any more: {stale}"


# --- the guard itself ---------------------------------------------------------------------------------------------
def _problems(text, results=RESULTS_DIR, nb=None, allowed=()):
    return [m for _, m in check_text(text, results_dir=results, outputs=Outputs(nb) if nb else None,
                                     allowed=allowed)]


def _nb(*outputs):
    """A notebook whose code cells print ``outputs``, after one markdown cell."""
    cells = [{"cell_type": "markdown", "source": "prose", "metadata": {}}]
    cells += [{"cell_type": "code", "source": "", "metadata": {}, "execution_count": 1,
               "outputs": [{"output_type": "stream", "name": "stdout", "text": t}]} for t in outputs]
    return {"cells": cells}


@pytest.fixture
def results(tmp_path):
    (tmp_path / "run.json").write_text(json.dumps({
        "seconds": 321.5, "rows": [{"method": "fabrik", "effectors": "2", "mpjpe_mm_median": 75.84, "train_min": 13.7,
                                    "converged_fraction": 0.198},
                                   {"method": "dls", "effectors": "2", "mpjpe_mm_median": 140.8, "train_min": 2.5,
                                    "converged_fraction": 1.0}]}))
    return tmp_path


def test_the_planted_sentence_fails():
    """The held-out check's planted sentence passed the old guard, backed by protores_ablation.json's
    ``train_min: 13.7`` (a unit coincidence): now a figure without its marker fails."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    planted = readme + "\nThe full test suite takes 13.7 minutes.\n"
    bad = _problems(planted)
    assert any("'13.7 minutes'" in b and "without a source" in b for b in bad), bad
    assert not any("13.7" in b for b in _problems(readme))


def test_a_marked_figure_is_checked_against_its_own_source(results):
    ok = "FABRIK lands 75.8 mm<!-- data: run.json rows[method=fabrik,effectors=2].mpjpe_mm_median --> away."
    assert _problems(ok, results) == []
    assert _problems("in 7.58 cm<!-- data: run.json rows[0].mpjpe_mm_median -->", results) == []
    # the value differs: another row's, or the right one badly rounded
    wrong = _problems("FABRIK lands 140.8 mm<!-- data: run.json rows[method=fabrik].mpjpe_mm_median -->", results)
    assert len(wrong) == 1 and "is not its source" in wrong[0] and "75.84" in wrong[0], wrong
    assert _problems("75.9 mm<!-- data: run.json rows[0].mpjpe_mm_median -->", results) != []
    # a stated scale: the prose's figure is in thousandths of the key's unit-less value
    assert _problems("198<!-- data: run.json rows[0].converged_fraction scale 1000 -->", results) == []
    # the key, the element or the file does not exist
    for bad_src, says in (("run.json rows[method=ccd].mpjpe_mm_median", "0 elements"),
                          ("run.json rows[0].mpjpe_mm_mean", "no key 'mpjpe_mm_mean'"),
                          ("run.json rows[5].mpjpe_mm_median", "has 2 elements"),
                          ("gone.json rows[0].mpjpe_mm_median", "no results file gone.json")):
        bad = _problems(f"FABRIK lands 75.8 mm<!-- data: {bad_src} -->", results)
        assert len(bad) == 1 and says in bad[0], (bad_src, bad)


def test_the_planted_figure_is_not_backed_by_a_value_of_another_unit(results):
    """A marker naming a key of another unit (seconds) for minutes: converted, 321.5 s is 5.4 min, not 13.7."""
    assert _problems("takes 5.4 min<!-- data: run.json seconds -->", results) == []
    bad = _problems("takes 13.7 minutes<!-- data: run.json seconds -->", results)
    assert bad and "5.36" in bad[0]
    bad = _problems("takes 75.8 ms<!-- data: run.json rows[0].mpjpe_mm_median -->", results)
    assert bad and "not a time" in bad[0], bad


def test_a_notebook_output_is_a_source():
    nb = _nb("training: 35.3 s\nFABRIK median MPJPE 28.9 mm\n",
             "method          L_ikd-L2  world joint mm  converged\n"
             "protores            1.52              54         0%\n"
             "fabrik              3.49              76        34%\n",
             "| solver | ms per solve | MPJPE mm |\n|:--|--:|--:|\n| dls | 0.521 | 20.5 |\n")
    ok = ('FABRIK is 29 mm<!-- out: "FABRIK median MPJPE" --> (2.89 cm<!-- out: "FABRIK median" -->) from it, '
          'trained in 35 s<!-- out: "training:" -->; FABRIK converges in 34%<!-- out: "fabrik" col "converged" --> '
          'of the cases, at 76 mm<!-- out: "fabrik" col "world joint mm" --> against '
          '54<!-- out: "protores" col "world joint mm" --> for ProtoRes, whose L_ikd-L2 is '
          '1.52<!-- out: "protores" #1 -->; DLS takes 0.52 ms<!-- out: "| dls" col "ms per solve" --> for '
          '20.5 mm<!-- out: "| dls" col "MPJPE mm" -->; the second anchor makes the first unique: '
          '76 mm<!-- out: "mm" "fabrik" col "world joint mm" -->.')
    assert _problems(ok, nb=nb) == []
    outs = [c["outputs"][0]["text"] for c in nb["cells"][1:]]
    for text, says in (('29 ms<!-- out: "FABRIK median MPJPE" -->', "not a time"),
                       ('30 mm<!-- out: "FABRIK median MPJPE" -->', "is not its source"),
                       ('29 mm<!-- out: "CCD median MPJPE" -->', 'no output shows "CCD median MPJPE"'),
                       ('20.5<!-- out: "| dls" #3 -->', "no number #3"),
                       ('34%<!-- out: "fabrik" col "met" -->', 'no column "met"'),
                       ('76 mm<!-- out: "fabrik" -->', "is not its source"),          # its first number: 3.49
                       ('3.49<!-- out: "mm" -->', "times (cells"),
                       ('0.52 ms<!-- out: "L_ikd-L2" "| dls" -->', 'followed by "| dls"')):
        bad = _problems(text, nb=_nb(*outs))
        assert len(bad) == 1 and says in bad[0], (text, bad)
    # the same table in two cells: anchors must say which
    twice = _nb("first run\n" + outs[1], "second run\n" + outs[1])
    bad = _problems('76 mm<!-- out: "fabrik" col "world joint mm" -->', nb=twice)
    assert len(bad) == 1 and "in the outputs 2 times (cells 1, 2)" in bad[0], bad
    assert _problems('76 mm<!-- out: "second run" "fabrik" col "world joint mm" -->', nb=twice) == []


def test_a_figure_without_a_source_fails_and_an_exemption_needs_a_reason():
    assert _problems("one solve within 0.1 ms<!-- goal: the lesson's Aim -->") == []
    assert _problems("the paper's 6.56 / 6.74 ms<!-- paper: Victor et al. 2021, Table 1 -->") == []
    for text in ("one solve within 0.1 ms", "one solve within 0.1 ms<!-- goal: -->", "0.1 ms<!-- goal -->"):
        assert _problems(text) != [], text
    assert _problems("one solve within 0.1 ms", allowed={"0.1 ms"}) == []


def test_a_marker_binds_the_figure_right_before_it():
    # a marker that binds nothing, or starts a line (CommonMark: an HTML block), fails
    bad = _problems("the error falls <!-- goal: a marker in the wrong place --> by a lot")
    assert len(bad) == 1 and "binds no figure" in bad[0]
    bad = _problems("the goal is 3 cm\n<!-- goal: the Aim --> for the effectors")
    assert any("starts a line" in b for b in bad) and any("without a source" in b for b in bad)
    # a marked count is checked; a marker inside code is an example
    assert _problems("in 34<!-- definition: a count --> of 100 cases") == []
    assert _problems('`29 mm<!-- out: "nowhere" -->` and\n```\n3 cm <!-- data: none.json x -->\n```') == []


def test_every_number_of_a_list_is_bound(results):
    both = "run.json rows[0].mpjpe_mm_median; data: run.json rows[1].mpjpe_mm_median"
    assert _problems(f"75.8 and 140.8 mm<!-- data: {both} -->", results) == []
    assert _problems("75.8<!-- data: run.json rows[0].mpjpe_mm_median --> and 140.8 mm<!-- data: run.json "
                     "rows[1].mpjpe_mm_median -->", results) == []
    # one source after a list binds its last number only: the first has none
    bad = _problems("75.8 and 140.8 mm<!-- data: run.json rows[1].mpjpe_mm_median -->", results)
    assert bad == ["'75.8 and 140.8 mm' (75.8): a measured figure without a source marker"]
    # the list's order is the sources' order
    swapped = "run.json rows[1].mpjpe_mm_median; data: run.json rows[0].mpjpe_mm_median"
    assert len(_problems(f"75.8 and 140.8 mm<!-- data: {swapped} -->", results)) == 2


def test_the_figures_the_old_guard_did_not_read():
    """Bare integers of a list after "and"/",", units it did not know (µs/pose, GB, k parameters, poses/second)
    and scientific notation."""
    found = [(f.num, f.unit) for f in figures(prose.blank_non_prose(
        "FABRIK 71, DLS 56 and CCD 80 mm; 12.9 µs/pose; 2.1 GB; 442k parameters; 1,542 poses/second; "
        "a step of 3 × 10⁻⁴ and 1e-3; Eq. 2, lesson 03 and Table 1.5; 5 effectors and 2 cm"))]
    assert found == [("71", None), ("56", None), ("80", "mm"), ("12.9", "µs/pose"), ("2.1", "GB"),
                     ("442", "k parameters"), ("1,542", "poses/second"), ("3", None), ("1", None), ("2", "cm")]
    sci = [f for f in figures("a step of 3 × 10⁻⁴") if f.num == "3"][0]
    assert agrees(sci, 0.0003, None)[0] and not agrees(sci, 0.0004, None)[0]
    k = [f for f in figures("442k parameters")][0]
    assert agrees(k, 441_900, "parameters")[0] and not agrees(k, 44_190, "parameters")[0]
    for text in ("FABRIK 71, DLS 56 and CCD 80 mm", "12.9 µs/pose", "2.1 GB", "442k parameters",
                 "1,542 poses/second", "a step of 3 × 10⁻⁴"):
        assert _problems(text) != [], text


def test_numbers_in_words_are_refused():
    """"about a tenth of a millisecond", "ten to thirty times", "about ten microseconds", "about a minute"."""
    for text in ("about a tenth of a millisecond", "ten to thirty times slower", "about ten microseconds per pose",
                 "It takes about a minute.", "trained in about an hour"):
        assert any(b.startswith("in words") for b in _problems(text)), text
    assert _problems("a user's hour of two cores; several times the cost") == []


def test_rounding_and_units():
    fig = figures("29 mm")[0]
    assert agrees(fig, 28.9, "mm")[0] and agrees(fig, 0.0289, "m")[0] and not agrees(fig, 29.6, "mm")[0]
    pct = figures("92%")[0]
    assert agrees(pct, 0.92, "share")[0] and agrees(pct, 92.4, "%")[0] and not agrees(pct, 0.92, "mm")[0]
    bare = figures("0.92")[0]
    assert agrees(bare, 0.921, None)[0] and not agrees(bare, 0.93, None)[0]


def test_the_generated_pages_bind_their_figures_to_the_files(tmp_path):
    """``posekit docs build`` writes a marker after each figure of the benchmarks page: a value changed in the
    results file after the page was written is caught at that figure, not matched by another of its unit."""
    from posekit.docs import bench_page

    for p in RESULTS_DIR.glob("*.json"):
        (tmp_path / p.name).write_text(p.read_text(encoding="utf-8"), encoding="utf-8")
    page = bench_page.markdown(tmp_path)
    assert check_text(page, results_dir=tmp_path) == []
    d = json.loads((tmp_path / "bench_all.json").read_text(encoding="utf-8"))
    fabrik = next(r for r in d["rows"] if (r["method"], r["effectors"], r["start"]) == ("fabrik", "2", "rest"))
    fabrik["mpjpe_mm_median"] += 1.0
    (tmp_path / "bench_all.json").write_text(json.dumps(d), encoding="utf-8")
    bad = [m for _, m in check_text(page, results_dir=tmp_path)]
    assert bad and all("rows[method=fabrik,effectors=2,start=rest].mpjpe_mm_median" in b for b in bad), bad


def test_the_cli_page_states_settings_not_measurements():
    """Every figure of the command-line page is marked a setting of the parser; so its help texts must not state
    a measured duration ("about 2 s once done"): such a figure belongs in a results file."""
    page = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    measured = re.findall(r"(?i)\b(?:about|takes?|took|typically|roughly)\s+[\d.,]+\s?[^\s<]*<!-- setting", page)
    assert measured == [], measured


# --- a lesson's bindings live in its cells' metadata -----------------------------------------------------------------
SOURCE_MARKER = re.compile(r"<!--\s*[a-z-]+\s*:")


@pytest.mark.parametrize("path", sorted((ROOT / "notebooks").glob("0*.ipynb")), ids=lambda p: p.name)
def test_the_lessons_markdown_holds_no_source_marker(path):
    """A lesson's markdown holds words, maths and links only (docs/testing.md): its figures' bindings are in the
    cells' metadata, not comments between a number and its unit."""
    nb = json.loads(path.read_text(encoding="utf-8"))
    marked = [i for i, c in enumerate(nb["cells"])
              if c["cell_type"] == "markdown" and SOURCE_MARKER.search("".join(c["source"]))]
    assert marked == [], (f"{_rel(path)}: source markers in the markdown of cells {marked}; move them into the "
                          f"metadata: python tools/mark_prose_sources.py --migrate {_rel(path)}")


PRINTED = ("training: 35.3 s\nFABRIK median MPJPE 28.9 mm\nDLS median MPJPE 20.5 mm\n",
           "method          L_ikd-L2  world joint mm  converged\n"
           "protores            1.52              54         0%\n"
           "fabrik              3.49              76        34%\n")


def _lesson(text, bindings=None, outputs=PRINTED):
    """A notebook of one markdown cell (``text``, its metadata's ``bindings``) and code cells printing ``outputs``."""
    md = {"cell_type": "markdown", "source": text, "metadata": {}}
    if bindings is not None:
        md["metadata"]["posekit"] = {"sources": bindings}
    nb = _nb(*outputs)
    nb["cells"][0] = md
    return nb


def _bound(figure, *sources, occurrence=1):
    return {"figure": figure, "occurrence": occurrence, "sources": list(sources)}


def _cell_problems(text, bindings, outputs=PRINTED, results=RESULTS_DIR):
    return [b.split(": ", 1)[1] for b in notebook_problems(_lesson(text, bindings, outputs), results_dir=results)]


GOOD = "FABRIK lands 29 mm from it and DLS 20.5 mm, in 35 s; ProtoRes's 54 against 76 mm. Goal: 3 cm."
GOOD_BINDINGS = [_bound("29 mm", 'out: "FABRIK median MPJPE"'), _bound("20.5 mm", 'out: "DLS median"'),
                 _bound("35 s", 'out: "training:"'),
                 _bound("54 against 76 mm", 'out: "protores" col "world joint mm"',
                        'out: "fabrik" col "world joint mm"'),
                 _bound("3 cm", "goal: a goal of this test")]


def test_a_cell_whose_figures_are_bound_in_its_metadata_passes():
    assert _cell_problems(GOOD, GOOD_BINDINGS) == []
    # white space inside a figure is any white space (a line may break inside it)
    assert _cell_problems(GOOD.replace("54 against", "54\nagainst"), GOOD_BINDINGS) == []
    # the order of the bindings in the metadata does not matter
    assert _cell_problems(GOOD, GOOD_BINDINGS[::-1]) == []


def test_a_figure_without_a_binding_fails():
    bad = _cell_problems(GOOD, GOOD_BINDINGS[1:])
    assert bad == ["'29 mm' (29): a measured figure without a source marker"], bad
    bad = _cell_problems(GOOD, None)
    assert len(bad) == 6 and all("without a source" in b for b in bad), bad
    # a figure an author adds to a bound cell is unbound, even where the same text is bound once already
    bad = _cell_problems(GOOD + " Again 29 mm.", GOOD_BINDINGS)
    assert bad == ["'29 mm' (29): a measured figure without a source marker"], bad


def test_a_binding_whose_source_is_missing_fails(tmp_path):
    for source, says in (('out: "CCD median MPJPE"', 'no output shows "CCD median MPJPE"'),
                         ('out: "fabrik" col "met"', 'no column "met"'),
                         ("data: gone.json rows[0].mpjpe_mm_median", "no results file gone.json")):
        bad = _cell_problems(GOOD, [_bound("29 mm", source)] + GOOD_BINDINGS[1:], results=tmp_path)
        assert len(bad) == 1 and says in bad[0], (source, bad)


def test_a_binding_whose_source_gives_another_value_fails():
    bad = _cell_problems(GOOD.replace("29 mm", "30 mm"), [_bound("30 mm", 'out: "FABRIK median MPJPE"')]
                         + GOOD_BINDINGS[1:])
    assert len(bad) == 1 and "'30 mm' (30) is not its source" in bad[0] and "28.9" in bad[0], bad
    # the sources of a list are bound in the figure's order: swapped, both fail
    swapped = GOOD_BINDINGS[:3] + [_bound("54 against 76 mm", 'out: "fabrik" col "world joint mm"',
                                          'out: "protores" col "world joint mm"')] + GOOD_BINDINGS[4:]
    bad = _cell_problems(GOOD, swapped)
    assert len(bad) == 2 and all("is not its source" in b for b in bad), bad


def test_a_binding_whose_figure_is_no_longer_in_the_cell_is_stale():
    # the student edits the figure: the binding is stale, and the new figure is unbound
    bad = _cell_problems(GOOD.replace("29 mm", "31 mm"), GOOD_BINDINGS)
    assert any("binding of '29 mm' is stale" in b and "0 times" in b for b in bad), bad
    assert any("'31 mm' (31): a measured figure without a source" in b for b in bad), bad
    # a binding of a second place the text no longer has
    bad = _cell_problems(GOOD, GOOD_BINDINGS + [_bound("29 mm", 'out: "FABRIK median MPJPE"', occurrence=2)])
    assert len(bad) == 1 and "(2nd place) is stale" in bad[0] and "1 time," in bad[0], bad
    # a figure's text inside a longer number is not the figure ("29 mm" is not the end of "1.29 mm")
    bad = _cell_problems("It lands 1.29 mm away.", [_bound("29 mm", 'out: "FABRIK median MPJPE"')])
    assert any("is stale" in b for b in bad) and any("'1.29 mm'" in b for b in bad), bad


def test_a_binding_names_its_place_by_the_figure_and_its_occurrence():
    text = "FABRIK: 29 mm, then 29 mm again."
    first = [_bound("29 mm", 'out: "FABRIK median MPJPE"'), _bound("29 mm", "goal: the second", occurrence=2)]
    assert _cell_problems(text, first) == []
    bad = _cell_problems(text, first[:1] + [_bound("29 mm", "goal: the same place")])
    assert bad == ["binding of '29 mm' binds the same place as binding of '29 mm': keep one",
                   "'29 mm' (29): a measured figure without a source marker"], bad


def test_a_malformed_binding_or_an_inline_marker_fails():
    for binding, says in (({"figure": "29 mm", "sources": []}, "sources must be a list"),
                          ({"figure": "29 mm", "sources": ["goal:"]}, "needs its reason"),
                          ({"figure": "29 mm", "sources": ["mm: 29"]}, "does not start with out:"),
                          ({"figure": "29 mm", "occurrence": 0, "sources": ["goal: x"]}, "occurrence must be"),
                          ({"sources": ["goal: x"]}, "needs its figure")):
        bad = _cell_problems(GOOD, [binding] + GOOD_BINDINGS[1:])
        assert any(says in b for b in bad), (binding, bad)
    # a marker left in a lesson's text fails even where it names the right source
    bad = _cell_problems(GOOD.replace("29 mm", '29 mm<!-- out: "FABRIK median MPJPE" -->'), GOOD_BINDINGS)
    assert len(bad) == 1 and "inline source marker" in bad[0] and "--migrate" in bad[0], bad


def _tool():
    spec = importlib.util.spec_from_file_location("mark_prose_sources", ROOT / "tools" / "mark_prose_sources.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


INLINE = ('FABRIK lands 29 mm<!-- out: "FABRIK median MPJPE" --> from it and DLS 20.5 mm<!-- out: "DLS median" -->, '
          'in 35 s<!-- out: "training:" -->; ProtoRes\'s 54 against 76 mm<!-- out: "protores" col "world joint mm"; '
          'out: "fabrik" col "world joint mm" -->. Goal: 3 cm<!-- goal: a goal of this test -->.')


def test_the_migration_moves_the_markers_into_the_metadata_and_keeps_the_check():
    plain, entries = prose.move_markers(INLINE)
    assert plain == GOOD and entries == GOOD_BINDINGS
    assert prose.inline_bindings(plain, entries) == (INLINE, [])
    # the guard finds what it found with the markers inline: nothing, or the same wrong value
    assert _problems(INLINE, nb=_nb(*PRINTED)) == [] and _cell_problems(plain, entries) == []
    wrong = INLINE.replace("29 mm<", "30 mm<")
    plain_wrong, entries_wrong = prose.move_markers(wrong)
    assert _problems(wrong, nb=_nb(*PRINTED)) == _cell_problems(plain_wrong, entries_wrong) != []


def test_the_migration_is_idempotent_and_merges_what_a_merge_brings_back():
    tool = _tool()
    code = {"cell_type": "code", "source": "print('<!-- out: x -->')", "metadata": {}, "execution_count": 1,
            "outputs": [{"output_type": "stream", "name": "stdout", "text": "<!-- out: \"x\" --> 1.5 mm\n"}]}
    nb = _lesson(INLINE)
    nb["cells"].append(copy.deepcopy(code))
    assert tool.migrate(nb) == {0: 5}
    once = copy.deepcopy(nb)
    assert "".join(nb["cells"][0]["source"]) == GOOD and prose.cell_bindings(nb["cells"][0]) == GOOD_BINDINGS
    assert nb["cells"][-1] == code                          # code cells and outputs are never touched
    assert tool.migrate(nb) == {} and nb == once             # run again: nothing moves, nothing changes
    # a merge brings back a marker in a migrated cell (a new figure): it joins the metadata's bindings in order
    nb["cells"][0]["source"] = GOOD.replace("from it", 'from it (2.89 cm<!-- out: "FABRIK median" -->)')
    assert tool.migrate(nb) == {0: 1}
    entries = prose.cell_bindings(nb["cells"][0])
    assert [e["figure"] for e in entries] == ["29 mm", "2.89 cm", "20.5 mm", "35 s", "54 against 76 mm", "3 cm"]
    assert notebook_problems(nb) == []
    # a cell without bindings keeps its metadata as it was
    assert "posekit" not in _lesson("no figures here")["cells"][0]["metadata"]
    plain_nb = _lesson("no figures here<!-- an ordinary comment -->")
    tool.migrate(plain_nb)
    assert plain_nb["cells"][0]["metadata"] == {} and "ordinary comment" in plain_nb["cells"][0]["source"]


def test_the_migration_writes_the_notebook_as_nbformat_does(tmp_path):
    tool = _tool()
    path = tmp_path / "lesson.ipynb"
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell(INLINE),
                                         nbformat.v4.new_code_cell("print(1)")])
    path.write_text(nbformat.writes(nb) + "\n", encoding="utf-8")
    assert tool.migrate_file(path) == {0: 5}
    after = path.read_text(encoding="utf-8")
    assert after == nbformat.writes(nbformat.reads(after, as_version=4)) + "\n"
    assert tool.migrate_file(path) == {} and path.read_text(encoding="utf-8") == after


def test_a_bare_decimal_before_a_full_stop_is_a_figure():
    """With the markers out of the text, "... weighted 1 10.10. But" ends its sentence at the figure: it is read
    (the old guard saw the marker's ``<`` there, and missed the same figure without one); a version is not."""
    assert [f.num for f in figures(prose.blank_non_prose("weighted 1 10.10. But release 1.2.3 and 3e-4."))] == \
        ["10.10", "3"]
    assert _problems("with every joint weighted 1 10.10. But") != []


def test_a_merge_with_a_re_execution_keeps_its_outputs_and_this_branchs_markdown():
    """The other side re-executed the lesson (new outputs, markers still inline in its markdown): its notebook with
    this side's markdown cells, matched by id, is migrated and bound, and its outputs stay."""
    tool = _tool()
    ours = nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell(INLINE), nbformat.v4.new_code_cell("run()")])
    theirs = copy.deepcopy(ours)
    tool.migrate(ours)
    theirs["cells"][0]["source"] = INLINE.replace("from it", "from its target")   # their older words, inline
    theirs["cells"][1]["outputs"] = [nbformat.v4.new_output("stream", text=PRINTED[0] + PRINTED[1])]
    assert tool.take_markdown(theirs, ours) == []
    assert tool.migrate(theirs) == {}
    assert theirs["cells"][0] == ours["cells"][0] and theirs["cells"][1]["outputs"][0]["text"].startswith("training")
    assert notebook_problems(theirs) == []
    # a markdown cell the other side added (an id this side lacks) is kept, and named
    theirs["cells"].append(nbformat.v4.new_markdown_cell("new words"))
    assert tool.take_markdown(theirs, ours) == [theirs["cells"][-1]["id"]]
