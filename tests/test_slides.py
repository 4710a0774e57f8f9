"""The lecture layout of the slides (posekit/course/lecture.py): code hidden unless it is the point, a figure with
its lead-in, long printed tables cut with a pointer to the notebook, speaker notes from the lesson's own text and a
time per section, a title slide that names the lesson. The browser check that every slide fits the screen is
tests/test_slides_fit.py."""

from __future__ import annotations

import base64
import io
import re

import nbformat
import pytest

from posekit.course import lecture
from posekit.course import slides as rules
from posekit.course.lessons import find_lesson, lessons, read_notebook


def _png(w=800, h=400) -> str:
    from PIL import Image

    buf = io.BytesIO()
    Image.new("RGB", (w, h), "white").save(buf, format="PNG")
    return base64.b64encode(buf.getvalue()).decode()


def _lesson(*cells, minutes=60):
    nb = nbformat.v4.new_notebook()
    nb.metadata["posekit"] = {"lesson": "09", "duration_min": minutes, "prerequisites": []}
    out = []
    for kind, text, *rest in cells:
        if kind == "md":
            c = nbformat.v4.new_markdown_cell(text)
        else:
            c = nbformat.v4.new_code_cell(text)
            c.execution_count = len(out) + 1
            c.outputs = rest[0] if rest else []
        if len(rest) > 1:
            c.metadata["tags"] = rest[1]
        out.append(c)
    nb.cells = out
    return rules.mark(nb)


def _stream(text):
    return [nbformat.v4.new_output("stream", name="stdout", text=text)]


def _figure():
    return [nbformat.v4.new_output("display_data", data={"image/png": _png(), "text/plain": "<Figure>"})]


def _slides(nb):
    """The deck's slides as the HTML of each leaf <section>, and its notes."""
    page = rules.export(nb, "slides")
    leaves = re.findall(r"<section\b[^>]*>((?:(?!<section).)*?)</section>", page, re.S)
    return page, leaves


BASE = (("md", "# 09 — A test lesson\n\n**Aim.** Learn."), ("code", "import numpy as np"))


def test_code_is_hidden_unless_it_is_the_point():
    nb = _lesson(*BASE, ("md", "## 1. A figure\n\nThe curve below:"),
                 ("code", "plot_the_curve_secretly()", _figure()),
                 ("md", "A table."), ("code", "print_the_table_quietly()", _stream("a b\n1 2\n3 4\n")),
                 ("md", "The algorithm, by hand."), ("code", "def my_algorithm_by_hand(x):\n    return x", [], ["slide-code"]))
    page, _ = _slides(nb)
    assert "plot_the_curve_secretly" not in page and "print_the_table_quietly" not in page
    assert "data:image/png;base64," in page and "3 4" in page  # their outputs stay
    assert "my_algorithm_by_hand" in page  # tagged slide-code: the code is the point


def test_point_cells_name_one_code_cell_each():
    for number, needles in lecture.POINT_CELLS.items():
        nb = read_notebook(find_lesson(number).path)
        for needle in needles:
            hits = [c for c in nb.cells if c.cell_type == "code" and needle in c.source]
            assert len(hits) == 1, f"lesson {number}: {needle!r} names {len(hits)} code cells, expected one"


def test_a_figure_keeps_its_lead_in_and_explanation_goes_to_the_notes():
    long_text = "\n\n".join(f"Paragraph {k}: " + "words " * 60 for k in range(4))
    nb = _lesson(*BASE, ("md", f"## 1. Results\n\n{long_text}\n\nThe figure shows the error against time:"),
                 ("code", "plot()", _figure()),
                 ("md", "What the figure says: the error falls by half within the first minute."))
    _, leaves = _slides(nb)
    with_fig = [s for s in leaves if "data:image/png" in s]
    assert len(with_fig) == 1
    assert "the error against time:" in with_fig[0], "the figure's slide lost its lead-in sentence"
    notes = re.search(r'<aside class="notes">(.*?)</aside>', with_fig[0], re.S)
    assert notes and "falls by half" in notes.group(1)


