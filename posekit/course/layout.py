"""Fitting a lecture's content into slides: sizes estimated in CSS pixels, and blocks packed into 1280x720 slides.

The numbers here and the deck's stylesheet (``templates/posekit_reveal/index.html.j2``: padding, body text 24 px,
printed output at most 17 px) describe the same slide; change them together. :mod:`posekit.course.lecture` turns a
lesson into :class:`Block` s and lays them out with :func:`pack` and :func:`size_figures`;
``tests/test_slides_fit.py`` measures the result in Chromium.
"""

from __future__ import annotations

import base64
import math
import re
import struct
from dataclasses import dataclass, field

from .cells import SLIDE_HEIGHT, SLIDE_WIDTH

__all__ = ["Block", "Page", "WIDTH", "BUDGET", "PRE_PX", "KEY_PRE_PX", "MONO", "MIN_FIGURE", "CONT_PX", "md_height",
           "pre_font", "pre_height", "split_chunks", "split_tall_png", "pack", "size_figures"]

# ---- the deck's geometry: these numbers and the stylesheet in templates/posekit_reveal/index.html.j2 agree -------
PAD_X, PAD_Y = 48, 20
"""Slide padding (px): left/right, top/bottom."""
WIDTH = SLIDE_WIDTH - 2 * PAD_X
BUDGET = SLIDE_HEIGHT - 2 * PAD_Y - 24
"""Height (px) a slide's content may take: the slide less its padding and a margin for estimation error."""
TEXT_PX, TEXT_LINE = 24, 1.3
CHARS = int(WIDTH / (0.6 * TEXT_PX))
"""Characters of body text per line (a conservative mean glyph width)."""
PRE_PX, PRE_MIN_PX, PRE_LINE = 17, 11, 1.25
"""Printed output and shown code: font size, the smallest font a wide table may get, line height."""
KEY_PRE_PX = 21
"""The key table's largest font (px): it has its slide to itself."""
MONO = 0.66
"""A monospace glyph's width in ems."""
MIN_FIGURE = 300
"""A figure is not drawn shorter than this (px) to share a slide; it moves to a slide of its own instead."""
_BLOCK_GAP = 14
CONT_PX = 34
"""The "(continued)" line atop a slide that carries on a section."""


@dataclass
class Block:
    """One thing on a slide: a chunk of markdown, or one output (or shown code) of a code cell."""

    kind: str  # "md", "png", "pre", "html", "code"
    text: str = ""  # markdown, or preformatted text
    height: float = 0.0  # estimated px at its preferred size
    min_height: float = 0.0  # the least it may be drawn at (figures), else == height
    cell: int = -1  # index of the lesson cell it comes from
    data: str = ""  # png: base64
    size: tuple = (0, 0)  # png: natural (w, h)
    font: float = PRE_PX  # pre / code
    note: str = ""  # pre: a line said after a cut
    lead_in: bool = False  # md: a sentence that introduces what follows it
    origin: str = ""  # png cut from a taller figure: the head of the whole figure's base64 (its identity)

    def __post_init__(self):
        if not self.min_height:
            self.min_height = self.height

    @property
    def is_output(self) -> bool:
        return self.kind != "md"


@dataclass
class Page:
    """One slide of the deck: its blocks, whether it opens a column (a ``## `` section or the key figure), its
    section's title, and its speaker notes."""

    blocks: list
    opens_column: bool
    section: str
    continued: bool = False
    notes: list = field(default_factory=list)
    key: str = ""
    """``"key"``: the key figure's slide; ``"paper"``: the paper beside ours; ``""``: any other."""


# ---- estimating sizes ------------------------------------------------------------------------------------------


