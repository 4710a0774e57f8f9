"""Propose source markers for the unmarked figures of the lessons' markdown (``tests/test_prose_numbers.py``).

For each measured figure of a lesson's markdown that has no marker, it looks for the outputs of the notebook's code
cells (and the results files its code names) that show the same value in the same unit, nearest cell first, and
writes the marker that names it — ``<!-- out: "LABEL" -->``, ``<!-- out: "ROW" col "HEADER" -->`` or
``<!-- data: FILE PATH -->`` — after checking that the marker resolves to that very number. Only markdown cells are
edited; outputs are never touched. What it binds is a proposal to read: it prints every binding (figure, the
sentence, the output line it names) and every figure it could not bind, and ``--dry-run`` writes nothing.

    python tools/mark_prose_sources.py notebooks/05_protores.ipynb [--dry-run] [--exempt exempt.json]

``--exempt`` reads ``{"05": {"10 ms": "paper: Oreshkin et al. 2022 ..."}}``: figures as written, per lesson, that
get that exemption marker instead (goals, papers' figures, definitions, settings).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

import nbformat

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from posekit.docs import prose  # noqa: E402
from posekit.docs.prose import (_OUT_NUM, _UNIT_AFTER, Outputs, Source, SourceError, agrees,  # noqa: E402
                                blank_non_prose, family, figures, parse_markers, bind, resolve_data, _unit_of_header)

RESULTS = ROOT / "data_samples" / "results"

# the old allow-list of tests/test_prose_numbers.py, as markers: (lesson, figure as written) -> marker body
EXEMPT = {
    ("03", "0.1 ms"): "goal: one solve (the Aim)", ("03", "5 µs"): "goal: per pose, batched (the Aim)",
    ("03", "3 cm"): "goal: effectors (the Aim)", ("04", "10 ms"): "goal: one solve (the Aim)",
    ("04", "2,000 solves per second"): "goal: batched, one thread (the Aim)",
    ("04", "2 cm"): "goal: the generator's pose, two targets (the Aim)",
    ("05", "20,000 poses per second"): "goal: a retired goal, shown above every network's ideal (section 6)",
    ("06", "3 ms"): "goal: per solve (the Aim)",
    ("04", "50 %"): "definition: a discriminator's accuracy when it cannot tell",
    ("04", "100 %"): "definition: a discriminator's accuracy when it has won",
    ("05", "45 seconds"): "setting: exercise 4's time budget (its instructor notes: seconds=45)",
    ("04", "20 seconds"): "setting: the live demo's time budget, seconds=20 in its code",
    ("05", "20 seconds"): "setting: the live demo's time budget, seconds=20 in its code",
    ("05", "20 m"): "setting: a target distance for the reader to try",
    ("05", "50 cm"): "setting: a target distance for the reader to try",
    ("05", "90°"): "setting: an angle for the reader to try",
    ("05", "1 mm"): "setting: the default tolerance of an Effector",
    ("01", "1 mm"): "setting: the convergence tolerance",
    ("01", "1 s"): "setting: the same-clip start's distance (posekit.data.cases)",
    ("04", "1 mm"): "setting: the optimisers' tolerance",
    ("06", "1 mm"): "setting: the sliders' step", ("06", "50 cm"): "setting: the sliders' range",
    ("06", "1 m"): "setting: where a look-at target starts",
    ("00", "90°"): "setting: an angle in an example", ("00", "0.5°"): "setting: an exercise's tolerance",
    ("01", "6.56 / 6.74 ms"): "paper: Victor et al. 2021, Table 1 (FABRIK, 2 / 5 effectors)",
    ("03", "6.56 / 6.74 ms"): "paper: Victor et al. 2021, Table 1 (FABRIK, 2 / 5 effectors)",
    ("05", "10 ms"): "paper: Oreshkin et al. 2022, about 10 ms per pose in Unity",
    ("05", "33 hours"): "paper: Oreshkin et al. 2022, their training time on a GPU",
    ("03", "1 cm"): "setting: the std floor of the z-score (posekit.data.pose_vectors.STD_FLOOR)",
    ("03", "1 s"): "setting: training pairs at most 1 s apart (PAIR_MAX_S)",
    ("03", "5 s"): "setting: an exercise's suggested setting",
    ("03", "40 cm"): "setting: a suggested target for the reader to try",
    ("04", "40 cm"): "setting: a suggested target for the reader to try",
    ("03", "0.94 m"): "definition: the mini set's root helper point below the pelvis (a fact of the data)",
    ("03", "442 kB"): "paper: Victor et al. 2021, their model's size for two effectors",
    ("04", "0.1 %"): "setting: the optimisers' stopping rule", ("04", "0.05"): "setting: Adam's step size",
    ("04", "8 steps"): "setting: L-BFGS's memory",
    ("00", "30 fps"): "definition: the Bandai data's frame rate (a fact of the data)",
    ("01", "60°"): "setting: the near-extended step's threshold",
}

# read and decided: (lesson, the text that ends with the figure, once in the lesson's markdown) -> marker body
DECIDED = [
    ("00", "in 720 small steps of 0.5°", "setting: the demonstration's step"),
    ("01", "FABRIK reaches its targets (within 1 mm) in at least 95%", "goal: the lesson's Aim"),
    ("01", "sits at 97–99 %", "setting: the reach shares section 2's table places a head target at"),
    ("01", "is at ≥ 90 %", "setting: straighten_chain's ratio=0.9"),
    ("01", "lies at ≥ 90 %", "setting: straighten_chain's ratio=0.9"),
    ("01", "weighted as 0.1 m", "setting: DLS's weight of an angle, metres per radian"),
    ("01", "with `ratio` 0.5, 0.8, 0.95 and 0.999", "setting: ratios for the exercise to try"),
    ("01", "convergence (0.60",
     'out: "method set effector mm MPJPE mm bone mm converged iters" "fabrik-constrained 5point" col "converged"'),
    ("01", "a converged fraction of 1.00",
     'out: "method set effector mm MPJPE mm bone mm converged iters" "fabrik 5" col "converged"'),
]

# words before a figure that make it a setting, a goal or an example more often than a measurement: never bound
# by the script (listed for a reader to decide)
SETTING_CONTEXT = re.compile(r"(?i)(within|tolerance|ratio|at least|at most|≥|≤|<=|>=|goal|target of|step of|"
                             r"\bsay\b|\btry\b|e\.g\.|for example|budget|threshold|`[a-z_]+=)[^.]{0,25}$")


def _quote_ok(s: str) -> bool:
    return '"' not in s and "--" not in s and ";" not in s and s.strip() != ""


def _numbers(outputs: Outputs):
    """Every number of the outputs: (cell, text, line index, line, match, unit or None)."""
    for cell, text in outputs.cells:
        lines = text.split("\n")
        for li, line in enumerate(lines):
            for m in _OUT_NUM.finditer(line):
                after = line[m.end():]
                u = re.match(_UNIT_AFTER, after)
                if re.match(r"[A-Za-z_]", after) and not u:
                    continue
                unit = u.group("unit") if u else None
                header = _header_over(lines, li, m) if "|" not in line else _md_header(lines, li, m)
                if unit is None and header:
                    unit = _unit_of_header(header)
                yield cell, text, li, line, m, unit, header


def _header_over(lines, li, m):
    """The fixed-width column header over the number ``m`` of line ``li``: the run of words (single spaces) of the
    nearest line above with no decimal that overlaps the number's span."""
    for k in range(li - 1, max(-1, li - 40), -1):
        line = lines[k]
        if not line.strip():
            continue
        if any(re.fullmatch(r"-?[\d,.]+%?", t) for t in re.sub(r"\([^)]*\)", "", line).split()):
            continue                  # a data line (a number of its own outside parentheses): a header has none
        # the header word over the number (overlapping it, else at most 2 characters beside it), with the words
        # before it when it alone is not unique on the line ("model kB" beside "solver kB")
        toks = list(re.finditer(r"\S+", line))
        best, gap = None, 3
        for k, t in enumerate(toks):
            g = max(t.start() - m.end(), m.start() - t.end(), -1)
            if g < gap and re.search(r"[A-Za-z%]", t.group(0)):
                best, gap = k, g
        if best is not None:
            k = best
            head = toks[k].group(0)
            while k > 0 and len(re.findall(rf"(?<!\S){re.escape(head)}(?!\S)", line)) > 1:
                k -= 1
                head = toks[k].group(0) + " " + head
            return head
        # a line of words that does not reach the number: keep looking up only through data lines
        if not re.search(r"\d", line):
            return None
    return None