def test_a_long_printed_table_is_cut_and_points_to_the_notebook():
    table = "\n".join(f"row {k:3d}   {k * 1.5:8.2f}" for k in range(120))
    nb = _lesson(*BASE, ("md", "## 1. A long table"), ("code", "print(t)", _stream(table)))
    page, leaves = _slides(nb)
    assert "row   0" in page and "row 119" not in page
    assert re.search(r"more lines: the whole is in the notebook \(cell In \[\d+\]\)", page)


def test_a_wide_table_gets_a_smaller_font_not_a_cut_edge():
    wide = "name" + "   1.25" * 15  # a row of a table: columns that must not wrap
    font = lecture.pre_font([wide])
    assert font < lecture.PRE_PX and lecture.MONO * font * len(wide) <= lecture.WIDTH + 1


def _grid_png(rows=4, title=14, panel=300, gap=30, title_gap=8, labels=False):
    """A figure drawn as the lessons' grids are: per row a title line, a gap, a panel; x labels under the last."""
    from PIL import Image, ImageDraw

    h = rows * (title + title_gap + panel + gap) + (40 if labels else 0)
    img = Image.new("RGB", (900, h), "white")
    d = ImageDraw.Draw(img)
    y, spans = 0, []
    for _ in range(rows):
        d.rectangle((400, y, 500, y + title - 1), fill="black")  # the title
        top = y
        y += title + title_gap
        d.rectangle((50, y, 850, y + panel - 1), outline="black", fill=(200, 220, 255))
        y += panel
        spans.append((top, y))
        y += gap
    if labels:
        d.rectangle((300, y - gap + 6, 600, y - gap + 20), fill="black")
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    return base64.b64encode(buf.getvalue()).decode(), spans, h


def _heights(parts):
    from PIL import Image

    return [Image.open(io.BytesIO(base64.b64decode(p))).height for p in parts]


def test_a_tall_grid_is_cut_between_its_rows_with_each_title_on_its_panel():
    from posekit.course.layout import split_tall_png

    b64, spans, h = _grid_png()
    parts = split_tall_png(b64, max_rows=720)
    heights = _heights(parts)
    assert len(parts) == 2 and sum(heights) == h and max(heights) <= 720
    cut = heights[0]
    assert spans[1][1] < cut < spans[2][0], "the cut must fall after a panel and before the next row's title"
    # one row per part when a slide holds one; the x labels stay with the last panel
    b64, spans, h = _grid_png(labels=True)
    heights = _heights(split_tall_png(b64, max_rows=400))
    assert len(heights) == 4 and heights[-1] > 340
    assert split_tall_png(b64, max_rows=h) == [b64]  # it fits: whole
    blank = _png(900, 2000)  # nothing drawn: nowhere to cut, so whole
    assert split_tall_png(blank, max_rows=500) == [blank]


def test_a_tall_figure_takes_slides_at_a_readable_size_and_keys_to_its_whole():
    b64, spans, h = _grid_png()
    fig = [nbformat.v4.new_output("display_data", data={"image/png": b64, "text/plain": "<Figure>"})]
    nb = _lesson(*BASE, ("md", "## 1. A grid\n\nFour rows:"), ("code", "draw_grid()", fig))
    _, leaves = _slides(nb)
    with_fig = [s for s in leaves if "data:image/png" in s]
    assert len(with_fig) >= 2, "a grid four slides tall was not cut"
    assert all(f'data-figure="{b64[:40]}' in s for s in with_fig)  # each part names its whole figure
    assert "Four rows:" in with_fig[0] and "(continued)" in with_fig[1]


def test_section_times_share_the_planned_time():
    assert lecture.section_plan(["a", "b", "c"], [1, 1, 2], 60) == [15, 15, 30]
    shares = lecture.section_plan(list("abcdefg"), [3, 1, 4, 1, 5, 9, 2], 90)
    assert sum(shares) == 90 and min(shares) >= 1


