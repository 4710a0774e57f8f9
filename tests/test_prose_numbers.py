"""Prose never states a figure that no output shows (it drifts): every measured figure in a lesson's markdown is
an output of the same notebook (or of the shipped results its code names) *of the same quantity*; every figure
of ``README.md``, ``data_samples/README.md`` and ``docs/*.md`` is in the shipped results
(``data_samples/results/*``). Reviewed exceptions (goals, definitions, the papers' figures) sit on an allow-list
with their reason.

How a prose figure is matched
-----------------------------
* **Same unit family, after conversion.** "12 ms" is a time and matches an output time of 0.012 s, 12.3 ms or
  11,800 µs — never a joint index 12 or 12 mm. Families: length (µm, mm, cm, m), time (µs, ms, s, min, h),
  ratio (×, x, times), angle (°, deg, rad), rates (poses/s and solves/s; frames/s), steps, core-hours, %, sizes
  (kB, MB). A number in an output gets its unit from the text right after it ("29.1 mm"), else from the header
  of its table column (fixed-width text tables and Markdown tables: "MPJPE mm" over "67.8"), else from its JSON
  key ("mpjpe_mm_median", "seconds"); otherwise it is a bare number.
* **Rounding.** The output, converted to the prose's unit, rounds to the prose's decimals ("29 mm" matches 28.9
  mm and 0.0289 m).
* **Every number of a list or range**: "71 / 56 / 80 mm", "12.9–13.9 µs", "1.21–6.48 ms", "28 and 29 mm".
* **Bare decimals** ("0.473", "1.52", "0.92"), which carry no unit, must equal some output number; bare
  integers (counts, indices, equation numbers) are not checked.
* **Digits for measured durations and ratios**: "about a minute", "ten to thirty times", "about ten
  microseconds" are refused (a number in words escapes every check); write the digits an output shows.
"""