def _md_header(lines, li, m):
    line = lines[li]
    pos = line[:m.start()].count("|") - 1
    for k in range(li - 1, -1, -1):
        if "|" not in lines[k]:
            return None
        cells = [c.strip() for c in lines[k].strip().strip("|").split("|")]
        if all(re.fullmatch(r":?-+:?", c) for c in cells if c):
            continue
        if k == 0 or "|" not in lines[k - 1] or all(re.fullmatch(r":?-+:?", c) for c in [
                c.strip() for c in lines[k + 1].strip().strip("|").split("|")] if c):
            return cells[pos] if 0 <= pos < len(cells) else None
    return None


def _unique_line_above(outputs: Outputs, text: str, li: int):
    """The nearest title-like line above ``li`` (this cell's output: words, at most one number) whose text occurs
    once in all the outputs."""
    lines = text.split("\n")
    for k in range(li - 1, -1, -1):
        t = " ".join(lines[k].split())
        if len(t) < 4 or not _quote_ok(t) or len(_OUT_NUM.findall(t)) > 1 or not re.search(r"[A-Za-z]{3}", t):
            continue
        src = Source("out", "", anchors=[t])
        try:
            outputs.resolve(src)
        except SourceError as e:
            if "times" in str(e):
                continue
            if "no number" not in str(e):
                continue
        return t
    return None