def _plain(md: str) -> str:
    """Markdown as the characters a reader sees (roughly): links and emphasis markers out, TeX shortened."""
    s = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", md)
    s = re.sub(r"\$([^$]+)\$", lambda m: "x" * max(1, len(m.group(1)) // 2), s)
    return s.replace("**", "").replace("`", "").replace("*", "")


def _math_state(s: str, in_math: bool) -> bool:
    """Whether a display formula (``$$ ... $$``) is still open after line ``s``."""
    t = s.rstrip(".,;:")
    if in_math:
        return not t.endswith("$$")
    if t.startswith("$$"):
        return not (len(t) >= 4 and t.endswith("$$") and t != "$$")
    return False


def md_height(md: str, width_chars: int = CHARS) -> float:
    """Estimated height (px) of a markdown chunk on a slide (a paragraph's or list item's source lines are one
    flowing text)."""
    h = 0.0
    line_px = TEXT_PX * TEXT_LINE
    in_math = False
    para, indent = [], 0

    def flush():
        nonlocal h, para
        if para:
            h += line_px * max(1, math.ceil(len(_plain(" ".join(para))) / (width_chars - indent)))
            para = []
    for line in md.splitlines():
        s = line.strip()
        was = in_math
        in_math = _math_state(s, in_math)
        if was or s.startswith("$$"):
            flush()
            h += 14 if was else 60
            continue
        item = re.match(r"^([-*+]|\d+\.)\s", s)
        if not s or s.startswith(("#", "|")) or item:
            flush()
        if not s:
            h += 6
        elif s.startswith("# "):
            h += 46 * 1.2 * math.ceil(len(s) / 44) + 20
        elif s.startswith("## "):
            h += 36 * 1.2 * math.ceil(len(s) / 56) + 18
        elif s.startswith("#"):
            h += 30 * 1.2 * math.ceil(len(s) / 66) + 14
        elif s.startswith("|"):
            if not re.match(r"^\|[\s:|-]+\|$", s):  # a table row (20 px text): as tall as its longest cell
                cols = [_plain(c).strip() for c in s.strip("|").split("|")]
                per_col = max(4, int(WIDTH / (0.56 * 20) / len(cols)) - 2)
                h += 26 * max(math.ceil(len(c) / per_col) or 1 for c in cols) + 8
        else:
            if item:
                indent = 5
                h += 4
            elif not para:
                indent = 0
            para.append(s)
    flush()
    return h + 12


def _png_size(b64: str) -> tuple[int, int]:
    raw = base64.b64decode(b64[:64] + "=" * (-len(b64[:64]) % 4))
    w, h = struct.unpack(">II", raw[16:24])
    return int(w), int(h)


REACH = 1.5
"""How far past ``max_rows`` :func:`split_tall_png` looks for the gap between two rows of panels (a part that ends
there is drawn a little smaller to fit, rather than cut through a panel's labels)."""


def split_tall_png(b64: str, max_rows: float, white: int = 245) -> list[str]:
    """A tall figure cut across its white bands into parts each at most ``max_rows`` pixel rows high.

    A grid of panels drawn much taller than a slide would have to shrink until its panels could not be read; cut between
    its rows of panels (runs of rows whose every pixel is at least ``white`` in every channel), each part can take
    a slide at a readable size. The figure is read as runs of drawn rows, panels and thin runs (lines of text);
    between two panels the cut takes the widest gap that does not part a panel from the text right above it (its
    title): the lowest such cut within ``max_rows``, else the nearest within :data:`REACH` times it.
    A figure with no white band where one is needed is returned whole (``[b64]``), as is one that already fits.
    """
    import io

    import numpy as np
    from PIL import Image

    img = Image.open(io.BytesIO(base64.b64decode(b64))).convert("RGB")
    px = np.asarray(img)
    h = px.shape[0]
    if h <= max_rows:
        return [b64]
    blank = (px.min(axis=(1, 2)) >= white)
    edges = np.flatnonzero(np.diff(np.r_[0, (~blank).astype(np.int8), 0]))
    blocks = list(zip(edges[::2], edges[1::2]))  # runs of drawn rows: [start, end)
    thin = max(8.0, 0.04 * h)  # a line of text (a title, tick labels), not a panel
    big = [k for k, (a, b) in enumerate(blocks) if b - a >= thin]
    if len(big) < 2:
        return [b64]
    allowed = []
    for prev, k in zip(big, big[1:]):
        # the gaps between two panels; the one right above a panel parts it from its own title, so it is left out
        # when there is text between them, and the cut takes the widest of the rest (wider than a line's spacing)
        gaps = [(blocks[j + 1][0] - blocks[j][1], (blocks[j][1] + blocks[j + 1][0]) // 2) for j in range(prev, k)]
        allowed.append(max(gaps[:-1] or gaps)[1])
    cuts, start = [], 0
    while h - start > max_rows:
        fits = [c for c in allowed if start + 0.25 * max_rows <= c <= start + max_rows]
        near = [c for c in allowed if start + max_rows < c <= start + REACH * max_rows]
        if not fits and not near:
            break
        start = max(fits) if fits else min(near)
        cuts.append(start)
    if not cuts:
        return [b64]
    parts = []
    for a, b in zip([0] + cuts, cuts + [h]):
        buf = io.BytesIO()
        img.crop((0, a, img.width, b)).save(buf, format="PNG")
        parts.append(base64.b64encode(buf.getvalue()).decode())
    return parts


_TABULAR = re.compile(r"\S {2,}\S|^\s+\S")
"""A line laid out in columns (a run of spaces inside it, or indented): its width must not wrap."""


def pre_font(lines: list[str], largest: float = PRE_PX) -> float:
    """The font (px) a block of preformatted lines gets so that its widest line fits the slide."""
    widest = max((len(ln) for ln in lines if _TABULAR.search(ln)), default=1)  # a sentence may wrap, a table not
    return max(PRE_MIN_PX, min(largest, WIDTH / (MONO * max(widest, 1))))


def pre_height(lines: list[str], font: float) -> float:
    """Estimated height (px) of preformatted lines at ``font`` px (lines too wide even then wrap)."""
    per_line = max(1, int(WIDTH / (MONO * font)))
    rows = sum(max(1, math.ceil(len(ln) / per_line)) for ln in lines)
    return rows * font * PRE_LINE + 16


def split_chunks(md: str) -> list[str]:
    """A markdown cell's natural breaks: paragraphs, lists, tables and display formulas, each kept whole."""
    chunks, cur, in_math, in_fence = [], [], False, False
    for line in md.splitlines():
        s = line.strip()
        if s.startswith("```"):
            in_fence = not in_fence
        in_math = _math_state(s, in_math)
        if not s and not in_math and not in_fence:
            if cur:
                chunks.append("\n".join(cur))
                cur = []
            continue
        cur.append(line)
    if cur:
        chunks.append("\n".join(cur))
    return chunks


# ---- packing blocks into slides --------------------------------------------------------------------------------


def _fit_alone(b: Block, room: float, where: str) -> list[Block]:
    """A block too tall for a slide of its own, cut so it fits ``room`` px (printed text, markdown) — the rest
    said to be in the notebook — or split into pieces that each fit (markdown lists)."""
    if b.kind in ("pre", "code"):
        lines = b.text.splitlines()
        line_px = b.font * PRE_LINE
        keep = max(3, int((room - 16 - 34) / line_px))
        keep = min(keep, len(lines))
        while keep > 3 and pre_height(lines[:keep], b.font) + 34 > room:
            keep -= 1
        if keep == len(lines):  # the lines fit (they only wrapped on the estimate's side)
            return [Block(b.kind, b.text, pre_height(lines, b.font) + (30 if b.note else 0), cell=b.cell, font=b.font,
                          note=b.note)]
        note = f"… {len(lines) - keep} more lines: the whole is in the notebook ({where})"
        return [Block(b.kind, "\n".join(lines[:keep]), pre_height(lines[:keep], b.font) + 34, cell=b.cell,
                      font=b.font, note=note)]
    if b.kind == "md":
        units = []  # list items (with their wrapped source lines), else single lines
        for ln in b.text.splitlines():
            if units and not re.match(r"^\s*([-*+]|\d+\.)\s", ln) and re.match(r"^\s*([-*+]|\d+\.)\s", units[-1][0]):
                units[-1].append(ln)
            else:
                units.append([ln])
        pieces, cur, limit = [], [], room
        for unit in units:
            if cur and md_height("\n".join(cur + unit)) > limit:
                pieces.append("\n".join(cur))
                cur, limit = [], BUDGET - CONT_PX
            cur.extend(unit)
        pieces.append("\n".join(cur))
        return [Block("md", p, md_height(p), cell=b.cell) for p in pieces]
    if b.kind == "html":  # a markdown output (a report): its first lines
        lines, keep = b.text.splitlines(), []
        for ln in lines:
            if md_height("\n".join(keep + [ln]), int(CHARS * 1.15)) > room - 40:
                break
            keep.append(ln)
        rest = len(lines) - len(keep)
        text = "\n".join(keep) + (f"\n\n*… {rest} more lines: the whole is in the notebook ({where}).*" if rest else "")
        return [Block("html", text, md_height(text, int(CHARS * 1.15)), cell=b.cell)]
    b.height = b.min_height = min(b.height, room)
    return [b]


def pack(blocks: list[Block], where, head: float = 0.0) -> list[list[Block]]:
    """Blocks into slides of at most :data:`BUDGET` px, in order; a figure or table moves with its lead-in.

    ``where(cell)`` names a cell for "the whole is in the notebook" notes; ``head`` px are taken on the first slide
    (its "Key result" line)."""
    pages, cur, used = [], [], head
    for b in blocks:
        gap = _BLOCK_GAP if cur or used else 0
        if used + gap + b.height <= BUDGET or (b.kind == "png" and used + gap + b.min_height <= BUDGET):
            cur.append(b)
            used += gap + min(b.height, BUDGET - used - gap)
            continue
        if b.kind == "md" and cur and all(_heading(x) for x in cur) and BUDGET - used - gap > 3 * TEXT_PX * TEXT_LINE:
            pieces = _fit_alone(b, BUDGET - used - gap, where(b.cell))  # a heading keeps the text it heads
            if len(pieces) > 1:
                pages.append(cur + [pieces[0]])
                cur, used = [], CONT_PX
                for p in pieces[1:-1]:
                    pages.append([p])
                b = pieces[-1]
                cur.append(b)
                used += b.height
                continue
        carry = []
        if b.is_output and cur and cur[-1].lead_in:
            carry = [cur.pop()]
            while cur and _heading(cur[-1]):  # a heading does not stay behind alone
                carry.insert(0, cur.pop())
        if cur:
            pages.append(cur)
        cur = carry
        used = CONT_PX + sum(x.height for x in cur) + _BLOCK_GAP * len(cur)
        room = BUDGET - used
        if b.min_height > room:
            pieces = _fit_alone(b, room if room > BUDGET / 2 else BUDGET - CONT_PX, where(b.cell))
            if room <= BUDGET / 2 and cur:
                pages.append(cur)
                cur, used = [], CONT_PX
            for p in pieces[:-1]:
                pages.append(cur + [p])
                cur, used = [], CONT_PX
            b = pieces[-1]
        cur.append(b)
        used += b.height + (_BLOCK_GAP if len(cur) > 1 else 0)
    if cur:
        pages.append(cur)
    return pages


def size_figures(page: Page) -> None:
    """Give a slide's figures the height its other blocks leave (each at least its least height)."""
    figs = [b for b in page.blocks if b.kind == "png"]
    if not figs:
        return
    other = sum(b.height for b in page.blocks if b.kind != "png") + _BLOCK_GAP * (len(page.blocks) - 1)
    other += CONT_PX if page.continued or page.key else 0
    room = max(BUDGET - other, MIN_FIGURE * len(figs))
    want = sum(b.height for b in figs)
    for b in figs:
        b.height = max(min(b.height * room / want if want > room else b.height * min(room / want, 1.6), BUDGET),
                       min(b.min_height, room / len(figs)))
        b.height = min(b.height, room / len(figs) if len(figs) > 1 else room, b.size[1] * WIDTH / b.size[0])


def _heading(b: Block) -> bool:
    return b.kind == "md" and b.text.lstrip().startswith("#") and "\n" not in b.text.strip()


def _used(page: Page) -> float:
    head = CONT_PX if page.continued or page.key else 0.0
    return head + sum(b.height for b in page.blocks) + _BLOCK_GAP * (len(page.blocks) - 1)