import json
import math
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
RESULTS_DIR = ROOT / "data_samples" / "results"
RESULTS = sorted(RESULTS_DIR.glob("*.json")) + sorted(RESULTS_DIR.glob("*.md"))
PAGES = [p for p in [ROOT / "README.md", ROOT / "data_samples" / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
         if p.exists()]

# unit as written -> (family, factor to the family's base unit)
_UNITS = {
    "µm": ("length", 1e-6), "um": ("length", 1e-6), "mm": ("length", 1e-3), "cm": ("length", 1e-2),
    "m": ("length", 1.0), "metres": ("length", 1.0), "meters": ("length", 1.0),
    "µs": ("time", 1e-6), "us": ("time", 1e-6), "microseconds": ("time", 1e-6), "microsecond": ("time", 1e-6),
    "ms": ("time", 1e-3), "milliseconds": ("time", 1e-3), "millisecond": ("time", 1e-3),
    "s": ("time", 1.0), "sec": ("time", 1.0), "seconds": ("time", 1.0), "second": ("time", 1.0),
    "min": ("time", 60.0), "minutes": ("time", 60.0), "minute": ("time", 60.0),
    "h": ("time", 3600.0), "hours": ("time", 3600.0), "hour": ("time", 3600.0),
    "core-hours": ("core-time", 3600.0), "core-hour": ("core-time", 3600.0), "core-min": ("core-time", 60.0),
    "×": ("ratio", 1.0), "x": ("ratio", 1.0), "times": ("ratio", 1.0),
    "°": ("angle", math.pi / 180), "deg": ("angle", math.pi / 180), "degrees": ("angle", math.pi / 180),
    "degree": ("angle", math.pi / 180), "rad": ("angle", 1.0), "radians": ("angle", 1.0),
    "poses/s": ("poses/s", 1.0), "solves/s": ("poses/s", 1.0), "poses per second": ("poses/s", 1.0),
    "solves per second": ("poses/s", 1.0), "poses a second": ("poses/s", 1.0), "solves a second": ("poses/s", 1.0),
    "frames/s": ("frames/s", 1.0), "frame/s": ("frames/s", 1.0), "fps": ("frames/s", 1.0),
    "frames per second": ("frames/s", 1.0),
    "steps": ("steps", 1.0), "step": ("steps", 1.0),
    "%": ("percent", 1.0), "per cent": ("percent", 1.0),
    "kB": ("size", 1e3), "MB": ("size", 1e6),
}
_UNIT_ALT = "|".join(sorted((re.escape(u) for u in _UNITS), key=len, reverse=True))
NUM = r"\d{1,3}(?:,\d{3})+(?:\.\d+)?|\d+(?:\.\d+)?"
# the unit follows the number (a space or none; "9x", "0.5°", "12 %"), and is not the start of a longer word
_UNIT_AFTER = rf"\s?(?P<unit>{_UNIT_ALT})(?![\w/²^])"
_SEP = r"\s*(?:–|-|/|,|to|and|or|against)\s*"
# a figure: one or more numbers joined by list or range separators, then a unit
PROSE = re.compile(rf"(?<![\w.$^{{/-])(?P<nums>(?:{NUM})(?:{_SEP}(?:{NUM}))*){_UNIT_AFTER}")
# what a bare decimal after these is: a section or algorithm number, an arXiv id, a version, a DOI
_NOT_A_FIGURE = re.compile(r"(?:Secs?\.|Sections?|Alg\.|Algorithm|Eqs?\.|Table|Fig\.|arXiv:|doi:\S*|version|v|"
                           r"ikpy|pyfabrik|numpy|torch|Python|nbval|ipywidgets|pythreejs|JupyterLab|and|,)\s*[(]?$")
BARE_DECIMAL = re.compile(r"(?<![\w.$^{/-])(?P<num>\d+\.\d+)(?![\w.%°×/-])")
OUTPUT_NUM = re.compile(rf"(?<![\w.])(?P<num>-?(?:{NUM})(?:e-?\d+)?)(?:{_UNIT_AFTER})?")
_NUM_IN = re.compile(NUM)

# a measured duration or ratio written in words (it escapes every check): write its digits
_WORD_NUMBER = (r"(?:one|two|three|four|five|six|seven|eight|nine|ten|eleven|twelve|fifteen|twenty|thirty|forty|"
                r"fifty|sixty|a hundred|hundreds|a thousand|thousands|a tenth of a|a few|tens)")
IN_WORDS = re.compile(
    rf"(?i)\b(?:(?:about|roughly|nearly|some|under|over|within|in|takes?|took|only)\s+(?:an?|{_WORD_NUMBER})"
    rf"(?:\s+(?:to|or)\s+{_WORD_NUMBER})?|{_WORD_NUMBER}(?:\s+(?:to|or)\s+{_WORD_NUMBER})?)\s+"
    r"(?P<unit>microseconds?|milliseconds?|seconds?|minutes?|hours?|times\s+(?:faster|slower|as|more|less|longer|"
    r"shorter|larger|smaller|higher|lower|fewer|the))\b")

# Reviewed: figures a page may state that no output shows, each with its reason. (page, text as written)
ALLOWED = {
    # goals the lessons judge the solvers by (introduced in each Aim)
    ("03", "0.1 ms"): "goal: one solve", ("03", "5 µs"): "goal: per pose, batched", ("03", "3 cm"): "goal: effectors",
    ("04", "10 ms"): "goal: one solve", ("04", "2,000 solves per second"): "goal: batched, one thread",
    ("04", "2 cm"): "goal: the generator's pose, two targets",
    ("05", "20,000 poses per second"): "a retired goal, shown above every network's ideal (section 6)", ("06", "3 ms"): "goal: per solve (Aim)",
    # definitions, settings and budgets, not measurements
    ("04", "50 %"): "a discriminator's accuracy when it cannot tell (a definition)",
    ("04", "100 %"): "a discriminator's accuracy when it has won (a definition)",
    ("05", "45 seconds"): "exercise 4's time budget (its instructor notes: seconds=45)",
    ("04", "20 seconds"): "the live demo's time budget, seconds=20 in its code",
    ("05", "20 seconds"): "the live demo's time budget, seconds=20 in its code",
    ("05", "20 m"): "a target distance for the reader to try",
    ("05", "50 cm"): "a target distance for the reader to try",
    ("05", "90°"): "an angle for the reader to try",
    ("05", "1 mm"): "the default tolerance of an Effector (a setting)",
    ("01", "1 mm"): "the convergence tolerance (a setting)",
    ("01", "1 s"): "the same-clip start's distance (a setting of posekit.data.cases)",
    ("04", "1 mm"): "the optimisers' tolerance (a setting)",
    ("06", "1 mm"): "the sliders' step (a setting)", ("06", "50 cm"): "the sliders' range (a setting)",
    ("06", "1 m"): "where a look-at target starts (a setting)",
    ("00", "90°"): "an angle in an example", ("00", "0.5°"): "an exercise's tolerance (a setting)",
    ("02", "20 frames"): "the animator's key spacing (a setting)",
    # the papers' own figures
    ("01", "6.56 / 6.74 ms"): "Victor et al. 2021, Table 1 (FABRIK, 2 / 5 effectors)",
    ("03", "6.56 / 6.74 ms"): "Victor et al. 2021, Table 1 (FABRIK, 2 / 5 effectors)",
    ("05", "10 ms"): "Oreshkin et al. 2022: about 10 ms per pose in Unity",
    ("05", "33 hours"): "Oreshkin et al. 2022: their training time on a GPU",
    # fixed facts of the method or the data, not measurements
    ("03", "1 cm"): "the std floor of the z-score (posekit.data.pose_vectors.STD_FLOOR)",
    ("03", "1 s"): "training pairs at most 1 s apart (PAIR_MAX_S)",
    ("03", "5 s"): "an exercise's suggested setting",
    ("03", "40 cm"): "a suggested target for the reader to try",
    ("04", "40 cm"): "a suggested target for the reader to try",
    ("03", "0.94 m"): "the mini set's root helper point below the pelvis (a fact of the data)",
    ("03", "442 kB"): "Victor et al. 2021: their model's size for two effectors",
    ("04", "0.1 %"): "the optimisers' stopping rule (a setting)", ("04", "0.05"): "Adam's step size (a setting)", ("04", "8 steps"): "L-BFGS's memory (a setting)",
    ("00", "30 fps"): "the Bandai data's frame rate (a fact of the data)",
    ("01", "60°"): "the near-extended step's threshold (a setting)",
    # versions, not measurements
    ("README.md", "3.13"): "the newest Python posekit supports (pyproject.toml)",
    ("docs/setup.md", "3.13"): "the newest Python posekit supports (pyproject.toml)",
    ("docs/setup.md", "2.13"): "the newest torch pyproject.toml admits",
    # the hub's settings and TLJH's sizing rule
    ("docs/hub.md", "20 minutes"): "the hub's kernel cull setting (deploy/jupyterhub/jupyterhub_config.py)",
    ("docs/hub.md", "128 MB"): "TLJH's sizing rule: the hub's own share",
    ("docs/hub.md", "64 MB"): "the values file rounds the measured peak up to a multiple of it (a rule)",
}


def _family(unit):
    return _UNITS[unit] if unit in _UNITS else _UNITS.get(unit.lower(), (None, None))


def _value(s):
    return float(s.replace(",", ""))


def _decimals(s):
    return len(s.split(".")[1]) if "." in s else 0


# --- what the outputs show ------------------------------------------------------------------------------------
_HEADER_UNIT = re.compile(rf"(?:^|[\s(])(?P<unit>{_UNIT_ALT})(?:\)|$|\s|,)|(?P<per>poses/s|solves/s|frames/s|us/pose|"
                          r"ms/pose|ms/case|ms/step|µs/pose)")


def _unit_of_header(text):
    """The unit a column header names ("MPJPE mm", "joint error (cm)", "us/pose", "ms per solve"), or None."""
    text = text.strip()
    if text.strip("()") in _UNITS:
        return text.strip("()")
    m = re.search(r"(poses/s|solves/s|frames/s)", text)
    if m:
        return m.group(1)
    m = re.search(r"\b(us|µs|ms)/(?:pose|case|step|solve)\b", text)
    if m:
        return m.group(1)
    m = re.search(r"\b(ms|µs|us|mm|cm|deg|rad|min|kB|MB)\b", text)
    if m:
        return m.group(1)
    m = re.search(r"\((m|s|%)\)|\b(seconds|minutes|steps)\b", text)
    if m:
        return m.group(1) or m.group(2)
    return None


def _text_tables(text):
    """(unit, number) for numbers under a fixed-width header: a line of words with no decimal figure, whose word
    ending in the same column as a number of a following line names a unit ("MPJPE mm", "joint error (cm)",
    "ms/pose", "solves/s"). Headers are right-aligned over their numbers, as every table of the course prints them."""
    found = []
    header = None
    for line in text.splitlines():
        nums = list(re.finditer(rf"(?<![\w.])-?(?:{NUM})(?![\w.])", line))
        tokens = {m.end(): m.group(0) for m in re.finditer(r"\S+", line)}
        names_unit = any(_unit_of_header(t) for t in tokens.values())
        if re.search(r"[A-Za-z]{2,}", line) and not any("." in m.group(0) for m in nums) and (not nums or names_unit):
            header = tokens
            continue
        if header is None:
            continue
        for m in nums:
            for end in (m.end(), m.end() + 1, m.end() - 1):
                unit = _unit_of_header(header[end]) if end in header else None
                if unit:
                    found.append((unit, m.group(0)))
                    break
    return found


def _markdown_tables(text):
    """(unit, number) for numbers in Markdown table cells whose column header names a unit."""
    found = []
    header = None
    for line in text.splitlines():
        if not line.startswith("|"):
            header = None
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if all(re.fullmatch(r":?-+:?", c) for c in cells if c):
            continue
        if header is None:
            header = cells
            continue
        for h, c in zip(header, cells):
            unit = _unit_of_header(h)
            m = re.fullmatch(rf"(?:{NUM})", c.replace("`", ""))
            if unit and m:
                found.append((unit, m.group(0)))
    return found


_KEY_UNIT = [(re.compile(p), u) for p, u in (
    (r"(^|_)mm($|_)", "mm"), (r"(^|_)cm($|_)", "cm"), (r"(^|_)ms($|_)", "ms"), (r"(^|_)(us|µs)($|_)", "µs"),
    (r"(^|_)deg($|_)", "deg"), (r"(^|_)(s|seconds|sec)($|_)", "s"), (r"(^|_)min($|_)", "min"),
    (r"(^|_)kb($|_)", "kB"), (r"poses_per_s|solves_per_s", "poses/s"), (r"frames_per_s", "frames/s"),
    (r"(^|_)steps($|_)", "steps"))]


def _json_values(obj, key=""):
    """(unit or None, value) for every number of a JSON document, the unit read off its key."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _json_values(v, str(k))
    elif isinstance(obj, list):
        for v in obj:
            yield from _json_values(v, key)
    elif isinstance(obj, (int, float)) and not isinstance(obj, bool):
        unit = next((u for p, u in _KEY_UNIT if p.search(key.lower())), None)
        yield unit, float(obj)
    elif isinstance(obj, str):
        yield from ((u, _value(n)) for u, n in _unit_numbers(obj))


def _unit_numbers(text):
    """(unit or None, number as text) for every number of a text: the unit right after it, else its column's."""
    out = []
    for m in OUTPUT_NUM.finditer(text):
        out.append((m.group("unit"), m.group("num")))
    out += _text_tables(text) + _markdown_tables(text)
    return out


class Known:
    """The figures some outputs show, by unit family (in the family's base unit), and every number bare."""

    def __init__(self):
        self.by_family = {}
        self.bare = set()

    def add(self, unit, value):
        value = float(value)
        for d in range(0, 6):
            self.bare.add((d, round(value, d)))
            self.bare.add((d, round(abs(value), d)))
        if unit:
            fam, f = _family(unit)
            if fam:
                self.by_family.setdefault(fam, set()).add(value * f)
                if fam == "percent":          # 92% is also a share of 0.92
                    self.bare.update((d, round(value / 100, d)) for d in range(0, 6))

    def add_text(self, text):
        for unit, num in _unit_numbers(text):
            try:
                self.add(unit, _value(num))
            except ValueError:
                continue
        return self

    def add_json(self, doc):
        for unit, v in _json_values(doc):
            self.add(unit, v)
        return self

    def matches(self, num, unit):
        """Does an output of the same family, in ``unit``, round to ``num`` at its decimals?"""
        fam, f = _family(unit)
        p, d = _value(num), _decimals(num)
        half = 0.5 * 10 ** -d * (1 + 1e-9)
        return any(abs(v / f - p) <= half + 1e-12 for v in self.by_family.get(fam, ()))

    def matches_bare(self, num):
        d = _decimals(num)
        return (d, round(_value(num), d)) in self.bare


# --- what the prose says --------------------------------------------------------------------------------------
def _prose_without_code(text):
    """Markdown minus code blocks and spans, maths and link targets (numbers there are code, symbols or paths),
    and blocks a command renders from its results file (``<!-- NAME: begin (command) -->`` ... ``<!-- NAME: end
    -->``: the test of that command compares them with the file)."""
    text = re.sub(r"<!-- ([\w-]+): begin.*?<!-- \1: end -->", " ", text, flags=re.S)
    text = re.sub(r"```.*?```", " ", text, flags=re.S)
    text = re.sub(r"`[^`]*`", " ", text)
    text = re.sub(r"\]\([^)]*\)", "]", text)
    return re.sub(r"\$\$.*?\$\$|\$[^$]*\$", " ", text, flags=re.S)


def _figure_matches(text):
    """PROSE matches, less dimensions ("2 × 200", "4 x 256": a product, not a ratio)."""
    return [m for m in PROSE.finditer(text)
            if not (m.group("unit") in ("×", "x") and re.match(r"\s*\d", text[m.end():]))]


def figures(text):
    """(as written, [numbers], unit) for every figure with a unit in ``text``."""
    return [(m.group(0), _NUM_IN.findall(m.group("nums")), m.group("unit")) for m in _figure_matches(text)]


def unbacked(text, known, page):
    """The figures of ``text`` that ``known`` does not back, minus the reviewed exceptions of ``page``."""
    bad = []
    for written, nums, unit in figures(text):
        if (page, written) in ALLOWED:
            continue
        if not all(known.matches(n, unit) for n in nums):
            bad.append(written)
    with_unit = [m.span() for m in PROSE.finditer(text)]
    for m in BARE_DECIMAL.finditer(text):
        if any(a <= m.start() < b for a, b in with_unit):
            continue                      # a number of a figure with a unit: checked above
        if _NOT_A_FIGURE.search(text[max(0, m.start() - 16):m.start()]):
            continue                      # a section, an equation, an arXiv id, a version
        if (page, m.group("num")) not in ALLOWED and not known.matches_bare(m.group("num")):
            bad.append(m.group("num"))
    bad += [f"in words: {m.group(0)}" for m in IN_WORDS.finditer(text)]
    return bad


# --- the notebooks ----------------------------------------------------------------------------------------------
def _output_text(nb):
    parts = []
    for c in nb["cells"]:
        for o in c.get("outputs", []):
            parts.append("".join(o.get("text", "")))
            data = o.get("data", {})
            for kind in ("text/plain", "text/markdown", "text/html"):
                parts.append("".join(data.get(kind, "")))
    return "\n".join(parts)


# results a lesson loads through a helper rather than by name: file -> the helper its code calls
LOADED_BY_HELPER = {"protores_ablation.json": "posekit.models.protores.studies import studies_path",
                    "protores_scaling.json": "posekit.models.protores.studies import scaling_path"}


def _results_loaded(nb):
    """The shipped results the notebook's code names (``bench_all.md``, ``f"ae_scale_{proto}.json"``)."""
    code = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")
    named = [p for p in RESULTS if p.stem in code or p.stem.rsplit("_", 1)[0] + "_{" in code]
    named += [p for p in RESULTS if p.name in LOADED_BY_HELPER and LOADED_BY_HELPER[p.name] in code]
    return named


def _known_for(paths, texts=()):
    known = Known()
    for t in texts:
        known.add_text(t)
    for p in paths:
        if p.suffix == ".json":
            known.add_json(json.loads(p.read_text(encoding="utf-8")))
        else:
            known.add_text(p.read_text(encoding="utf-8"))
    return known


def _markdown(nb):
    return "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "markdown")


def unbacked_figures(path):
    nb = json.loads(path.read_text(encoding="utf-8"))
    known = _known_for(_results_loaded(nb), [_output_text(nb)])
    return unbacked(_prose_without_code(_markdown(nb)), known, path.name[:2])


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_every_figure_in_the_prose_is_an_output(path):
    bad = unbacked_figures(path)
    assert bad == [], (f"{path.name}: figures in the markdown that no output of the notebook (nor the "
                       f"data_samples/results it loads) shows as the same quantity — quote an output, drop the "
                       f"figure, or allow-list it with a reason: {bad}")


# the pages `posekit docs build` writes are rendered from the results files and the argument parser themselves
# (tests/test_docs.py compares them with what the code writes); every other page is prose and checked here
_GENERATED = {"docs/cli.md", "docs/benchmarks.md", "docs/tested-versions.md"}
PAGE_PARAMS = [p for p in PAGES if str(p.relative_to(ROOT)) not in _GENERATED]


@pytest.mark.parametrize("page", PAGE_PARAMS, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_figure_of_a_page_is_in_the_results(page):
    """README.md, data_samples/README.md and docs/*.md: a measured figure lives in a results file a command wrote."""
    known = _known_for(RESULTS)
    bad = unbacked(_prose_without_code(page.read_text(encoding="utf-8")), known, str(page.relative_to(ROOT)))
    assert bad == [], (f"{page.relative_to(ROOT)}: figures no file of data_samples/results shows as the same "
                       f"quantity: {bad}")


def test_every_allowed_figure_is_still_in_its_lesson():
    """A stale allow-list entry would hide the next figure written the same way: each must still be used."""
    texts = {p.name[:2]: _prose_without_code(_markdown(json.loads(p.read_text(encoding="utf-8")))) for p in NOTEBOOKS}
    texts.update({str(p.relative_to(ROOT)): _prose_without_code(p.read_text(encoding="utf-8")) for p in PAGES})
    stale = [k for k in ALLOWED if k[1] not in texts.get(k[0], "")]
    assert stale == [], f"allow-list entries no page uses any more: {stale}"


# --- the matcher, and each escape route of the old guard (lessons audit, section 2) -----------------------------
def _known(text):
    return Known().add_text(text)


def test_the_matcher():
    known = _known("median 28.9 mm; took 1,542 poses/s; share 0.241; 12.9 µs")
    assert known.matches("29", "mm") and known.matches("2.89", "cm") and known.matches("1,542", "poses/s")
    assert known.matches_bare("0.24") and known.matches("0.0129", "ms")
    assert not known.matches("29", "ms") and not known.matches("1,400", "poses/s") and not known.matches_bare("0.15")
    found = [f[0] for f in figures("took 12.9–13.9 µs, 1,542 poses/s, 5 % and 3 cm; Eq. 2; 10⁻⁴; "
                                   "896–938 solves per second")]
    assert found == ["12.9–13.9 µs", "1,542 poses/s", "5 %", "3 cm", "896–938 solves per second"]


def test_a_seconds_figure_is_not_backed_by_a_joint_index_or_a_length():
    """00 "15 seconds" was backed by joint index 15; 02 "6 seconds" by "5.54 cm"; 03 "15 s" by "14.8" mm."""
    known = _known("15 left_hand\njoint error 5.54 cm\nmedian 14.8 mm, 9.5 mm")
    for prose in ("runs in about 15 seconds", "about 6 seconds each", "takes 15 s", "about 10 s"):
        assert unbacked(prose, known, "--") != [], prose
    assert unbacked("runs in 15 seconds", _known("done in 15.2 s"), "--") == []


def test_a_percentage_is_not_backed_by_a_bare_number():
    """04 "0.1 %" was backed by "0.13"."""
    assert unbacked("a 0.1 % change", _known("ratio 0.13"), "--") == ["0.1 %"]
    assert unbacked("met in 92% of the cases", _known("all met: 92%"), "--") == []


def test_the_units_the_old_guard_skipped_are_checked():
    """×/x/times, m, °, rad, hours, core-hours, frames/s and steps were not units to it."""
    known = _known("12.5x faster; 35.13 frame/s; 2.1 core-hours; 0.5 rad; 303 steps")
    for prose in ("4 to 10 times slower", "9x the compute", "45 core-hours", "33 hours", "0.5°", "2 m away",
                  "at 40 frames/s", "after 300 steps"):
        assert unbacked(prose, known, "--") != [], prose
    for prose in ("12.5× faster", "35 frames/s", "2.1 core-hours", "0.5 rad", "303 steps"):
        assert unbacked(prose, known, "--") == [], prose


def test_bare_decimals_are_checked():
    """Table values, accuracies and GT errors carry no unit (05 c43 "1.52", 04 "0.92", 02 "0.473")."""
    known = _known("L_ikd-L2 1.52\nGT error 0.473\naccuracy 0.92")
    assert unbacked("ProtoRes 1.52, GT error 0.473, accuracy 0.92", known, "--") == []
    assert unbacked("ProtoRes 1.53, GT error 0.47, accuracy 0.29", known, "--") == ["1.53", "0.29"]


def test_numbers_in_words_are_refused():
    """"about a tenth of a millisecond", "ten to thirty times", "about ten microseconds", "about a minute"."""
    for prose in ("about a tenth of a millisecond", "ten to thirty times slower", "about ten microseconds per pose",
                  "It takes about a minute.", "trained in about an hour"):
        assert any(b.startswith("in words") for b in unbacked(prose, Known(), "--")), prose
    assert unbacked("a user's hour of two cores; several times the cost", Known(), "--") == []


def test_every_number_of_a_list_is_read():
    """In "71 / 56 / 80 mm" only "56 / 80 mm" was checked."""
    known = _known("71 mm\n80 mm\n55.9 mm")
    assert unbacked("71 / 56 / 80 mm", known, "--") == []
    assert unbacked("71 / 57 / 80 mm", known, "--") == ["71 / 57 / 80 mm"]
    assert unbacked("28 and 29 mm", _known("28.2 mm 29.4 mm"), "--") == []
    assert unbacked("28 and 31 mm", _known("28.2 mm 29.4 mm"), "--") == ["28 and 31 mm"]


def test_a_number_takes_its_unit_from_its_column_header():
    """A fixed-width table's "MPJPE mm" column backs "76 mm", not "76 ms"; likewise a Markdown table's column."""
    table = "method      set  MPJPE mm  ms/pose\nfabrik        5        76     0.71\n"
    known = _known(table)
    assert known.matches("76", "mm") and known.matches("0.71", "ms") and not known.matches("76", "ms")
    md = "| solver | ms per solve | MPJPE mm |\n|:--|--:|--:|\n| `dls` | 0.521 | 20.5 |\n"
    known = _known(md)
    assert known.matches("20.5", "mm") and known.matches("0.521", "ms") and not known.matches("20.5", "ms")


def test_results_files_back_the_pages():
    """README's "200 cases / 1.5 min" against a results file made in 321.5 s is caught."""
    known = Known().add_json({"seconds": 321.5, "cases": 1000, "rows": [{"mpjpe_mm_median": 67.8}]})
    assert unbacked("about 1.5 min on 2 cores", known, "--") == ["1.5 min"]
    assert unbacked("5.4 min; 67.8 mm", known, "--") == []