def _try(outputs, src, fig, value):
    try:
        v, unit, _ = outputs.resolve(src)
    except SourceError:
        return False
    return v == value and agrees(fig, v, unit)[0]


def _fmt(src: Source) -> str:
    body = " ".join(f'"{a}"' for a in src.anchors)
    if src.col:
        body += f' col "{src.col}"'
    if src.nth != 1:
        body += f" #{src.nth}"
    if src.unit:
        body += f" unit {src.unit}"
    return f"out: {body}"


def out_sources(outputs: Outputs, cell, text, li, line, m, header, fig, value, unit_hint=None):
    """Markers that name this number, most readable first, each checked to resolve to it."""
    nums_before = [n for n in _OUT_NUM.finditer(line[:m.start()])]
    label_start = nums_before[-1].end() if nums_before else 0
    label = " ".join(line[label_start:m.start()].split())
    label = re.split(r"[;,]", label)[-1].strip()
    label = re.sub(r"^[^A-Za-z(]*", "", label)
    first_cell = re.split(r"\s{2,}|\|", line.strip())[0].strip()
    between = " ".join(line[label_start:m.start()].split()).strip(" )")
    tries = []
    if len(label) >= 3 and _quote_ok(label):
        tries.append([label])
        # what comes before on the line, up to the number before: "worst frame ...: optimisation" then "GPR guess"
        prefix = line[:nums_before[-1].start()] if nums_before else ""
        prefix = " ".join(re.split(r"[;]", prefix)[-1].split()).strip(" ,:")
        if len(prefix) > 60:
            prefix = prefix[-60:].split(" ", 1)[-1]
        if len(prefix) >= 3 and _quote_ok(prefix):
            tries.append([prefix, label])
    if between and not label and _quote_ok(between) and first_cell and _quote_ok(first_cell) and \
            line.find(first_cell) + len(first_cell) <= label_start:
        tries.append([first_cell, between])
        # a longer label: from the line's start
        full = " ".join(line[:m.start()].split())
        if full != label and _quote_ok(full):
            tries.append([full])
    # a table row: its first cell, or its first cells, under the column's header
    cells = [c.strip() for c in re.split(r"\s{2,}|\|", line[:m.start()].strip()) if c.strip()]
    col = None
    rows = []
    if header and len(header) <= 30 and _quote_ok(header):
        for k in range(1, len(cells) + 1):
            row = " ".join(" ".join(cells[:k]).split())
            if _quote_ok(row):
                rows.append(row)
        col = header
    tries = [[r] for r in rows] + tries
    ctx = _unique_line_above(outputs, text, li)
    out = []
    for anchors in tries:
        is_col = col is not None and anchors[0] in rows
        for a in (anchors, ([ctx] + anchors) if ctx and ctx not in anchors else None):
            if a is None:
                continue
            src = Source("out", "", anchors=list(a), col=col if is_col else None, unit=unit_hint)
            if _try(outputs, src, fig, value):
                out.append(src)
                break
        if out:
            break
    if not out and ctx:
        # the N-th number after the unique line above
        start = text.find(ctx) if ctx in text else None
        for n in range(1, 60):
            src = Source("out", "", anchors=[ctx], nth=n, unit=unit_hint)
            try:
                v, _, _ = outputs.resolve(src)
            except SourceError:
                break
            if _try(outputs, src, fig, value):
                out.append(src)
                break
        del start
    return out


def _results_named(nb) -> list[Path]:
    code = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")
    helpers = {"protores_ablation.json": "studies_path", "protores_scaling.json": "scaling_path"}
    return [p for p in sorted(RESULTS.glob("*.json")) if p.stem in code or p.stem.rsplit("_", 1)[0] + "_{" in code
            or (p.name in helpers and helpers[p.name] in code)]


