"""A lesson laid out as a lecture deck: every slide fits the screen, code stays in the notebook, notes for the speaker.

:func:`lecture_notebook` turns a lesson (marked by the slide convention of :mod:`posekit.course.slides`) into the
notebook that reveal.js shows. Its rules:

* **Code is hidden** on a slide; the cell's outputs (figure, table, printed result) stay. A cell tagged
  :data:`SLIDE_CODE` (``slide-code``), or listed in :data:`POINT_CELLS`, is the point of its slide and shows its
  code too.
* **Every slide fits** :data:`~posekit.course.slides.SLIDE_WIDTH` x :data:`~posekit.course.slides.SLIDE_HEIGHT`
  (:mod:`posekit.course.layout`). Each slide's text, figures and tables are measured in estimated CSS pixels (the sizes set by the deck's
  stylesheet, ``templates/posekit_reveal``); a slide that would be taller continues on the next one at a natural
  break (a paragraph, a list, a cell), a figure shrinks to no less than :data:`MIN_FIGURE` px tall before it moves
  on, a figure or table goes to its next slide *with its lead-in sentence*, and a printed table or report too long
  for one slide shows its first rows and says where the whole is (the notebook's cell). Wide printed tables get a
  smaller font rather than a cut edge. ``tests/test_slides_fit.py`` checks the result in Chromium.
* **A figure fills its slide**: the height left on its slide goes to it.
* **Speaker notes** (reveal.js ``s``) come from the lesson's own text: for a figure or table, the paragraphs that
  follow it in the lesson (what it says); for an exercise, the instructor notes (open exercises,
  ``posekit/exercises/solutions/nbNN.md``) or where its reference solution is; for a 3D view, which cell to run
  live; on the first slide of each section, its time, and on the title slide, the whole plan. A section's time is
  the lesson's planned time shared by the sections' weights (:func:`section_plan`).
* **The summary slide**: a lesson's Summary opens with its :data:`KEY_POINTS`; the slide shows them and the
  **Next:** line, the speaker notes the detailed list (:func:`summary_slide`).
* **The paper beside ours**: a cell tagged :data:`~posekit.course.slides.PAPER_BESIDE` (``paper-beside``) shows
  the paper's figures and the lesson's measured ones side by side, in columns of one table; it gets a slide of its
  own, after the key result.
* **3D views** (widgets that live in a kernel) show the description the viewer stores with its output and the cell
  to open live (``In [k]``).
"""

from __future__ import annotations

import copy
import html
import re

from .layout import (BUDGET, CHARS, CONT_PX, KEY_PRE_PX, MIN_FIGURE, MONO, PRE_PX, WIDTH, Block, Page, _BLOCK_GAP,  # noqa: F401
                     _heading, _png_size, _used, md_height, pack, pre_font, pre_height, size_figures, split_chunks,
                     split_tall_png)
from .cells import KEY_FIGURE, PAPER_BESIDE, WIDGET_VIEW, _PROGRESS, _source, strip_test_markers
from .stills import load as load_still, render_png

__all__ = ["SLIDE_CODE", "POINT_CELLS", "KEY_POINTS", "MIN_FIGURE", "lecture_notebook", "section_plan", "summary_slide",
           "Page"]

SLIDE_CODE = "slide-code"
"""Cell tag: this code cell is the point of its slide, so its code is shown (at most :data:`MAX_CODE_LINES`)."""
POINT_CELLS = {
    "00": ["def my_fk("],
    "01": ["def my_fabrik_chain("],
    "03": ["class MyAutoencoder("],
    "05": ["for r, block in enumerate(net.encoder.blocks"],
}
"""Code cells shown on the slides without a tag in the lesson: lesson number -> a line each such cell's source
contains (``tests/test_slides.py`` checks each names exactly one code cell). Algorithms written by hand in front of
the class, the part of the lesson that *is* code."""

TALL = 1.5
"""A figure that would be drawn more than this many slide heights tall at the slide's width is cut between its rows
of panels (:func:`~posekit.course.layout.split_tall_png`), one part per slide."""

