"""Lecture slides from the lessons: one slide convention for every notebook, and the reveal.js build.

The convention (stored in each cell's ``metadata.slideshow.slide_type``, so JupyterLab's property
inspector and nbconvert both read it; :func:`mark` writes it, ``tests/test_course.py`` checks every
lesson follows it):

===============================================  =============================================
cell                                             slide type
===============================================  =============================================
the title cell (``# NN — ...``: aim, background)  ``slide``
the setup code cell right after it                ``skip`` (imports are not lecture material)
a markdown cell opening with ``## `` (theory,     ``slide``: a new column of slides
practical sections, exercises, summary)
any other markdown cell (a practical step, an     ``subslide``: one slide further down
exercise's text)
a code cell right after a markdown cell           ``-``: on the slide of its explanation
a code cell after another code cell               ``subslide``: a practical step of its own
the cell tagged ``key-figure``                    ``slide``: the lesson's key figure or table
a cell tagged ``paper-beside``                    ``subslide``: the paper's figures beside the lesson's
a cell tagged ``slide-skip`` / ``slide-notes``    ``skip`` / ``notes`` (an instructor's override)
===============================================  =============================================

:func:`mark` first splits markdown cells so that every level-2 heading and every exercise starts a
cell of its own; the notebooks are stored that way.
"""

from __future__ import annotations

import copy
import hashlib
import re
from pathlib import Path

from .cells import (KEY_FIGURE, PAPER_BESIDE, SLIDE_HEIGHT, SLIDE_WIDTH, WIDGET_VIEW, _PROGRESS,  # noqa: F401
                    _source, strip_source_markers, strip_test_markers)

OVERRIDES = {"slide-skip": "skip", "slide-notes": "notes"}
_SPLIT = re.compile(r"^(?=## |\*\*Exercise \d)", re.MULTILINE)


def split_markdown(cells: list) -> list:
    """Split markdown cells before every ``## `` heading and every ``**Exercise N`` paragraph.

    Parameters
    ----------
    cells : list of dict
        nbformat-4 cells; not modified.

    Returns
    -------
    list of dict
        The same cells, markdown cells cut into pieces (each piece keeps the cell's metadata; pieces
        after the first get an id derived from the cell's id and the piece's text).
    """
    out = []
    for cell in cells:
        if cell["cell_type"] != "markdown":
            out.append(cell)
            continue
        parts = [p.strip("\n") for p in _SPLIT.split(_source(cell))]
        parts = [p for p in parts if p.strip()]
        if len(parts) <= 1:
            out.append(cell)
            continue
        for k, text in enumerate(parts):
            piece = copy.deepcopy(cell)
            piece["source"] = text
            if k and "id" in cell:
                piece["id"] = hashlib.sha1(f"{cell['id']}:{text}".encode()).hexdigest()[:8]
            out.append(piece)
    return out


def slide_types(cells: list) -> list[str]:
    """The convention's slide type of every cell (see the module docstring).

    Parameters
    ----------
    cells : list of dict
        nbformat-4 cells, already split by :func:`split_markdown`.

    Returns
    -------
    list of str
        One of ``slide``, ``subslide``, ``-``, ``skip``, ``notes`` per cell.
    """
    types = []
    for i, cell in enumerate(cells):
        tags = set(cell.get("metadata", {}).get("tags", []))
        override = [OVERRIDES[t] for t in sorted(tags) if t in OVERRIDES]
        prev = cells[i - 1]["cell_type"] if i else None
        if override:
            t = override[0]
        elif i == 0 or KEY_FIGURE in tags:
            t = "slide"
        elif PAPER_BESIDE in tags:
            t = "subslide"
        elif cell["cell_type"] == "markdown":
            t = "slide" if _source(cell).startswith("## ") else "subslide"
        elif i == 1:
            t = "skip"
        else:
            t = "-" if prev == "markdown" else "subslide"
        types.append(t)
    return types


def mark(nb: dict) -> dict:
    """Return a copy of notebook ``nb`` split and marked by the slide convention (idempotent)."""
    nb = copy.deepcopy(nb)
    nb["cells"] = split_markdown(nb["cells"])
    for cell, t in zip(nb["cells"], slide_types(nb["cells"])):
        cell.setdefault("metadata", {})["slideshow"] = {"slide_type": t}
    return nb


def key_figure_cell(nb: dict) -> int:
    """Index of the one cell tagged ``key-figure`` in ``nb``.

    Raises
    ------
    ValueError
        No such cell, several, or one that is not a code cell with a figure or printed table.
    """
    hits = [i for i, c in enumerate(nb["cells"]) if KEY_FIGURE in c.get("metadata", {}).get("tags", [])]
    if len(hits) != 1:
        raise ValueError(f"expected exactly one cell tagged {KEY_FIGURE!r}, found {len(hits)}")
    cell = nb["cells"][hits[0]]
    if cell["cell_type"] != "code" or not key_outputs(cell):
        raise ValueError(f"cell {hits[0]} tagged {KEY_FIGURE!r} must be a code cell whose output is a figure "
                         "(image/png) or a printed table")
    return hits[0]