def _json_leaves(node, path=""):
    if isinstance(node, dict):
        for k, v in node.items():
            if re.fullmatch(r"[^.\[\]=,]+", str(k)):
                yield from _json_leaves(v, f"{path}.{k}" if path else str(k))
    elif isinstance(node, list):
        for i, e in enumerate(node):
            sel = f"[{i}]"
            if isinstance(e, dict):
                ids = {k: v for k, v in e.items() if isinstance(v, str) and len(v) < 40 and re.fullmatch(r"[^,\]=]+", v)}
                if ids and sum(all(isinstance(o, dict) and o.get(k) == v for k, v in ids.items()) for o in node) == 1:
                    sel = "[" + ",".join(f"{k}={v}" for k, v in ids.items()) + "]"
            yield from _json_leaves(e, path + sel)
    elif isinstance(node, (int, float)) and not isinstance(node, bool):
        yield path, float(node)


def data_sources(files, fig):
    out = []
    for p in files:
        doc = json.loads(p.read_text(encoding="utf-8"))
        for path, v in _json_leaves(doc):
            src = Source("data", "", file=p.name, path=path)
            try:
                value, unit, _ = resolve_data(RESULTS, src)
            except SourceError:
                continue
            fam = family(unit)[0]
            if fig.unit and fam and fam != family(fig.unit)[0]:
                continue
            if not (fig.unit and fam) and fig.unit:
                continue              # a unit in the prose wants a key that names one
            if agrees(fig, value, unit)[0]:
                out.append(src)
    return out


def _plain(text: str):
    """``text`` without its source markers, and for each of its positions the position in ``text``."""
    keep, where = [], []
    pos = 0
    for mk in parse_markers(text):
        keep.append(text[pos:mk.start])
        where += range(pos, mk.start)
        pos = mk.end
    keep.append(text[pos:])
    where += range(pos, len(text) + 1)
    return "".join(keep), where


def insert_after(nb: dict, snippet: str, body: str) -> str | None:
    """Write ``<!-- body -->`` after ``snippet`` (once in the notebook's markdown, markers aside); None when done,
    else why not."""
    hits = []
    for c in nb["cells"]:
        if c["cell_type"] != "markdown":
            continue
        text = "".join(c["source"])
        plain, where = _plain(text)
        pattern = r"\s+".join(re.escape(w) for w in snippet.split())
        hits += [(c, text, where, m.end()) for m in re.finditer(pattern, plain)]
    if len(hits) != 1:
        return f"{len(hits)} places"
    c, text, where, end = hits[0]
    at = where[end - 1] + 1
    if text[at:].lstrip(" ").startswith("<!--"):
        return None               # marked already
    c["source"] = text[:at] + f"<!-- {body} -->" + text[at:]
    return None


def carry(old: dict, new: dict, width: int = 40) -> list[str]:
    """Carry the markers of an older version of a notebook (``old``) into ``new`` where the text before each is
    still there, once; returns the markers it could not place."""
    lost = []
    for c in old["cells"]:
        if c["cell_type"] != "markdown":
            continue
        text = "".join(c["source"])
        for mk in parse_markers(text):
            before, _ = _plain(text[:mk.start])
            snippet = before[-width:]
            why = insert_after(new, snippet, mk.raw[4:-3].strip())
            if why:
                lost.append(f"{mk.raw} after '{snippet}': {why}")
    return lost