MAX_CODE_LINES = 30
"""A shown code cell longer than this is cut (the notebook has it whole)."""


# ---- the lesson's cells as blocks ------------------------------------------------------------------------------


def _text(o) -> str:
    t = o.get("text", "")
    return t if isinstance(t, str) else "".join(t)


def _data(d, key) -> str:
    v = d.get(key, "")
    return v if isinstance(v, str) else "".join(v)


def widget_caption(plain: str) -> str:
    """The description a viewer stores with its output (its text form), without the brackets."""
    return plain.strip().strip("[]").strip()


def output_blocks(cell, index: int, shown_code: bool, key: str, still=None) -> list[Block]:
    """The blocks a code cell puts on its slides: its code when it is the point, then its outputs.

    ``key``: ``"key"`` (the key figure) or ``"paper"`` (the paper beside ours) for a cell with a slide to itself,
    whose printed tables may take the larger font; ``""`` for any other.

    ``still(index)``: the recorded still of a 3D view and its state (:func:`posekit.course.stills.load`)."""
    blocks = []
    if shown_code:
        lines = strip_test_markers(_source(cell)).splitlines()
        note = ""
        if len(lines) > MAX_CODE_LINES:
            note = f"… {len(lines) - MAX_CODE_LINES} more lines in the notebook"
            lines = lines[:MAX_CODE_LINES]
        font = pre_font(lines)
        blocks.append(Block("code", "\n".join(lines), pre_height(lines, font) + (30 if note else 0), cell=index,
                            font=font, note=note))
    outs = cell.get("outputs", [])
    if key:  # the key figure's picture first: it opens the slide
        outs = sorted(outs, key=lambda o: "image/png" not in o.get("data", {}))
    for o in outs:
        d = o.get("data", {})
        if o.get("output_type") == "stream":
            if o.get("name") == "stderr":
                continue
            lines = _text(o).rstrip("\n").splitlines()
            if not lines:
                continue
            if blocks and blocks[-1].kind == "pre" and blocks[-1].cell == index:  # one printed block per cell
                lines = blocks.pop().text.splitlines() + lines
            font = pre_font(lines, KEY_PRE_PX if key else PRE_PX)
            blocks.append(Block("pre", "\n".join(lines), pre_height(lines, font), cell=index, font=font))
        elif WIDGET_VIEW in d:
            plain = _data(d, "text/plain")
            if _PROGRESS.search(plain):
                continue
            what = widget_caption(plain) or "an interactive widget"
            data, state = still(index) if still is not None else (None, "none")
            text = (f"**Live in the notebook:** {what}.\n\nOpen the lesson in JupyterLab (`make lab`) and run cell "
                    f"`In [{cell.get('execution_count') or '?'}]` to use it.")
            if data is not None:
                what = " ".join(p for p in re.split(r"(?<=\.)\s+", what) if "kernel" not in p).rstrip(".")
                text = (f"*A still of the view as its cell draws it (targets as red crosses).* {what}. Live: cell "
                        f"`In [{cell.get('execution_count') or '?'}]` in JupyterLab (`make lab`).")
            elif state == "stale":
                text += " *(Its still is out of date: `python -m posekit.course.stills` records it again.)*"
            caption = Block("html", text, md_height(text) + 30, cell=index, lead_in=data is not None)
            blocks.append(caption)  # the caption first: it travels with its still, as a lead-in does
            if data is not None:
                b64 = render_png(data)
                w, h = _png_size(b64)
                pref = min(h * WIDTH / w, BUDGET - caption.height - _BLOCK_GAP - CONT_PX)
                blocks.append(Block("png", height=pref, min_height=min(pref, max(MIN_FIGURE, 0.6 * pref)),
                                    cell=index, data=b64, size=(w, h)))
        elif "image/png" in d:
            b64 = _data(d, "image/png").strip()
            w, h = _png_size(b64)
            scale = min(1.25, WIDTH / w)  # small figures may grow a little, up to the slide's width
            # a grid taller than a slide is cut between its rows of panels, a part per slide, rather than shrunk
            parts = split_tall_png(b64, (BUDGET - CONT_PX) / scale) if h * scale > TALL * BUDGET else [b64]
            for part in parts:
                w, h = _png_size(part)
                pref = min(h * scale, BUDGET)
                blocks.append(Block("png", height=pref, min_height=min(pref, max(MIN_FIGURE, 0.6 * pref)), cell=index,
                                    data=part, size=(w, h), origin=b64[:200] if len(parts) > 1 else ""))
        elif "text/markdown" in d:
            md = _data(d, "text/markdown")
            blocks.append(Block("html", md, md_height(md, int(CHARS * 1.15)), cell=index))
        elif "text/html" in d:
            blocks.append(Block("html", _data(d, "text/html"), 120, cell=index))
        elif "text/plain" in d:
            lines = _data(d, "text/plain").splitlines()
            font = pre_font(lines)
            blocks.append(Block("pre", "\n".join(lines), pre_height(lines, font), cell=index, font=font))
    return blocks