def key_outputs(cell: dict) -> list[str]:
    """What identifies a key-figure cell's output in a page: its PNGs (base64) and table lines."""
    keys = []
    for o in cell.get("outputs", []):
        data = o.get("data", {})
        if "image/png" in data:
            png = data["image/png"]
            keys.append((png if isinstance(png, str) else "".join(png)).strip()[:200])
        text = o.get("text") if o.get("output_type") == "stream" else None
        if text:
            lines = [ln for ln in (text if isinstance(text, str) else "".join(text)).splitlines() if ln.strip()]
            if len(lines) >= 3:  # a table: a header and rows
                keys.append(lines[0].strip())
    return keys


def _for_readers(nb: dict) -> dict:
    """A copy of ``nb`` whose markdown cells hold what a reader sees: no source marker, no figure bindings."""
    nb = copy.deepcopy(nb)
    for cell in nb["cells"]:
        if cell["cell_type"] == "markdown":
            cell["source"] = strip_source_markers(_source(cell))
            own = cell.get("metadata", {}).get("posekit")
            if isinstance(own, dict):
                own.pop("sources", None)
                if not own:
                    cell["metadata"].pop("posekit")
    return nb


WIDGET_NOTE = ('<div class="posekit-widget-note"><p><em>{what} lives in a running kernel: open this lesson in '
               'JupyterLab (<code>make lab</code>) to use it.</em></p></div>')


def static_outputs(outputs: list) -> list:
    """A code cell's outputs as a static page can show them.

    A widget has no state in a stored lesson (its view lives in the kernel), so nbconvert would print its
    Python repr: a 3D view or other widget becomes a short note saying where to use it, and a progress bar
    (whose stored text is its first, 0 % state) is dropped. Other outputs are kept.
    """
    kept = []
    for o in outputs:
        data = o.get("data", {})
        if WIDGET_VIEW not in data:
            kept.append(o)
            continue
        plain = data.get("text/plain", "")
        plain = plain if isinstance(plain, str) else "".join(plain)
        if _PROGRESS.search(plain):
            continue
        what = "This interactive 3D view" if "Renderer(" in plain else "This interactive widget"
        kept.append({"output_type": "display_data", "metadata": {},
                     "data": {"text/html": WIDGET_NOTE.format(what=what)}})
    return kept


def _presentable(nb: dict) -> dict:
    nb = copy.deepcopy(nb)
    for cell in nb["cells"]:
        if cell["cell_type"] == "code":
            cell["source"] = strip_test_markers(_source(cell))
            cell["outputs"] = static_outputs(cell.get("outputs", []))
    return nb


def export(nb: dict, kind: str, static: str = "../_static", back: str | None = None, lesson=None,
           instructor: bool = False) -> str:
    """One lesson as HTML with posekit's templates: ``kind`` ``"slides"`` (reveal.js) or ``"page"``.

    Parameters
    ----------
    nb : dict
        An executed notebook (its stored outputs are what the slides show).
    kind : {"slides", "page"}
    static : str
        Relative URL of the course's ``_static`` folder (reveal.js, MathJax) from the written file.
    back : str, optional
        Relative URL of the course page, linked at the top of a page.
    lesson : posekit.course.lessons.Lesson, optional
        The lesson's facts for its slides (title slide, time plan, exercise notes: :mod:`posekit.course.lecture`).
    instructor : bool
        Slides only: the speaker notes carry the exercises' reference solutions and instructor notes (the
        instructor's deck). The default deck is safe to give to students.
    """
    import nbformat
    from nbconvert import HTMLExporter, SlidesExporter

    templates = str(Path(__file__).with_name("templates"))
    if kind == "slides":
        exp = SlidesExporter(template_name="posekit_reveal", extra_template_basedirs=[templates], extra_template_paths=[templates])
        exp.reveal_url_prefix = f"{static}/reveal.js"
        exp.reveal_theme = "white"
        exp.reveal_transition = "none"
        exp.reveal_width, exp.reveal_height = str(SLIDE_WIDTH), str(SLIDE_HEIGHT)
    elif kind == "page":
        exp = HTMLExporter(template_name="posekit_lab", extra_template_basedirs=[templates], extra_template_paths=[templates])
    else:
        raise ValueError(f"kind must be 'slides' or 'page', not {kind!r}")
    nb = _for_readers(nb)
    if kind == "slides":
        from .lecture import lecture_notebook

        node = lecture_notebook(nb, lesson, instructor=instructor)
    else:
        node = nbformat.from_dict(_presentable(nb))
        if "title" not in node.metadata and node.cells and _source(node.cells[0]).startswith("# "):
            node.metadata["title"] = _source(node.cells[0]).splitlines()[0][2:].strip()  # the tab names the lesson
    body, _ = exp.from_notebook_node(node, resources={"posekit_static": static, "posekit_back": back})
    return body


def count_slides(html: str) -> int:
    """Slides in a page written by :func:`export`: reveal.js's leaf ``<section>`` elements."""
    leaves, open_leaf = 0, []  # one flag per open <section>: no <section> inside it yet
    for m in re.finditer(r"<(/?)section\b", html):
        if not m.group(1):
            if open_leaf:
                open_leaf[-1] = False
            open_leaf.append(True)
        elif open_leaf.pop():
            leaves += 1
    return leaves