def propose(path: Path, exempt: dict, write: bool) -> tuple[int, list]:
    nb = json.loads(path.read_text(encoding="utf-8"))
    lesson = path.name[:2]
    for les, snippet, body in DECIDED:
        if les == lesson:
            why = insert_after(nb, snippet, body)
            if why:
                print(f"{path.name}: DECIDED '{snippet}' not placed: {why}")
    outputs = Outputs(nb)
    numbers = list(_numbers(outputs))
    files = _results_named(nb)
    unbound = []
    bound = 0
    for i, c in enumerate(nb["cells"]):
        if c["cell_type"] != "markdown":
            continue
        text = "".join(c["source"])
        blanked = blank_non_prose(text)
        pairs, _ = bind(blanked, figures(blanked), parse_markers(text))
        inserts = {}            # position -> [marker sources]
        groups = {}
        for fig, src, mk in pairs:
            if src is None and fig.required:
                groups.setdefault(fig.group, []).append(fig)
        for g, figs in groups.items():
            written = figs[-1].written
            if written in exempt.get(lesson, {}) or (lesson, written) in EXEMPT:
                inserts.setdefault(figs[-1].fig_end, []).append(exempt.get(lesson, {}).get(written)
                                                                 or EXEMPT[lesson, written])
                print(f"{path.name} cell {i}: {written!r} -> <!-- {inserts[figs[-1].fig_end][-1]} -->\n"
                      f"      | {_sentence(text, figs[-1].start)}")
                continue
            if SETTING_CONTEXT.search(blanked[max(0, figs[0].start - 60):figs[0].start]):
                for fig in figs:
                    unbound.append((i, fig.written, fig.num, "SETTING? " + _sentence(text, fig.start)))
                continue
            for fig in figs:
                found = None
                cands = []
                sentence = _sentence(text, fig.start)
                for cell, otext, li, line, m, unit, header in numbers:
                    value = float(m.group("num").replace(",", ""))
                    fam_s, fam_p = family(unit)[0], family(fig.unit)[0]
                    hint = None
                    if fam_p and fam_s and fam_s != fam_p:
                        continue
                    ok = agrees(fig, value, unit)[0]
                    if not ok and fam_p == "percent" and fam_s is None and agrees(fig, value, "share")[0]:
                        ok, hint = True, "share"
                    if not ok:
                        continue
                    same = 0 if (fam_p and fam_s) or not fam_p else 1
                    dist = (i - cell) if cell < i else (cell - i) + 2
                    nb_ = [n for n in _OUT_NUM.finditer(line[:m.start()])]
                    near = line[nb_[-1].end() if nb_ else 0:m.start()] + " " + re.split(r"\s{2,}", line.strip())[0]
                    words = {w.lower() for w in re.findall(r"[A-Za-z][\w+-]{2,}", near)}
                    said = sentence.lower()
                    overlap = -sum(1 for w in words if w in said)
                    cands.append((same, overlap, dist, cell, otext, li, line, m, header, value, hint))
                cands.sort(key=lambda t: (t[0], t[2], t[1]))
                for same, overlap, dist, cell, otext, li, line, m, header, value, hint in cands[:12]:
                    srcs = out_sources(outputs, cell, otext, li, line, m, header, fig, value, hint)
                    if srcs:
                        found = (_fmt(srcs[0]), f"cell {cell}: {line.strip()[:110]}", len(cands))
                        break
                if found is None:
                    ds = data_sources(files, fig)
                    if len(ds) >= 1:
                        found = (f"data: {ds[0].file} {ds[0].path}", f"{len(ds)} keys agree", len(ds))
                if found is None:
                    unbound.append((i, fig.written, fig.num, _sentence(text, fig.start)))
                    continue
                inserts.setdefault(fig.end if fig is not figs[-1] else fig.fig_end, []).append(found[0])
                bound += 1
                print(f"{path.name} cell {i}: {fig.num!r} of {fig.written!r} [{found[2]} candidates] -> "
                      f"<!-- {found[0]} -->   ({found[1]})\n      | {_sentence(text, fig.start)}")
        if inserts and write:
            for pos in sorted(inserts, reverse=True):
                text = text[:pos] + "<!-- " + "; ".join(inserts[pos]) + " -->" + text[pos:]
            c["source"] = text
    if write:
        path.write_text(nbformat.writes(nbformat.from_dict(nb)) + "\n", encoding="utf-8")
    return bound, unbound


def _sentence(text, pos):
    """The words around ``pos``: what a reader checks a binding against."""
    return " ".join(text[max(0, pos - 90):pos].split()) + " ⟦" + " ".join(text[pos:pos + 50].split())


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("notebooks", nargs="+")
    ap.add_argument("--dry-run", action="store_true")
    ap.add_argument("--exempt", default=None)
    ap.add_argument("--carry-from", default=None, metavar="REV",
                    help="first carry the markers of each notebook at git revision REV (after a merge took the "
                         "other side's notebook)")
    args = ap.parse_args(argv)
    exempt = json.loads(Path(args.exempt).read_text()) if args.exempt else {}
    if args.carry_from:
        import subprocess

        for nbp in args.notebooks:
            rel = Path(nbp).resolve().relative_to(ROOT)
            old = json.loads(subprocess.run(["git", "show", f"{args.carry_from}:{rel}"], cwd=ROOT, check=True,
                                            capture_output=True, text=True).stdout)
            new = json.loads(Path(nbp).read_text(encoding="utf-8"))
            lost = carry(old, new)
            for line in lost:
                print(f"{nbp}: NOT CARRIED {line}")
            if not args.dry_run:
                Path(nbp).write_text(nbformat.writes(nbformat.from_dict(new)) + "\n", encoding="utf-8")
    for nbp in args.notebooks:
        bound, unbound = propose(Path(nbp), exempt, not args.dry_run)
        print(f"== {nbp}: {bound} bound, {len(unbound)} without a source")
        for i, w, n, s in unbound:
            print(f"   UNBOUND cell {i}: {n!r} of {w!r} | {s}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