# ---- sections, time and notes ----------------------------------------------------------------------------------


def section_plan(titles: list[str], weights: list[float], minutes: int) -> list[int]:
    """Share ``minutes`` among sections in proportion to ``weights`` (whole minutes, largest remainders first,
    at least one each); the shares add up to ``minutes``."""
    total = sum(weights) or 1.0
    raw = [minutes * w / total for w in weights]
    whole = [max(1, int(r)) for r in raw]
    order = sorted(range(len(raw)), key=lambda i: raw[i] - int(raw[i]), reverse=True)
    k = 0
    while sum(whole) < minutes and order:
        whole[order[k % len(order)]] += 1
        k += 1
    while sum(whole) > minutes and max(whole) > 1:
        whole[whole.index(max(whole))] -= 1
    return whole


_EXERCISE = re.compile(r"^\*\*Exercise (\d+)\b([^*]*)\*\*")


def _where(cell) -> str:
    n = cell.get("execution_count")
    return f"cell In [{n}]" if n else "its cell"


_LIVE = ("**Live in the notebook", "*A still of the view")
_SAYS = "**What it shows** (the lesson's text on it): "


KEY_POINTS = "**Key points**"
"""Opens the short list a lesson's Summary starts with; the list, the heading and the **Next:** line make the
deck's summary slide (:func:`summary_slide`)."""
_DETAIL = "**In more detail**"


def summary_slide(src: str) -> tuple[str, str]:
    """A Summary cell as its slide and its speaker notes: ``(slide, notes)``.

    A cell holding :data:`KEY_POINTS` and ``**In more detail**`` keeps its heading, the key points and its
    ``**Next:**`` line on the slide, and gives the detailed list to the notes. Any other cell is returned as it is,
    with empty notes."""
    if KEY_POINTS not in src or _DETAIL not in src:
        return src, ""
    head, rest = src.split(_DETAIL, 1)
    nxt = ""
    if "**Next:**" in rest:
        rest, nxt = rest.split("**Next:**", 1)
        nxt = "\n\n**Next:**" + nxt
    return head.rstrip() + nxt, rest.strip()


def _explanation(cells, after: int) -> list[str]:
    """The lesson's prose that follows code cell ``after``: markdown cells up to the next code cell or section."""
    out = []
    for c in cells[after + 1:]:
        if c["cell_type"] != "markdown" or _source(c).startswith("## ") or _EXERCISE.match(_source(c)):
            break
        out.append(_source(c))
    return out


