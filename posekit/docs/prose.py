"""Figures in prose and the sources they are bound to: the lessons' cell bindings, the README's and ``docs/``'s markers.

A measured figure in prose is bound to where it comes from — an output of a code cell of the same notebook, or a
key of a results file under ``data_samples/results`` — or to why it needs no source (a goal, a paper's figure, a
definition, a setting). On a page (the README, ``docs/``) the binding is an HTML comment right after the figure, a
*source marker*: not rendered on GitHub, readable in the raw text. A lesson's markdown holds words, maths and links
only, so each markdown cell keeps its bindings in its metadata (:func:`cell_bindings`), each naming its figure by
its text and its place among the cell's places that write it; :func:`move_markers` moves markers there, and
:func:`inline_bindings` puts them back in the text for the marking tool. ``tests/test_prose_numbers.py`` reads every
page and lesson with this module and compares each figure with the value its source names; the syntax is written
down once, in ``docs/testing.md`` (*Figures in prose*) and in that test's docstring. ``posekit docs build``
(:mod:`posekit.docs.bench_page`) writes the markers of the pages it renders with :func:`data_marker`.

This module finds the figures (:func:`figures`), reads the markers (:func:`parse_markers`) and a cell's bindings
(:func:`binding_markers`), resolves a source (:class:`Outputs`, :func:`resolve_data`) and compares
(:func:`agrees`): :func:`check_text` for a page, :func:`check_cell` for a lesson's cell. It imports nothing of
posekit.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["UNITS", "EXEMPT_KINDS", "Figure", "Marker", "Source", "SourceError", "blank_non_prose", "figures",
           "mark_figures",
           "parse_markers", "bind", "Outputs", "resolve_data", "agrees", "data_marker", "check_text", "in_words",
           "BINDINGS_KEY", "BINDINGS_FIELD", "cell_bindings", "set_cell_bindings", "figure_pattern",
           "binding_markers", "check_cell", "inline_bindings", "move_markers"]

# --------------------------------------------------------------------------------------------------- units
# unit as written -> (family, factor to the family's base unit)
UNITS = {
    "µm": ("length", 1e-6), "um": ("length", 1e-6), "mm": ("length", 1e-3), "cm": ("length", 1e-2),
    "m": ("length", 1.0), "metres": ("length", 1.0), "meters": ("length", 1.0),
    "µs": ("time", 1e-6), "us": ("time", 1e-6), "microseconds": ("time", 1e-6), "microsecond": ("time", 1e-6),
    "ms": ("time", 1e-3), "milliseconds": ("time", 1e-3), "millisecond": ("time", 1e-3),
    "s": ("time", 1.0), "sec": ("time", 1.0), "seconds": ("time", 1.0), "second": ("time", 1.0),
    "min": ("time", 60.0), "minutes": ("time", 60.0), "minute": ("time", 60.0),
    "h": ("time", 3600.0), "hours": ("time", 3600.0), "hour": ("time", 3600.0),
    # a time per item is a time ("12.9 µs/pose" is backed by "12.9 µs" per pose)
    "µs/pose": ("time", 1e-6), "us/pose": ("time", 1e-6), "µs per pose": ("time", 1e-6),
    "ms/pose": ("time", 1e-3), "ms per pose": ("time", 1e-3), "ms/solve": ("time", 1e-3),
    "ms per solve": ("time", 1e-3), "ms/case": ("time", 1e-3), "ms/step": ("time", 1e-3),
    "s/step": ("time", 1.0), "s per step": ("time", 1.0), "s/epoch": ("time", 1.0),
    "core-hours": ("core-time", 3600.0), "core-hour": ("core-time", 3600.0), "core-min": ("core-time", 60.0),
    "×": ("ratio", 1.0), "x": ("ratio", 1.0), "times": ("ratio", 1.0),
    "°": ("angle", math.pi / 180), "deg": ("angle", math.pi / 180), "degrees": ("angle", math.pi / 180),
    "degree": ("angle", math.pi / 180), "rad": ("angle", 1.0), "radians": ("angle", 1.0),
    "poses/s": ("rate", 1.0), "solves/s": ("rate", 1.0), "poses per second": ("rate", 1.0),
    "solves per second": ("rate", 1.0), "poses a second": ("rate", 1.0), "solves a second": ("rate", 1.0),
    "poses/second": ("rate", 1.0), "poses/sec": ("rate", 1.0), "solves/sec": ("rate", 1.0),
    "poses per s": ("rate", 1.0), "solves per s": ("rate", 1.0), "cases/s": ("rate", 1.0),
    "updates/s": ("rate", 1.0), "updates per second": ("rate", 1.0), "steps/s": ("rate", 1.0),
    "k poses/s": ("rate", 1e3), "M poses/s": ("rate", 1e6),
    "frames/s": ("frames/s", 1.0), "frame/s": ("frames/s", 1.0), "fps": ("frames/s", 1.0),
    "frames per second": ("frames/s", 1.0),
    "GMAC/s": ("arithmetic rate", 1e9), "GFLOP/s": ("arithmetic rate", 1e9), "GFLOPS": ("arithmetic rate", 1e9),
    "steps": ("steps", 1.0), "step": ("steps", 1.0),
    "%": ("percent", 1.0), "per cent": ("percent", 1.0),
    # a share written as a fraction: only for a source (``unit share``; keys ending in _fraction / _share)
    "share": ("percent", 100.0),
    "B": ("size", 1.0), "bytes": ("size", 1.0), "kB": ("size", 1e3), "KB": ("size", 1e3), "MB": ("size", 1e6),
    "GB": ("size", 1e9), "KiB": ("size", 2.0 ** 10), "MiB": ("size", 2.0 ** 20), "GiB": ("size", 2.0 ** 30),
    "parameters": ("parameters", 1.0), "k parameters": ("parameters", 1e3), "M parameters": ("parameters", 1e6),
    "weights": ("parameters", 1.0), "k weights": ("parameters", 1e3),
    "multiply-adds": ("multiply-adds", 1.0), "k multiply-adds": ("multiply-adds", 1e3),
    "M multiply-adds": ("multiply-adds", 1e6), "MACs": ("multiply-adds", 1.0),
}
_PROSE_ONLY = {"share"}
_UNIT_ALT = "|".join(sorted((re.escape(u) for u in UNITS if u not in _PROSE_ONLY), key=len, reverse=True))
NUM = r"\d{1,3}(?:,\d{3})+(?:\.\d+)?|\d+(?:\.\d+)?"
_NUM_IN = re.compile(NUM)
# the unit follows the number (a space or none; "9x", "0.5°", "12 %"), and is not the start of a longer word
_UNIT_AFTER = rf"[ \u00a0\u202f]?(?P<unit>{_UNIT_ALT})(?![\w/²^])"
_SEP = r"\s*(?:–|-|/|,|to|and|or|against)\s*"
# a figure: one or more numbers joined by list or range separators, then a unit
_PROSE = re.compile(rf"(?<![\w.$^{{/-])(?P<nums>(?:{NUM})(?:{_SEP}(?:{NUM}))*){_UNIT_AFTER}")
_SUPER = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻⁺", "0123456789-+")
# scientific notation: "3 × 10⁻⁴", "3e-4", "1.2E5", "10⁻³"
_SCI = re.compile(r"(?<![\w.$^{/-])(?:(?P<mant>\d+(?:\.\d+)?)\s?[×x·]\s?10(?P<sup>[⁻⁺]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+)"
                  r"|(?P<emant>\d+(?:\.\d+)?)[eE](?P<eexp>[-+]?\d+)"
                  r"|10(?P<only>[⁻⁺]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+))(?!\w|\.\w)")
# what a bare decimal after these is: a section or algorithm number, an arXiv id, a version, a DOI
_NOT_A_FIGURE = re.compile(r"(?:Secs?\.|Sections?|sections?|Alg\.|Algorithm|Eqs?\.|Table|Fig\.|arXiv:|doi:\S*|"
                           r"versions?|v|ikpy|pyfabrik|numpy|torch|Python|nbval|nbgrader|SQLAlchemy|ipywidgets|"
                           r"pythreejs|JupyterLab|Voila|BY(?:-NC)?(?:-SA)?|lessons?|Lessons?)"
                           r"\s*(?:\d+(?:\.\d+)*\s*[–-]\s*)?[(]?$")
# a sentence's full stop may follow ("... is 0.92."), a version's next part may not ("1.2.3")
_BARE_DECIMAL = re.compile(r"(?<![\w.$^{/-])(?P<num>\d+\.\d+)(?![\w%°×/-]|\.\w)")
# a bare integer of a list that ends in a figure: "FABRIK 71, DLS 56 and CCD 80 mm" -> 71 and 56
_LIST_ITEM = re.compile(rf"(?<![\w.$^{{/–-])(?P<num>{NUM})(?P<gap>\s*(?:,|\band\b|\bor\b|/)\s*(?:(?:and|or)\s+)?"
                        r"(?:[^\W\d][\w'’+-]*\s+){0,3})$")

# a measured duration or ratio written in words (it escapes every check): write its digits
_WORD_NUMBER = (r"(?:one|two|three|four|five|six|seven|eight|nine|ten|eleven|twelve|fifteen|twenty|thirty|forty|"
                r"fifty|sixty|a hundred|hundreds|a thousand|thousands|a tenth of a|a few|tens)")
_IN_WORDS = re.compile(
    rf"(?i)\b(?:(?:about|roughly|nearly|some|under|over|within|in|takes?|took|only)\s+(?:an?|{_WORD_NUMBER})"
    rf"(?:\s+(?:to|or)\s+{_WORD_NUMBER})?|{_WORD_NUMBER}(?:\s+(?:to|or)\s+{_WORD_NUMBER})?)\s+"
    r"(?P<unit>microseconds?|milliseconds?|seconds?|minutes?|hours?|times\s+(?:faster|slower|as|more|less|longer|"
    r"shorter|larger|smaller|higher|lower|fewer|the))\b")

EXEMPT_KINDS = ("goal", "paper", "definition", "setting")
"""Marker kinds that say why a figure has no measured source; each needs a reason."""


def family(unit):
    """``(family, factor to its base unit)`` of a unit as written, or ``(None, None)``."""
    if unit is None:
        return None, None
    return UNITS[unit] if unit in UNITS else UNITS.get(unit.lower(), (None, None))


def _value(s: str) -> float:
    return float(s.replace(",", ""))


def _decimals(s: str) -> int:
    return len(s.split(".")[1]) if "." in s else 0


# --------------------------------------------------------------------------------------------------- the text
def _blank(text: str, a: int, b: int) -> str:
    return text[:a] + re.sub(r"[^\n]", " ", text[a:b]) + text[b:]


def blank_non_prose(text: str, comments: bool = True) -> str:
    """``text`` with what is not prose replaced by spaces of the same length (offsets and lines stay): code blocks
    and spans, maths, link targets, HTML comments, and blocks a command renders from its results file
    (``<!-- NAME: begin (command) -->`` ... ``<!-- NAME: end -->``: the test of that command compares them).
    ``comments=False`` keeps the other HTML comments."""
    patterns = [r"<!-- ([\w-]+): begin.*?<!-- \1: end -->", r"```.*?```", r"`[^`]*`", r"\$\$.*?\$\$",
                r"\$[^$\n]*\$", r"(?<=\])\([^)\n]*\)"] + ([r"<!--.*?-->"] if comments else [])
    for pattern in patterns:
        for m in list(re.finditer(pattern, text, flags=re.S)):
            text = _blank(text, m.start(), m.end())
    return text


@dataclass
class Figure:
    """One number of the prose: ``written`` is the whole figure as written ("71 / 56 / 80 mm"), ``num`` this
    number ("56"), ``unit`` the figure's unit (None: a bare number), ``scale`` a power of ten the number is
    multiplied by (scientific notation), ``start``/``end`` the number's offsets, ``fig_end`` the figure's end."""
    written: str
    num: str
    unit: str | None
    start: int
    end: int
    fig_end: int
    group: int
    scale: float = 1.0
    required: bool = True

    @property
    def value(self) -> float:
        return _value(self.num) * self.scale

    @property
    def half_step(self) -> float:
        """Half the last written digit's step: the prose's rounding."""
        return 0.5 * 10.0 ** -_decimals(self.num) * self.scale


def _sci_value(m):
    if m.group("mant"):
        return m.group("mant"), 10.0 ** int(m.group("sup").translate(_SUPER))
    if m.group("emant"):
        return m.group("emant"), 10.0 ** int(m.group("eexp"))
    return "1", 10.0 ** int(m.group("only").translate(_SUPER))


_SECTION_LIST = re.compile(r"(?:Secs?\.|Sections?|sections?)\s*\d+(?:\.\d+)*(?:\s*\([^)]*\))?"
                           r"(?:\s*(?:,|and|or|–)\s*\d+(?:\.\d+)*(?:\s*\([^)]*\))?)*\s*(?:,|and|or|–)\s*$")


def _not_a_figure(prose: str, start: int) -> bool:
    """A section, an equation, an arXiv id, a version: by the words before the number (up to a list of sections,
    "Sec. 3.2 (data), 3.3 (autoencoder)")."""
    return bool(_NOT_A_FIGURE.search(prose[max(0, start - 24):start])
                or _SECTION_LIST.search(prose[max(0, start - 200):start]))


def figures(prose: str) -> list[Figure]:
    """Every figure of ``prose`` (already :func:`blank_non_prose`'d) that needs a source: numbers with a unit
    (each number of a list or range), scientific notation, bare decimals, and the bare integers of a list that
    ends in a figure with a unit ("FABRIK 71, DLS 56 and CCD 80 mm": one figure, three numbers, one ``group``)."""
    out: list[Figure] = []
    taken: list[tuple[int, int]] = []
    group = 0
    for m in _SCI.finditer(prose):
        num, scale = _sci_value(m)
        unit = None
        u = re.match(_UNIT_AFTER, prose[m.end():])
        if u:
            unit = u.group("unit")
        end = m.end() + (u.end() if u else 0)
        out.append(Figure(prose[m.start():end], num, unit, m.start(), m.end(), end, group, scale))
        taken.append((m.start(), end))
        group += 1
    unit_figs = []
    for m in _PROSE.finditer(prose):
        if any(a <= m.start() < b for a, b in taken):
            continue
        if m.group("unit") in ("×", "x") and re.match(r"\s*\d", prose[m.end():]):
            continue                  # a dimension ("2 × 200", "4 x 256"), not a ratio
        base = m.start("nums")
        nums = [Figure(m.group(0), n.group(0), m.group("unit"), base + n.start(), base + n.end(), m.end(), group)
                for n in _NUM_IN.finditer(m.group("nums"))]
        out += nums
        unit_figs.append(nums)
        taken.append((m.start(), m.end()))
        group += 1
    # the bare integers of lists that end in a figure, read backwards from the figure's first number
    for nums in unit_figs:
        first = nums[0]
        while True:
            m = _LIST_ITEM.search(prose[max(0, first.start - 80):first.start])
            if not m:
                break
            s = max(0, first.start - 80) + m.start("num")
            e = s + len(m.group("num"))
            if s > 0 and re.match(r"[\w.$^{/–-]", prose[s - 1]):
                break                 # the window began inside a number or a word
            if any(a <= s < b for a, b in taken) or _not_a_figure(prose, s):
                break
            if "." in m.group("num"):
                break                 # a bare decimal: read below
            item = Figure(m.group("num"), m.group("num"), None, s, e, e, first.group)
            out.append(item)
            taken.append((s, e))
            first = item
    last = None
    for m in _BARE_DECIMAL.finditer(prose):
        if any(a <= m.start() < b for a, b in taken):
            continue
        if _not_a_figure(prose, m.start()):
            continue                  # a section, an equation, an arXiv id, a version
        if last is not None and re.fullmatch(_SEP, prose[last.end:m.start()]):
            g = last.group            # a list of bare decimals ("0.5, 0.8, 0.95 and 0.999"): one figure
        else:
            g, group = group, group + 1
        last = Figure(m.group("num"), m.group("num"), None, m.start(), m.end(), m.end(), g)
        out.append(last)
    return sorted(out, key=lambda f: f.start)


def mark_figures(text: str, marker: str) -> str:
    """``text`` with ``marker`` written after each figure that :func:`figures` finds in it and no marker follows
    (for generated text whose figures are all settings: ``<!-- setting: ... -->``)."""
    prose = blank_non_prose(text)
    ends = {}
    for f in figures(prose):
        ends[f.group] = max(ends.get(f.group, 0), f.fig_end)
    for end in sorted(ends.values(), reverse=True):
        if not text[end:].lstrip(" ").startswith("<!--"):
            text = text[:end] + marker + text[end:]
    return text


def in_words(prose: str) -> list[str]:
    """Measured durations and ratios written in words ("about a minute", "ten times faster"): they escape every
    check, so they are refused."""
    return [m.group(0) for m in _IN_WORDS.finditer(prose)]


# --------------------------------------------------------------------------------------------------- markers
class SourceError(ValueError):
    """A marker that cannot be read, or a source that does not exist."""


@dataclass
class Source:
    """``kind``: ``out`` (anchors, ``col`` or ``nth``), ``data`` (``file``, ``path``), or one of
    :data:`EXEMPT_KINDS` (``reason``); ``unit``: the source's unit when the marker states it."""
    kind: str
    text: str
    anchors: list = field(default_factory=list)
    col: str | None = None
    nth: int = 1
    file: str | None = None
    path: str | None = None
    unit: str | None = None
    scale: float = 1.0
    reason: str = ""


@dataclass
class Marker:
    start: int
    end: int
    raw: str
    sources: list
    line_start: bool
    error: str | None = None


_MARKER = re.compile(r"<!--\s*(?P<kind>out|data|goal|paper|definition|setting)\s*:(?P<body>.*?)-->", re.S)
_TOKEN = re.compile(r'\s*(?:"(?P<q>[^"]*)"|(?P<w>[^\s"]+))')


def _parse_source(kind: str, body: str) -> Source:
    body = body.strip()
    text = f"{kind}: {body}"
    if kind in EXEMPT_KINDS:
        if not body:
            raise SourceError(f"'{kind}:' needs its reason")
        return Source(kind, text, reason=body)
    tokens = []
    pos = 0
    while pos < len(body):
        m = _TOKEN.match(body, pos)
        if not m or m.end() == pos:
            raise SourceError(f"cannot read '{body}' (an unclosed quote?)")
        tokens.append(("q", m.group("q")) if m.group("q") is not None else ("w", m.group("w")))
        pos = m.end()
        while pos < len(body) and body[pos].isspace():
            pos += 1
    src = Source(kind, text)
    rest = []
    k = 0
    while k < len(tokens):
        t, v = tokens[k]
        if t == "w" and v == "unit" and k + 1 < len(tokens):
            src.unit = tokens[k + 1][1]
            if family(src.unit)[0] is None:
                raise SourceError(f"unknown unit '{src.unit}' (known: {', '.join(UNITS)})")
            k += 2
            continue
        if t == "w" and v == "scale" and k + 1 < len(tokens):
            try:
                src.scale = float(tokens[k + 1][1])
            except ValueError:
                raise SourceError(f"scale takes a number ('scale 1000': the value times 1000), not "
                                  f"'{tokens[k + 1][1]}'") from None
            k += 2
            continue
        if t == "w" and v == "col" and k + 1 < len(tokens) and tokens[k + 1][0] == "q":
            src.col = tokens[k + 1][1]
            k += 2
            continue
        if t == "w" and re.fullmatch(r"#\d+", v):
            src.nth = int(v[1:])
            k += 1
            continue
        rest.append((t, v))
        k += 1
    if kind == "out":
        if not rest or any(t != "q" for t, _ in rest):
            raise SourceError(f"'out:' takes quoted output text (\"...\"), then optionally col \"HEADER\", #N or "
                              f"unit U; got '{body}'")
        src.anchors = [v for _, v in rest]
        if any(not a.strip() for a in src.anchors):
            raise SourceError("an empty quoted anchor")
    else:
        if len(rest) != 2 or any(t != "w" for t, _ in rest):
            raise SourceError(f"'data:' takes a results file and a key path (data: bench_all.json "
                              f"rows[method=dls,effectors=2,start=rest].mpjpe_mm_median); got '{body}'")
        src.file, src.path = rest[0][1], rest[1][1]
    return src


def _split_sources(inner: str) -> list[tuple[str, str]]:
    """``kind: body; kind: body`` -> [(kind, body)], splitting at ``;`` outside quotes before ``out:``/``data:``."""
    parts, cur, quoted = [], "", False
    for ch in inner:
        if ch == '"':
            quoted = not quoted
        if ch == ";" and not quoted:
            parts.append(cur)
            cur = ""
            continue
        cur += ch
    parts.append(cur)
    out = []
    for p in parts:
        m = re.match(r"\s*(out|data|goal|paper|definition|setting)\s*:(.*)$", p, re.S)
        if not m:
            if out and out[-1][0] in EXEMPT_KINDS:
                out[-1] = (out[-1][0], out[-1][1] + ";" + p)     # a reason may hold a semicolon
                continue
            raise SourceError(f"'{p.strip()}' does not start with out:, data:, goal:, paper:, definition: or setting:")
        out.append((m.group(1), m.group(2)))
    return out


def parse_markers(text: str) -> list[Marker]:
    """Every source marker of ``text`` (code blocks and spans left out): ``<!-- out: ... -->``,
    ``<!-- data: ... -->``, ``<!-- goal|paper|definition|setting: reason -->``; several sources of a list figure
    are separated by ``;``."""
    kept = blank_non_prose(text, comments=False)
    markers = []
    for m in _MARKER.finditer(text):
        if kept[m.start():m.end()] != m.group(0):
            continue                  # inside code or a rendered block: an example, not a marker
        inner = m.group(0)[4:-3]
        line_start = text[:m.start()].rsplit("\n", 1)[-1].strip() == ""
        try:
            sources = [_parse_source(k, b) for k, b in _split_sources(inner)]
            err = None
        except SourceError as e:
            sources, err = [], str(e)
        markers.append(Marker(m.start(), m.end(), m.group(0), sources, line_start, err))
    return markers


def bind(prose: str, figs: list[Figure], markers: list[Marker]):
    """Pair markers with figures: a marker binds the number (or the whole figure, unit included) that ends right
    before it (spaces allowed). One source binds that number; a marker after a list figure with one source per
    number binds them in order; an exemption after a figure covers all its numbers. A marker after a number that
    is no figure (a count) makes it one. Returns ``(pairs, errors)``: ``pairs`` a list of (Figure, Source or None,
    Marker or None) for every figure; ``errors`` (Marker, message) for markers that bind nothing."""
    by_end = {}
    for f in figs:
        by_end.setdefault(f.end, []).append(f)
    groups = {}
    for f in figs:
        groups.setdefault(f.group, []).append(f)
    fig_end = {}
    for g, fs in groups.items():
        fig_end.setdefault(fs[-1].fig_end, g)
    bound: dict[int, tuple] = {}
    errors = []
    extra = []
    for mk in markers:
        if mk.error:
            errors.append((mk, mk.error))
            continue
        q = mk.start
        while q > 0 and prose[q - 1] in " \u00a0":
            q -= 1
        if q in fig_end:
            fs = groups[fig_end[q]]
            if mk.sources[0].kind in EXEMPT_KINDS:
                for f in fs:
                    bound[id(f)] = (f, mk.sources[0], mk)
                continue
            free = [f for f in fs if id(f) not in bound]
            if len(mk.sources) == len(free):
                for f, s in zip(free, mk.sources):
                    bound[id(f)] = (f, s, mk)
            elif len(mk.sources) == 1:
                bound[id(fs[-1])] = (fs[-1], mk.sources[0], mk)
            else:
                errors.append((mk, f"{len(mk.sources)} sources for '{fs[0].written}', which has {len(free)} "
                                   "numbers without one"))
            continue
        if q in by_end:
            f = by_end[q][0]
            if len(mk.sources) != 1:
                errors.append((mk, f"{len(mk.sources)} sources for the one number {f.num}"))
            else:
                bound[id(f)] = (f, mk.sources[0], mk)
            continue
        m = re.search(rf"(?<![\w.$^{{/-])(?:{NUM})$", prose[:q])
        if m and len(mk.sources) == 1:
            f = Figure(m.group(0), m.group(0), None, m.start(), m.end(), m.end(), -1, required=False)
            extra.append(f)
            bound[id(f)] = (f, mk.sources[0], mk)
            continue
        errors.append((mk, "binds no figure: put it right after the number (or the number and its unit)"))
    pairs = [bound.get(id(f), (f, None, None)) for f in sorted(figs + extra, key=lambda f: f.start)]
    return pairs, errors


# --------------------------------------------------------------------------------------------------- sources
_OUT_NUM = re.compile(rf"(?<![\w.])(?P<num>-?(?:{NUM})(?:[eE][-+]?\d+)?)")


def _unit_of_header(text: str):
    """The unit a column header names ("MPJPE mm", "joint error (cm)", "us/pose", "ms per solve"), or None."""
    text = text.strip()
    if text.strip("()") in UNITS:
        return text.strip("()")
    for pattern in (r"(poses/s|solves/s|frames/s|GMAC/s)", r"\b(us|µs|ms)/(?:pose|case|step|solve)\b",
                    r"\b(ms|µs|us|mm|cm|deg|rad|min|kB|MB|GB|MiB|GiB)\b", r"\((m|s|%)\)|\b(seconds|minutes|steps)\b"):
        m = re.search(pattern, text)
        if m:
            return next(g for g in m.groups() if g)
    return None


def _flex(anchor: str) -> re.Pattern:
    """An anchor as a pattern: its text, any run of white space matching any other, never starting or ending
    inside a word or a number ("fabrik 5" is not "fabrik 5point", "dls" not "dlsx")."""
    words = anchor.split()
    body = r"\s+".join(re.escape(w) for w in words)
    head = r"(?<![\w.])" if re.match(r"[\w.]", words[0]) else ""
    tail = r"(?![\w])" if re.search(r"\w$", words[-1]) else ""
    return re.compile(head + body + tail)


def _number_after(text: str, pos: int):
    """The first number at or after ``pos`` that is not part of a word, with its unit if one follows."""
    for m in _OUT_NUM.finditer(text, pos):
        after = text[m.end():]
        u = re.match(_UNIT_AFTER, after)
        if re.match(r"[A-Za-z_]", after) and not u:
            continue                  # part of a name ("5point", "L2")
        return m, (u.group("unit") if u else None)
    return None, None


class Outputs:
    """The text outputs of a notebook's code cells (streams, ``text/plain``, ``text/markdown``), by cell index."""

    def __init__(self, nb: dict):
        self.cells = []
        for i, c in enumerate(nb.get("cells", [])):
            if c.get("cell_type") != "code":
                continue
            parts = []
            for o in c.get("outputs", []):
                parts.append("".join(o.get("text", "")))
                data = o.get("data", {})
                for kind in ("text/plain", "text/markdown"):
                    parts.append("".join(data.get(kind, "")))
            text = "\n".join(p for p in parts if p)
            if text:
                self.cells.append((i, text))

    def resolve(self, src: Source):
        """``(value, unit or None, where)`` for an ``out:`` source; raises :class:`SourceError`."""
        first = _flex(src.anchors[0])
        hits = [(i, m) for i, t in self.cells for m in first.finditer(t)]
        if not hits:
            raise SourceError(f'no output shows "{src.anchors[0]}"')
        # the anchors in order, each after the one before in the same cell's output: one place must have them all
        found = []
        for cell, m in hits:
            text = dict(self.cells)[cell]
            for a in src.anchors[1:]:
                m = _flex(a).search(text, m.end())
                if not m:
                    break
            if m:
                found.append((cell, m))
        if not found:
            raise SourceError(f'no output shows "{src.anchors[0]}" followed by '
                              + " then ".join(f'"{a}"' for a in src.anchors[1:]))
        if len(found) > 1:
            cells = sorted({i for i, _ in found})
            raise SourceError(f'{" then ".join(chr(34) + a + chr(34) for a in src.anchors)} is in the outputs '
                              f'{len(found)} times (cells {", ".join(map(str, cells))}): add text that makes it '
                              'unique, or an anchor before it')
        cell, m = found[0]
        text = dict(self.cells)[cell]
        where = f"cell {cell}"
        if src.col is not None:
            return (*_under_column(text, m.end(), src.col, where), where)
        pos = m.end()
        for k in range(src.nth):
            n, unit = _number_after(text, pos)
            if n is None:
                raise SourceError(f"{where}'s output has no number #{k + 1} after \"{src.anchors[-1]}\"")
            pos = n.end()
        return float(n.group("num").replace(",", "")), src.unit or unit, where


def _under_column(text: str, pos: int, header: str, where: str):
    """The number on the line holding ``pos`` under the column ``header`` (the nearest line above naming it):
    fixed-width tables, right- or left-aligned, and Markdown tables."""
    lines = text.split("\n")
    offs, o = [], 0
    for line in lines:
        offs.append(o)
        o += len(line) + 1
    row_i = max(k for k, s in enumerate(offs) if s <= max(pos - 1, 0))
    row = lines[row_i]
    pat = _flex(header)
    for k in range(row_i - 1, -1, -1):
        line = lines[k]
        if row.strip().startswith("|") and "|" in line:
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if header in cells:
                vals = [c.strip() for c in row.strip().strip("|").split("|")]
                v = vals[cells.index(header)] if cells.index(header) < len(vals) else ""
                n, unit = _number_after(v, 0)
                if n is None:
                    raise SourceError(f"{where}: no number under \"{header}\" in the row '{row.strip()}'")
                return float(n.group("num").replace(",", "")), unit or _unit_of_header(header)
            continue
        h = None
        for hm in pat.finditer(line):
            before, after = line[hm.start() - 1:hm.start()], line[hm.end():hm.end() + 1]
            if not before.strip() and not after.strip():
                h = hm
                break
        if h is None:
            continue
        best, overlap = None, -3           # overlapping the header, else at most 2 characters beside it
        for n in _OUT_NUM.finditer(row):
            ov = min(n.end(), h.end()) - max(n.start(), h.start())
            if ov > overlap:
                best, overlap = n, ov
        if best is None:
            raise SourceError(f"{where}: no number under \"{header}\" in the row '{row.strip()}'")
        u = re.match(_UNIT_AFTER, row[best.end():])
        return float(best.group("num").replace(",", "")), (u.group("unit") if u else _unit_of_header(header))
    raise SourceError(f"{where}: no column \"{header}\" above the row '{row.strip()}'")


_KEY_UNIT = [(re.compile(p), u) for p, u in (
    (r"(^|_)mm($|_)", "mm"), (r"(^|_)cm($|_)", "cm"), (r"(^|_)ms($|_)", "ms"), (r"(^|_)(us|µs)($|_)", "µs"),
    (r"(^|_)deg($|_)", "deg"), (r"(^|_)(s|seconds|sec)($|_)", "s"), (r"(^|_)min($|_)", "min"),
    (r"(^|_)kb($|_)", "kB"), (r"(^|_)mb($|_)", "MB"), (r"(^|_)gb($|_)", "GB"),
    (r"poses_per_s|solves_per_s", "poses/s"), (r"frames_per_s", "frames/s"), (r"gmacs", "GMAC/s"),
    (r"(^|_)steps($|_)", "steps"), (r"(fraction|share)($|_)", "share"))]


def _key_unit(key: str):
    return next((u for p, u in _KEY_UNIT if p.search(key.lower())), None)


_SEGMENT = re.compile(r"(?P<key>[^.\[\]]+)?(?P<sel>(?:\[[^\]]*\])*)")


def resolve_data(results_dir, src: Source):
    """``(value, unit or None, where)`` for a ``data:`` source: ``FILE`` under ``results_dir`` and a key path —
    keys joined by ``.``, ``[i]`` a list's element, ``[k=v,k2=v2]`` the one element whose keys have those values."""
    path = Path(results_dir) / src.file
    if not path.is_file() or path.suffix != ".json":
        raise SourceError(f"no results file {src.file} in data_samples/results")
    node = json.loads(path.read_text(encoding="utf-8"))
    key = ""
    for part in re.split(r"\.(?![^\[]*\])", src.path):
        m = _SEGMENT.fullmatch(part)
        if not m:
            raise SourceError(f"cannot read '{part}' of {src.path}")
        if m.group("key"):
            key = m.group("key")
            if not isinstance(node, dict) or key not in node:
                raise SourceError(f"{src.file}: no key '{key}' at {src.path}")
            node = node[key]
        for sel in re.findall(r"\[([^\]]*)\]", m.group("sel") or ""):
            if not isinstance(node, list):
                raise SourceError(f"{src.file}: '{key}' is no list ({src.path})")
            if re.fullmatch(r"-?\d+", sel):
                if not -len(node) <= int(sel) < len(node):
                    raise SourceError(f"{src.file}: '{key}' has {len(node)} elements, not [{sel}]")
                node = node[int(sel)]
                continue
            want = dict(kv.split("=", 1) for kv in sel.split(",") if "=" in kv)
            found = [e for e in node if isinstance(e, dict) and all(str(e.get(k)) == v for k, v in want.items())]
            if len(found) != 1:
                raise SourceError(f"{src.file}: {len(found)} elements of '{key}' have [{sel}] ({src.path}); "
                                  "one must")
            node = found[0]
    where = f"{src.file} {src.path}"
    if isinstance(node, bool) or not isinstance(node, (int, float, str)):
        raise SourceError(f"{where} is no number")
    if isinstance(node, str):
        n, unit = _number_after(node, 0)
        if n is None:
            raise SourceError(f"{where} is no number ('{node}')")
        return float(n.group("num").replace(",", "")), src.unit or unit, where
    return float(node), src.unit or _key_unit(key), where


def agrees(fig: Figure, value: float, unit) -> tuple[bool, str]:
    """Whether ``value`` (in ``unit``), converted to the figure's unit and rounded to its decimals, is the figure.
    A source without a unit is read in the figure's unit; one of another family (a time for a length) never
    agrees. Returns ``(agrees, the value as the figure's unit shows it)``."""
    fam_p, f_p = family(fig.unit)
    fam_s, f_s = family(unit)
    v = value
    if fam_p and fam_s:
        if fam_p != fam_s:
            return False, f"{value:g} {unit} (a {fam_s}, not a {fam_p})"
        v = value * f_s / f_p
    shown = f"{v:.{_decimals(fig.num) + 2}g}" if fig.scale != 1 else f"{v:.{_decimals(fig.num) + 1}f}"
    ok = abs(abs(v) - fig.value) <= fig.half_step * (1 + 1e-9) + 1e-12 * max(1.0, abs(v))
    return ok, shown + (f" {fig.unit}" if fig.unit else "")


def data_marker(file: str, path: str, unit: str | None = None) -> str:
    """The marker binding a figure to a results file's key: ``<!-- data: FILE PATH -->``."""
    return f"<!-- data: {file} {path}{' unit ' + unit if unit else ''} -->"


# --------------------------------------------------------------------------------------------------- a page
def _line_of(text: str, pos: int) -> int:
    return text.count("\n", 0, pos) + 1


def _check(text: str, prose: str, markers: list[Marker], *, results_dir, outputs, allowed):
    """The problems of ``text`` once its markers are read: binding, resolving and comparing every figure."""
    pairs, errors = bind(prose, figures(prose), markers)
    problems = [(_line_of(text, mk.start), f"marker {mk.raw!r}: {msg}") for mk, msg in errors]
    problems += [(_line_of(text, mk.start), f"marker {mk.raw!r} starts a line: put it right after its figure, on "
                  "the figure's line (a line that starts with a comment is an HTML block)")
                 for mk in markers if mk.line_start]
    for fig, src, mk in pairs:
        line = _line_of(text, fig.start)
        if src is None:
            if fig.required and fig.written not in allowed:
                problems.append((line, f"'{fig.written}'" + (f" ({fig.num})" if fig.num != fig.written else "")
                                 + ": a measured figure without a source marker"))
            continue
        if src.kind in EXEMPT_KINDS:
            continue
        try:
            if src.kind == "out":
                if outputs is None:
                    raise SourceError("out: sources are a notebook's outputs; a page names a results file (data:)")
                value, unit, at = outputs.resolve(src)
            else:
                value, unit, at = resolve_data(results_dir, src)
            value *= src.scale
        except SourceError as e:
            problems.append((line, f"'{fig.written}' ({fig.num}): {e}"))
            continue
        ok, shown = agrees(fig, value, unit)
        if not ok:
            problems.append((line, f"'{fig.written}' ({fig.num}) is not its source: {at} shows "
                                   f"{value:g}{' ' + unit if unit else ''} = {shown}"))
    problems += [(_line_of(text, text.find(w)), f"in words: '{w}' (write the digits an output shows)")
                 for w in in_words(prose)]
    return problems


def check_text(text: str, *, results_dir, outputs: Outputs | None = None, allowed=(), where=""):
    """The problems of one Markdown text whose figures carry inline markers (a page of ``docs/``, a README):
    ``[(line, message)]`` — a measured figure without a source, a source that does not exist, a value that is not
    the figure, a marker that binds nothing or starts a line (CommonMark reads a line that starts with a comment as
    an HTML block, and the rest of the line is not rendered as Markdown), a number in words. ``allowed``: figures
    as written this text may state without a source (the reviewed allow-list); ``outputs``: the notebook's outputs
    (None: a page, only ``data:`` sources)."""
    prose = blank_non_prose(text)
    return _check(text, prose, parse_markers(text), results_dir=results_dir, outputs=outputs, allowed=allowed)


# --------------------------------------------------------------------------------------------------- a lesson's cell
BINDINGS_KEY, BINDINGS_FIELD = "posekit", "sources"
"""Where a markdown cell keeps its figures' bindings: ``cell.metadata[BINDINGS_KEY][BINDINGS_FIELD]``."""


def cell_bindings(cell: dict) -> list:
    """The bindings a markdown cell's metadata holds (``cell.metadata["posekit"]["sources"]``), or ``[]``.

    A lesson's markdown holds words, maths and links only: what binds its figures to their sources is kept in the
    cell's metadata, one entry per bound figure, in the order of the text::

        {"figure": "28–29 mm", "occurrence": 1,
         "sources": ["out: \"Lambda pos mm\" \"0.7\" col \"pos mm\"", "out: ..."]}

    ``figure`` is the figure as the text writes it (white space aside), ``occurrence`` which of the cell's places
    writing it (1: the first), ``sources`` one source per number of the figure, each in the syntax of an inline
    marker's body (``out: ...``, ``data: FILE PATH``, ``goal: REASON`` ...; see :func:`parse_markers`)."""
    return list(cell.get("metadata", {}).get(BINDINGS_KEY, {}).get(BINDINGS_FIELD, []))


def set_cell_bindings(cell: dict, entries: list) -> None:
    """Write ``entries`` (see :func:`cell_bindings`) into the cell's metadata; none removes the key."""
    meta = cell.setdefault("metadata", {})
    if entries:
        meta.setdefault(BINDINGS_KEY, {})[BINDINGS_FIELD] = entries
        return
    own = meta.get(BINDINGS_KEY)
    if isinstance(own, dict):
        own.pop(BINDINGS_FIELD, None)
        if not own:
            meta.pop(BINDINGS_KEY)


def figure_pattern(figure: str) -> re.Pattern:
    """A figure as written, as a pattern over prose: any run of white space matches any other, and a match neither
    starts inside a number or a word nor runs on into one ("29" is not the end of "1.29" nor the start of
    "290")."""
    body = r"\s+".join(re.escape(w) for w in figure.split())
    return re.compile(r"(?<![\w.,])" + body + r"(?!\w|[.,]\d)")


def _ordinal(k: int) -> str:
    return {1: "1st", 2: "2nd", 3: "3rd"}.get(k, f"{k}th")


def _binding_sources(entry) -> tuple[list, str | None]:
    """The parsed sources of one binding, and what is wrong with it (None: nothing)."""
    if not isinstance(entry, dict) or not isinstance(entry.get("figure"), str) or not entry["figure"].strip():
        return [], "a binding needs its figure as written ({\"figure\": \"28 mm\", \"occurrence\": 1, \"sources\": [...]})"
    occ = entry.get("occurrence", 1)
    if not isinstance(occ, int) or isinstance(occ, bool) or occ < 1:
        return [], f"occurrence must be a whole number from 1, not {occ!r}"
    srcs = entry.get("sources")
    if not isinstance(srcs, list) or not srcs or not all(isinstance(s, str) for s in srcs):
        return [], "sources must be a list of one or more texts ('out: ...', 'data: FILE PATH', 'goal: REASON')"
    out = []
    try:
        for s in srcs:
            m = re.match(r"\s*(out|data|goal|paper|definition|setting)\s*:(.*)$", s, re.S)
            if not m:
                raise SourceError(f"'{s.strip()}' does not start with out:, data:, goal:, paper:, definition: or "
                                  "setting:")
            out.append(_parse_source(m.group(1), m.group(2)))
    except SourceError as e:
        return [], str(e)
    return out, None


def binding_markers(prose: str, entries: list) -> tuple[list[Marker], list[tuple[int, str]]]:
    """The bindings of a cell (see :func:`cell_bindings`) as markers placed right after their figures in ``prose``
    (already :func:`blank_non_prose`'d), so that :func:`bind` reads them as it reads inline markers.

    Returns ``(markers, stale)``: ``stale`` lists ``(position, message)`` for bindings whose figure the text no
    longer writes (or writes fewer times than their occurrence) and for two bindings of one place."""
    markers, stale, seen = [], [], {}
    for entry in entries:
        fig = entry.get("figure") if isinstance(entry, dict) else None
        occ = entry.get("occurrence", 1) if isinstance(entry, dict) else 1
        raw = f"binding of {fig!r}" + (f" ({_ordinal(occ)} place)" if occ != 1 else "")
        sources, err = _binding_sources(entry)
        if err:
            markers.append(Marker(0, 0, raw, [], False, err))
            continue
        hits = list(figure_pattern(fig).finditer(prose))
        if len(hits) < occ:
            stale.append((0, f"{raw} is stale: the cell writes {fig!r} {len(hits)} time"
                             f"{'' if len(hits) == 1 else 's'}, the binding names its {_ordinal(occ)} place "
                             "(edit the figure or the binding in the cell's metadata, or remove the binding)"))
            continue
        q = hits[occ - 1].end()
        if q in seen:
            stale.append((q, f"{raw} binds the same place as {seen[q]}: keep one"))
            continue
        seen[q] = raw
        markers.append(Marker(q, q, raw, sources, False))
    return sorted(markers, key=lambda mk: mk.start), stale


def check_cell(text: str, entries: list, *, results_dir, outputs: Outputs | None = None, allowed=()):
    """The problems of one markdown cell of a lesson whose figures are bound in its metadata (``entries``, see
    :func:`cell_bindings`): ``[(line, message)]`` — those of :func:`check_text`, a stale binding (its figure is no
    longer in the text), and any inline source marker (a lesson's markdown holds none: they live in the metadata,
    ``tools/mark_prose_sources.py --migrate`` moves them there)."""
    prose = blank_non_prose(text)
    problems = [(_line_of(text, mk.start), f"inline source marker {mk.raw!r}: a lesson keeps its bindings in the "
                 "cell's metadata (python tools/mark_prose_sources.py --migrate NOTEBOOK moves it there)")
                for mk in parse_markers(text)]
    markers, stale = binding_markers(prose, entries)
    problems += [(_line_of(text, at), msg) for at, msg in stale]
    problems += _check(text, prose, markers, results_dir=results_dir, outputs=outputs, allowed=allowed)
    return problems


def inline_bindings(text: str, entries: list) -> tuple[str, list]:
    """``text`` with each binding of ``entries`` written back as an inline marker after its figure (the form the
    marking tool and :func:`move_markers` read); returns ``(text, the bindings it could not place)``."""
    prose = blank_non_prose(text)
    placed, left = [], []
    for entry in entries:
        _, err = _binding_sources(entry)
        hits = [] if err else list(figure_pattern(entry["figure"]).finditer(prose))
        occ = entry.get("occurrence", 1) if not err else 1
        if err or len(hits) < occ:
            left.append(entry)
            continue
        placed.append((hits[occ - 1].end(), "<!-- " + "; ".join(s.strip() for s in entry["sources"]) + " -->"))
    for at, marker in sorted(placed, key=lambda t: t[0], reverse=True):
        text = text[:at] + marker + text[at:]
    return text, left


def move_markers(text: str, entries: list = ()) -> tuple[str, list]:
    """Move the inline source markers of a markdown cell into bindings (see :func:`cell_bindings`).

    Parameters
    ----------
    text : str
        The cell's source, with inline markers (``28–29 mm<!-- out: ...; out: ... -->``).
    entries : list
        The bindings the cell's metadata holds already; they are merged with the markers.

    Returns
    -------
    text, entries : str, list
        The source without its markers, and every binding in the order of the text. Idempotent: a text without
        markers comes back unchanged, with ``entries`` unchanged.

    Raises
    ------
    SourceError
        When a marker's figure could not be told apart by its text and place (nothing is moved then).
    """
    entries = list(entries)
    if not parse_markers(text):
        return text, entries
    text, stale = inline_bindings(text, entries)
    markers = parse_markers(text)
    plain, pos, shift = [], [], 0
    last = 0
    for mk in markers:
        plain.append(text[last:mk.start])
        shift += mk.start - last
        pos.append(shift)             # the marker's place in the text without markers
        last = mk.end
    plain.append(text[last:])
    plain = "".join(plain)
    prose = blank_non_prose(plain)
    figs = figures(prose)
    placed = []
    for mk, at in zip(markers, pos):
        q = at
        while q > 0 and prose[q - 1] in " \u00a0":
            q -= 1
        placed.append(Marker(q, q, mk.raw, mk.sources, False, mk.error))
    pairs, _ = bind(prose, figs, placed)
    first = {}
    for fig, _, mk in pairs:
        if mk is not None:
            first[id(mk)] = min(first.get(id(mk), fig.start), fig.start)
    out = []
    for mk, orig in zip(placed, markers):
        start = first.get(id(mk))
        if start is None:             # binds no figure: keep its last word, for the guard to report
            m = re.search(r"\S+$", prose[:mk.start])
            start = m.start() if m else mk.start
        figure = " ".join(prose[start:mk.start].split())
        try:
            sources = [f"{k}: {b.strip()}" for k, b in _split_sources(orig.raw[4:-3])]
        except SourceError:
            sources = [orig.raw[4:-3].strip()]
        ends = [h.end() for h in figure_pattern(figure).finditer(prose)] if figure else []
        if mk.start not in ends:
            raise SourceError(f"the marker {orig.raw!r} follows {figure!r}, which its text cannot place")
        out.append((mk.start, {"figure": figure, "occurrence": ends.index(mk.start) + 1, "sources": sources}))
    out.sort(key=lambda t: t[0])
    return plain, [e for _, e in out] + stale