def test_checked_and_open_exercises_bring_their_instructor_notes():
    le = find_lesson("01")
    page = rules.export(read_notebook(le.path), "slides", lesson=le, instructor=True)
    notes = " ".join(re.findall(r'<aside class="notes">(.*?)</aside>', page, re.S))
    assert "reference solution" in notes and "exercise_fabrik_planted" in notes  # a checked exercise: its solution
    assert "Instructor notes — exercise 3" in notes  # an open one: instructor/solutions/nb01.md


def _markdown_output(text):
    return [nbformat.v4.new_output("display_data", data={"text/markdown": text, "text/plain": "<Markdown>"})]


def test_the_paper_beside_ours_gets_its_own_slide_after_the_key_result():
    beside = "| claim | the paper | here |\n|---|---|---|\n| error | 2.07 | 1.52 |"
    nb = _lesson(*BASE, ("md", "## 1. The benchmark\n\nShort."),
                 ("code", "print_key_table()", _stream("method  error\nours    1.52\n"), ["key-figure"]),
                 ("code", "show_the_paper_beside()", _markdown_output(beside), ["paper-beside"]))
    _, leaves = _slides(nb)
    key = [k for k, s in enumerate(leaves) if "Key result — 1. The benchmark" in s]
    paper = [k for k, s in enumerate(leaves) if "The paper beside ours — 1. The benchmark" in s]
    assert len(key) == 1 and paper == [key[0] + 1], "the paper's slide must follow the key result's"
    assert "2.07" in leaves[paper[0]] and "ours    1.52" not in leaves[paper[0]]
    assert "show_the_paper_beside" not in leaves[paper[0]]


def test_a_summary_keeps_its_key_points_on_the_slide_and_its_detail_in_the_notes():
    detail = "\n".join(f"- Detail {k}: " + "words " * 30 for k in range(8))
    nb = _lesson(*BASE, ("md", f"## 2. Summary\n\n**Key points**\n\n- One short point.\n- Another.\n\n"
                               f"**In more detail**\n\n{detail}\n\n**Next:** lesson 10."))
    _, leaves = _slides(nb)
    last = leaves[-1]
    shown, notes = last.split('<aside class="notes">', 1)
    assert "One short point." in shown and "Another." in shown and "lesson 10" in shown
    assert "Detail 0" not in shown and "Detail 7" in notes  # one slide: the whole detail went to the notes
    assert not any("Summary (continued)" in s for s in leaves)
    assert lecture.summary_slide("## 2. Summary\n\n- no key points") == ("## 2. Summary\n\n- no key points", "")


def test_the_figures_source_markers_stay_out_of_the_deck_and_do_not_fill_its_slides():
    """A lesson binds its figures in the cells' metadata (tests/test_prose_numbers.py); should a source marker
    (``<!-- out: ... -->``) be left in its text, the deck and the page drop it, and a paragraph with long markers
    takes the slides it takes without them. The bindings themselves stay out of what a reader gets."""
    marker = '<!-- out: "a long anchor text of some printed table" "a row" col "a column header" -->'
    prose = "\n".join(f"- Figure {k}: 12.{k} mm{marker} against 3{k} mm{marker}, " + "words " * 12 for k in range(9))
    marked = _lesson(*BASE, ("md", f"## 2. Discussion\n\n{prose}"))
    plain = _lesson(*BASE, ("md", f"## 2. Discussion\n\n{prose.replace(marker, '')}"))
    (page, leaves), (_, plain_leaves) = _slides(marked), _slides(plain)
    assert "<!-- out:" not in page and "Figure 8: 12.8 mm against 38 mm" in page
    assert len(leaves) == len(plain_leaves)
    assert "<!-- out:" not in rules.export(marked, "page")
    assert rules.strip_source_markers("1 mm<!-- data: f.json a.b --> and 2<!-- setting: x -->; <!-- other -->") \
        == "1 mm and 2; <!-- other -->"
    bound = _lesson(*BASE, ("md", "## 2. Discussion\n\nFigure: 12.8 mm."))
    md = [c for c in bound["cells"] if c["cell_type"] == "markdown"][-1]
    md.setdefault("metadata", {})["posekit"] = {"sources": [{"figure": "12.8 mm", "occurrence": 1,
                                                             "sources": ["goal: an anchor of the bindings"]}]}
    assert "anchor of the bindings" not in rules.export(bound, "page")
    assert all("sources" not in c["metadata"].get("posekit", {}) for c in rules._for_readers(bound)["cells"])
    assert "sources" in md["metadata"]["posekit"]            # the lesson itself keeps them