def lecture_pages(nb, number: str, title: str, minutes: int, facts: str = "", exercise_notes=None,
                  solutions_module: str | None = None, solutions=None, stills: bool = True) -> list[Page]:
    """The lesson's slides as :class:`Page` s (see the module docstring).

    ``exercise_notes``: open exercise number -> the instructor's notes; ``solutions``: checked exercise number ->
    its reference solution's source (from ``solutions_module``)."""
    cells = nb["cells"]
    solutions = solutions or {}
    exercise_notes = exercise_notes or {}
    points = POINT_CELLS.get(number, [])
    groups = []  # (opens_column, section, [blocks], key, [notes])
    cell_notes = {}  # code cell -> notes for the slide that shows its output
    section = title
    for i, cell in enumerate(cells):
        st = cell.get("metadata", {}).get("slideshow", {}).get("slide_type", "-")
        tags = set(cell.get("metadata", {}).get("tags", []))
        if st == "skip":
            continue
        src = _source(cell)
        if cell["cell_type"] == "markdown":
            if st == "notes":
                if groups:
                    groups[-1][4].append(src)
                continue
            if src.startswith("## "):
                section = src.splitlines()[0][3:].strip()
            src, detail = summary_slide(src)
            chunks = split_chunks(src)
            blocks = [Block("md", c, md_height(c), cell=i) for c in chunks]
            if i == 0 and facts:
                blocks.insert(1, Block("md", facts, md_height(facts), cell=i))
            if blocks:
                blocks[-1].lead_in = True
            notes = [f"**In more detail** (the lesson's summary):\n\n{detail}"] if detail else []
            m = _EXERCISE.match(src)
            if m:
                k = int(m.group(1))
                if k in exercise_notes:
                    notes.append(f"**Instructor notes — exercise {k}.** {exercise_notes[k]}")
                elif k in solutions:
                    notes.append(f"**Exercise {k}: reference solution** (`{solutions_module}`; "
                                 f"`posekit exercises solutions {number}` runs it against its checker):\n\n"
                                 f"```python\n{solutions[k]}\n```")
            if st in ("slide", "subslide") or not groups:
                groups.append([st == "slide", section, blocks, "", notes])
            else:
                groups[-1][2].extend(blocks)
                groups[-1][4].extend(notes)
            continue
        shown = SLIDE_CODE in tags or any(p in src for p in points)
        key = "key" if KEY_FIGURE in tags else "paper" if PAPER_BESIDE in tags else ""
        blocks = output_blocks(cell, i, shown, key, (lambda k: load_still(number, nb, k)) if stills else None)
        if not blocks:
            if st == "slide" and groups is not None:
                groups.append([True, section, [], "", []])
            continue
        notes = cell_notes.setdefault(i, [])
        expl = _explanation(cells, i)
        if expl:
            notes.append(_SAYS + "\n\n".join(expl))
        if any(b.kind == "html" and b.text.startswith(_LIVE) for b in blocks):
            notes.append("Switch to JupyterLab for this one: run the lesson up to "
                         f"{_where(cell)} and move the targets while the class watches.")
        if st in ("slide", "subslide") or not groups:
            groups.append([st == "slide", section, blocks, key, []])
        else:
            groups[-1][2].extend(blocks)
            groups[-1][3] = groups[-1][3] or key
    # a figure that opens its own slide takes its lead-in (a sentence ending in ':') from the slide before
    for g in range(1, len(groups)):
        prev, blocks = groups[g - 1][2], groups[g][2]
        if (blocks and blocks[0].is_output and prev and prev[-1].kind == "md"
                and prev[-1].text.rstrip().endswith(":")):
            blocks.insert(0, prev.pop())
            if not prev:  # the lead-in was the whole slide: its place (a column's start) goes with it
                groups[g][0] = groups[g][0] or groups[g - 1][0]
                groups[g][1] = groups[g - 1][1]
                groups[g][4] = groups[g - 1][4] + groups[g][4]
    pages = []
    where = lambda c: _where(cells[c]) if c >= 0 else "the notebook"  # noqa: E731
    for opens, sec, blocks, key, notes in groups:
        if not blocks:
            continue
        exercise = any(b.kind == "md" and _EXERCISE.match(b.text) for b in blocks)
        for k, chunk in enumerate(pack(blocks, where, CONT_PX if key else 0.0)):
            page = Page(chunk, opens and k == 0, sec, continued=k > 0, key=key if k == 0 else "")
            page.notes.extend(notes if k == 0 else [])
            prev = pages[-1] if pages else None
            # a short step joins the slide before it when both fit on one (not a section's start, an exercise or
            # the key figure, nor a slide after the key figure)
            alone = prev is not None and all(_heading(b) for b in prev.blocks)  # a section's bare heading
            if (k == 0 and prev and not page.opens_column and not key and (not exercise or alone) and not prev.key
                    and prev.section == sec and _used(prev) + _BLOCK_GAP + _used(page) <= BUDGET):
                prev.blocks.extend(chunk)
                prev.notes.extend(page.notes)
            else:
                pages.append(page)
    for page in pages:
        shown = " ".join(b.text for b in page.blocks if b.kind == "md")
        for c in dict.fromkeys(b.cell for b in page.blocks if b.is_output):
            page.notes.extend(n for n in cell_notes.get(c, [])
                              if not (n.startswith(_SAYS) and n[len(_SAYS):][:60] in shown))
            cell_notes.pop(c, None)
        size_figures(page)
    return pages


def _timing(pages: list[Page], minutes: int) -> list[tuple[str, int, int]]:
    sections, weights = [], []
    for p in pages:
        if p.opens_column and not p.key or not sections:
            sections.append(p.section)
            weights.append(0.0)
        figs = sum(b.is_output for b in p.blocks)
        weights[-1] += 1.0 + 0.5 * figs
    shares = section_plan(sections, weights, minutes)
    plan, t = [], 0
    for s, m in zip(sections, shares):
        plan.append((s, m, t))
        t += m
    return plan


# ---- pages as the notebook nbconvert's reveal template draws -----------------------------------------------------


def _block_html(b: Block) -> str:
    if b.kind == "png":
        origin = f' data-figure="{html.escape(b.origin)}"' if b.origin else ""  # a part names its whole figure
        return (f'<img class="posekit-figure" src="data:image/png;base64,{b.data}"{origin} '
                f'style="height:{int(b.height)}px" alt="figure">')
    if b.kind in ("pre", "code"):
        body = html.escape(b.text)
        if b.kind == "code":
            body = _highlight(b.text)
        note = f'<p class="posekit-cut">{html.escape(b.note)}</p>' if b.note else ""
        cls = "posekit-code" if b.kind == "code" else "posekit-out"
        return f'<pre class="{cls}" style="font-size:{b.font:.1f}px">{body}</pre>{note}'
    return ""


def _highlight(code: str) -> str:
    from pygments import highlight
    from pygments.formatters import HtmlFormatter
    from pygments.lexers import PythonLexer

    out = highlight(code, PythonLexer(), HtmlFormatter(nowrap=True))
    return out.rstrip("\n")


def _cell(kind: str, source: str, slide_type: str, outputs=None):
    import nbformat

    if kind == "md":
        c = nbformat.v4.new_markdown_cell(source)
    else:
        c = nbformat.v4.new_code_cell("")
        c.outputs = outputs or []
        c.metadata["transient"] = {"remove_source": True}
    c.metadata["slideshow"] = {"slide_type": slide_type}
    return c


def pages_to_cells(pages: list[Page]) -> list:
    """The pages as notebook cells typed for nbconvert's reveal.js template (``slide``, ``subslide``, ``-``,
    ``notes``)."""
    cells = []
    for page in pages:
        first = "slide" if page.opens_column or not cells else "subslide"
        out = []
        if page.key:
            label = "Key result" if page.key == "key" else "The paper beside ours"
            out.append(_cell("md", f'<p class="posekit-key">{label} — {html.escape(page.section)}</p>', first))
        elif page.continued:
            out.append(_cell("md", f'<p class="posekit-cont">{html.escape(page.section)} (continued)</p>', first))
        md = []

        def flush():
            if md:
                out.append(_cell("md", "\n\n".join(md), first if not out else "-"))
                md.clear()
        for b in page.blocks:
            if b.kind == "md":
                md.append(b.text)
                continue
            flush()
            if b.kind == "html" and b.text.startswith(_LIVE):
                out.append(_cell("md", f'<div class="posekit-widget-note">\n\n{b.text}\n\n</div>',
                                 first if not out else "-"))
                continue
            elif b.kind == "html" and b.text.lstrip().startswith("<"):
                outputs = [{"output_type": "display_data", "metadata": {}, "data": {"text/html": b.text}}]
            elif b.kind == "html":
                outputs = [{"output_type": "display_data", "metadata": {}, "data": {"text/markdown": b.text}}]
            else:
                outputs = [{"output_type": "display_data", "metadata": {}, "data": {"text/html": _block_html(b)}}]
            out.append(_cell("code", "", first if not out else "-", outputs))
        flush()
        if page.notes:
            out.append(_cell("md", "\n\n".join(page.notes), "notes"))
        cells.extend(out)
    return cells