@pytest.mark.parametrize("number", [le.number for le in lessons()])
def test_each_deck_is_a_lecture(number):
    le = find_lesson(number)
    nb = read_notebook(le.path)
    page = rules.export(nb, "slides", lesson=le)
    assert re.search(r"<title>\s*" + re.escape(f"{le.number} — {le.title}"), page), "the tab does not name the lesson"
    notes = re.findall(r'<aside class="notes">(.*?)</aside>', page, re.S)
    times = [int(m) for m in re.findall(r"about (\d+) min for this section", " ".join(notes))]
    assert times and sum(times) == le.duration_min, f"lesson {number}: section times {times}"
    assert "Plan" in notes[0]
    first = re.search(r"<section\b[^>]*>(.*?)</section>", page, re.S).group(1)
    assert f"about {le.duration_min} min" in first
    # it ends on one summary slide: the key points on it, the lesson's detailed summary in its notes
    leaves = re.findall(r"<section\b[^>]*>((?:(?!<section).)*?)</section>", page, re.S)
    last, last_notes = leaves[-1].split('<aside class="notes">', 1)
    assert "Summary" in last and "Key points" in last, f"lesson {number}: no summary slide"
    assert "In more detail" in last_notes and "(continued)" not in leaves[-1]
    # code stays in the notebook: no code cell's input is drawn, except the ones that are the point
    assert "jp-CodeMirrorEditor" not in page.split("</head>", 1)[1]
    # a 3D view says what it shows (the viewer's own description) and where to run it
    for cell in nb.cells:
        for o in cell.get("outputs", []):
            plain = o.get("data", {}).get("text/plain", "")
            if rules.WIDGET_VIEW in o.get("data", {}) and not rules._PROGRESS.search(plain):
                assert lecture.widget_caption(plain).split(". ")[0] in page
                assert f"In [{cell.execution_count}]" in page


# ---- the 3D views as stills ------------------------------------------------------------------------------------


def test_a_view_runs_only_the_cells_it_needs():
    from posekit.course.stills import needed_cells

    nb = _lesson(("md", "# 09 — t"), ("code", "import numpy as np"), ("code", "a = np.ones(3)"),
                 ("code", "b = slow_benchmark()"), ("code", "a = a * 2\nc = 5"), ("code", "viewer = show(a)\nviewer"))
    assert needed_cells(nb, 5) == [1, 2, 4, 5]


@pytest.mark.parametrize("number", [le.number for le in lessons()])
def test_every_3d_view_has_a_fresh_still_on_its_slide(number):
    from posekit.course.stills import load, view_cells

    le = find_lesson(number)
    nb = read_notebook(le.path)
    views = view_cells(nb)
    assert views, f"lesson {number} has no 3D view"
    for v in views:
        still, state = load(number, nb, v)
        assert state == "ok", (f"lesson {number}, cell {v}: still {state} — run `python -m posekit.course.stills "
                               f"{number}`")
        assert still["views"] and all(len(view["pose"]) == len(still["parents"]) for view in still["views"])
    page = rules.export(nb, "slides", lesson=le)
    assert page.count("A still of the view as its cell draws it") == len(views)
    leaves = re.findall(r"<section\b[^>]*>((?:(?!<section).)*?)</section>", page, re.S)
    for v in views:  # the still, its caption and the cell to open live share one slide
        n = nb.cells[v].execution_count
        slide = next(s for s in leaves if f"In [{n}]" in s and "A still of the view" in s)
        assert "data:image/png;base64," in slide