def _solution_sources(lesson, nb) -> dict[int, str]:
    """Checked exercise number -> its reference solution's source (exercises without one are left out)."""
    import inspect
    import textwrap

    from .solutions import exercises, solution_function

    found = {}
    for ex in exercises(nb):
        if not ex.open:
            try:
                found[ex.number] = textwrap.dedent(inspect.getsource(solution_function(lesson, ex.function))).rstrip()
            except (LookupError, ImportError, OSError):
                pass
    return found


def lecture_notebook(nb, lesson=None, instructor: bool = False) -> dict:
    """The lesson ``nb`` as the notebook its reveal.js deck is drawn from (see the module docstring).

    Parameters
    ----------
    nb : dict
        An executed lesson, marked by the slide convention.
    lesson : posekit.course.lessons.Lesson, optional
        Its facts (title, planned time, prerequisites, paper, open-exercise notes); read from ``nb`` when absent.
    instructor : bool
        Put the exercises' reference solutions and instructor notes into the speaker notes (the instructor's
        deck, from ``instructor/solutions/``). Off by default: a deck given to students holds no solution.
    """
    import nbformat

    nb = copy.deepcopy(nb)
    first = _source(nb["cells"][0]).splitlines()[0] if nb["cells"] else "# lesson"
    number = (lesson.number if lesson else nb.get("metadata", {}).get("posekit", {}).get("lesson")) or "00"
    title = lesson.title if lesson else first.lstrip("# ").split("—", 1)[-1].strip()
    minutes = lesson.duration_min if lesson else int(nb.get("metadata", {}).get("posekit", {}).get("duration_min", 60))
    facts = [f"Lesson {number}", f"about {minutes} min"]
    paper = ""
    notes, module, solutions = {}, None, {}
    if lesson is not None:
        from .solutions import notes as open_notes, solutions_dir

        if lesson.prerequisites:
            facts.append(f"after lesson{'s' if len(lesson.prerequisites) > 1 else ''} {', '.join(lesson.prerequisites)}")
        if lesson.paper:
            paper = f"\n\n*Reproduces:* {lesson.paper}"
        if instructor:
            notes = open_notes(lesson)
            if (solutions_dir() / f"nb{number}.py").is_file():
                module = f"instructor/solutions/nb{number}.py"
                solutions = _solution_sources(lesson, nb)
    facts = f"*{' · '.join(facts)}*{paper}"
    pages = lecture_pages(nb, number, title, minutes, facts, notes, module, solutions)
    plan = _timing(pages, minutes)
    starts = {}
    for s, m, t in plan:
        starts.setdefault(s, (m, t))
    for p in pages:
        if p.opens_column and p.section in starts and not p.key:
            m, t = starts.pop(p.section)
            p.notes.insert(0, f"**Time:** about {m} min for this section (minutes {t}–{t + m} of {minutes}).")
    beside = any(PAPER_BESIDE in c.get("metadata", {}).get("tags", []) for c in nb["cells"])
    if lesson is not None and lesson.paper and not beside:
        for p in pages:
            if p.key == "key":
                p.notes.append("**The paper beside ours:** this lesson sets no table of the paper's figures beside its "
                               "own (no cell tagged `paper-beside`): its goals are the course's, as its Aim says.")
    pages[0].notes.insert(0, "**Plan** (the lesson's planned time shared by the sections' slides and figures):\n\n"
                          + "\n".join(f"- {s}: {m} min (from minute {t})" for s, m, t in plan))
    nb["cells"] = pages_to_cells(pages)
    nb.setdefault("metadata", {})["title"] = f"{number} — {title}"
    return nbformat.from_dict(nb)
