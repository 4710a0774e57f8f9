"""``docs/benchmarks.md``: the measured figures, rendered from the results files under ``data_samples/results``.

Each file carries how it was made — ``command``, ``date``, ``machine`` (:mod:`posekit.provenance`) — and the page
shows them beside its rows, so a figure on the page always names the run it comes from. Every measured figure
carries a source marker naming its file and key (``<!-- data: FILE PATH -->``, :mod:`posekit.docs.prose`), which
``tests/test_prose_numbers.py`` compares with the file. Re-running a benchmark and
then ``posekit docs build`` updates both. Files this module has no layout for are shown as a plain table of their
rows, so a new results file appears on the page without code.
"""

from __future__ import annotations

import json
from pathlib import Path

from .prose import data_marker, mark_figures

__all__ = ["markdown", "results_dir", "STUDIO_SESSIONS", "STUDIO_COMMAND"]

STUDIO_SESSIONS = "bench_studio_sessions.json"
"""The class-sizing results file: ``posekit bench studio --sessions ... --out`` writes it."""
STUDIO_COMMAND = f"posekit bench studio --sessions 1,2,4,8 --out data_samples/results/{STUDIO_SESSIONS}"

INTRO = """\
# Benchmarks

*Written by `posekit docs build` from the results files under
[`data_samples/results`](../data_samples/results); do not edit by hand. Each file holds the command that made it,
the machine and the date; re-run that command, then `posekit docs build`, and this page follows.
`tests/test_docs.py` fails when the page differs from what the files say.*

Errors repeat exactly on a rerun with the same seed; times depend on the machine and its load. Results measured
on the Bandai mini set or the full Bandai Namco datasets are CC BY-NC 4.0 like the data (non-commercial use only,
with attribution; see the [README](../README.md#licence-and-data-terms)). How the measures are defined:
[measures](measures.md).
"""


def results_dir() -> Path:
    """``data_samples/results`` (:func:`posekit.paths.samples_dir`)."""
    from ..paths import samples_dir

    return samples_dir() / "results"


# --------------------------------------------------------------------------------------------- formatting
def _num(v) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if v != v:
            return "n/a"
        return f"{v:.3g}" if abs(v) >= 1e5 else f"{v:.4g}"
    return " ".join(str(v).split()).replace("|", "\\|")


def _marked(v, file: str | None, path: str) -> str:
    """``v`` as :func:`_num` shows it, with the marker of its source when it is a number and ``file`` is given."""
    text = _num(v)
    if file and isinstance(v, (int, float)) and not isinstance(v, bool) and v == v:
        text += data_marker(file, path)
    elif file and isinstance(v, str):
        text = _settings(text, file, path)
    return text


def _settings(text: str, file: str, path: str) -> str:
    """A text of a results file (a run's label, its description): the figures it holds are the run's settings."""
    return mark_figures(text, f"<!-- setting: {file} {path} -->")


def _table(rows: list[dict], columns: list[str], labels: dict | None = None, file: str | None = None,
           paths: list[str] | None = None) -> str:
    """A Markdown table of ``columns`` (those empty in every row left out). With ``file``, each number carries the
    marker of its source: ``paths[i]`` is row ``i``'s path in the file (``rows[3]``)."""
    columns = [c for c in columns if any(r.get(c) is not None for r in rows)]
    labels = labels or {}
    paths = paths or [""] * len(rows)
    lines = ["| " + " | ".join(labels.get(c, f"`{c}`") for c in columns) + " |",
             "|" + "|".join(":--" if k == 0 else "--:" for k in range(len(columns))) + "|"]
    for r, path in zip(rows, paths):
        lines.append("| " + " | ".join(_marked(r.get(c), file, f"{path}.{c}") for c in columns) + " |")
    return "\n".join(lines)


def _indexed(d: dict, key: str, keep=lambda r: True) -> tuple[list[dict], list[str]]:
    """The elements of ``d[key]`` that ``keep`` keeps, and their paths in the file (``key[i]``)."""
    pairs = [(r, f"{key}[{i}]") for i, r in enumerate(d.get(key, [])) if keep(r)]
    return [r for r, _ in pairs], [p for _, p in pairs]


def _scalar_columns(rows: list[dict], limit: int = 12) -> list[str]:
    keys = []
    for r in rows:
        keys += [k for k, v in r.items() if not isinstance(v, (dict, list))]
    return list(dict.fromkeys(keys))[:limit]


def _machine(m) -> str:
    if not isinstance(m, dict):
        return _num(m) if m else "not recorded"
    parts = [m.get("platform"), m.get("processor"),
             f"{m['cpu_count']} CPUs" if m.get("cpu_count") else None,
             f"Python {m['python']}" if m.get("python") else None]
    return ", ".join(p for p in parts if p)


def _seconds(s, name: str) -> str | None:
    path = "seconds"
    if isinstance(s, dict):
        s, path = s.get("total"), "seconds.total"
    return None if s is None else f"{_marked(s, name, path)} s"


def _provenance(name: str, d: dict) -> str:
    rows = [("made by", f"`{d['command']}`" if d.get("command") else "not recorded"),
            ("date", d.get("date") or "not recorded"), ("machine", _machine(d.get("machine")))]
    took = _seconds(d.get("seconds"), name)
    if took:
        rows.append(("the run took", took))
    rows.append(("file", f"[`{name}`](../data_samples/results/{name})"))
    out = "| | this run |\n|:--|:--|\n" + "\n".join(f"| {k} | {v} |" for k, v in rows)
    if d.get("provenance_note"):
        out += f"\n\n*Provenance: {d['provenance_note']}.*"
    return out


# --------------------------------------------------------------------------------------------- the sections
def _bench_all(name: str, d: dict) -> str:
    from ..bench.all import EXACT, verdicts, winners

    rows = d["rows"]

    def mark(r, key):
        return data_marker(name, f"rows[method={r['method']},effectors={r['effectors']},start={r['start']}].{key}")

    def cell(r):
        if r is None:
            return "—"
        return (f"`{r['method']}` {r['mpjpe_mm_median']:.1f}{mark(r, 'mpjpe_mm_median')}, "
                f"{r['converged_fraction']:.3f}{mark(r, 'converged_fraction')}, "
                f"{_num(r['latency_ms_median'])}{mark(r, 'latency_ms_median')}")

    lines = ["| effectors | start | closest pose | closest that meets its effectors | `dls` | `fabrik` |",
             "|:-:|:--|:--|:--|:--|:--|"]
    for w in winners(rows, list(d["effectors"]), list(d["starts"])):
        lines.append(f"| `{w['effectors']}` | {w['start']} | {cell(w['closest'])} | {cell(w['closest_exact'])} | "
                     f"{cell(w['dls'])} | {cell(w['fabrik'])} |")
    return "\n\n".join([
        f"Every registered solver on the same {d['cases']} held-out cases of `{d['data']}` per start condition and "
        f"effector set, one thread (lesson 06). The full report, with a table per effector set and start "
        f"condition and every column defined: [`bench_all.md`](../data_samples/results/bench_all.md).",
        _provenance(name, d),
        f"**Who wins where.** Each cell: solver, median MPJPE in mm (as the report defines it), the share of cases "
        f"that converged, median ms per solve. *Meets its effectors*: converged in at least {_num(EXACT)}"
        "<!-- definition: posekit.bench.all.EXACT --> of the cases.",
        "\n".join(lines),
        *(["**Learned solvers against plain DLS and FABRIK** (median MPJPE, shown to 0.1 mm<!-- definition: the "
           "precision posekit.bench.verdicts compares at -->: a tie is not closer).",
           "\n".join(f"- {v}" for v in verdicts(rows, list(d["effectors"]), list(d["starts"]), mark=mark))]
          if verdicts(rows) else []),
        "![median time per solve against median MPJPE, every solver](../data_samples/results/bench_all.png)"])


def _studio(name: str, d: dict) -> str:
    rows = d.get("rows", [])
    parts = ["The posing studio served by Voila to headless Chromium (`posekit bench studio`, lesson 06). The "
             "browsers ran on the same machine as the server, so their software WebGL shared its cores: with a "
             "class, a pessimistic figure for students on their own machines.", _provenance(name, d)]
    klass, kpaths = _indexed(d, "rows", lambda r: "class" in r)
    if klass:
        parts += ["**A class at once** (every session moving its target at the same time; the kernels left after "
                  "the sessions closed and the idle cull ran):",
                  _table(klass, ["sessions", "kernels", "rss_mb_total", "lost", "worst_p95_ms",
                                 "kernels_after_cull", "cull_s"],
                         {"sessions": "sessions", "kernels": "kernels", "rss_mb_total": "kernels' memory MB",
                          "lost": "updates lost", "worst_p95_ms": "worst p95 ms per session",
                          "kernels_after_cull": "kernels left after the cull", "cull_s": "culled after s"},
                         name, kpaths)]
    sessions, spaths = _indexed(d, "rows", lambda r: "session" in r)
    if sessions:
        parts += ["Each session:", _table(sessions, ["sessions", "session", "updates", "lost", "p50_ms", "p95_ms",
                                                     "max_ms", "rss_mb"], None, name, spaths)]
    other, opaths = _indexed(d, "rows", lambda r: "class" not in r and "session" not in r)
    if other:
        parts += ["Other rows:", _table(other, _scalar_columns(other), None, name, opaths)]
    return "\n\n".join(parts)


PROTORES_COLUMNS = ["method", "width", "steps", "5point_ikd_l2_e3", "5point_loc_geo", "5point_mpjpe_mm",
                    "random_ikd_l2_e3", "random_loc_geo", "random_mpjpe_mm", "ms_predict", "parameters", "train_min"]


def _protores(name: str, d: dict) -> str:
    what = ("ProtoRes's scaling curve: widths and step counts, scored on lesson 05's benchmarks" if "scaling" in name
            else "ProtoRes's reference setting of the studies (its width and steps in the rows) once per seed, nothing else "
            "changed: how far runs that differ only in their seed differ, the yardstick lesson 05 reads every "
            "ordering of a network against" if "seeds" in name else
            "ProtoRes and its ablations (Table 2 of Oreshkin et al. 2022), short runs at CPU scale, scored on "
            "lesson 05's 5-point and random benchmarks")
    parts = [what + ". Column names are the file's keys; lesson 05 defines each measure.", _provenance(name, d),
             _table(*_indexed(d, "rows")[:1], PROTORES_COLUMNS + (["compute"] if "scaling" in name else []), None,
                    name, _indexed(d, "rows")[1])]
    if isinstance(d.get("width"), list):  # the seed study's "width" is its one width, not a study
        parts += ["The width study:", _table(d["width"], PROTORES_COLUMNS, None, name, _indexed(d, "width")[1])]
    return "\n\n".join(parts)


def _protores_speed(name: str, d: dict) -> str:
    """``posekit bench protores --speed-only --out``: each network's speed against the machine's arithmetic."""
    labels = {"method": "network", "macs_per_pose": "multiply-adds per pose", "gemm_gmacs": "GEMM rate GMAC/s",
              "ideal_poses_per_s": "ideal poses/s", "poses_per_s": "measured poses/s",
              "fraction_of_ideal": "of ideal",
              "fraction_met": f"goal >= {_marked(d.get('goal_fraction'), name, 'goal_fraction')} met",
              "ms_products_one": "one pose: products ms", "ms_solve_median": "one pose: solve ms (median)",
              "ms_met": f"goal <= {_marked(d.get('goal_ms'), name, 'goal_ms')} ms met"}
    return "\n\n".join([
        "ProtoRes and its baselines against the roofline (lesson 05), one thread, 5-point poses: the multiply-adds "
        "of one pose counted from the layer sizes, the float32 GEMM rate measured on each network's own matrix "
        "shapes for a batch of 1,000 poses, the poses/s that rate allows (ideal), the network's measured pass on "
        "that batch, and one pose: its products alone, then a whole pose through `solve` (medians of every round, "
        "in the thread's CPU time).",
        _provenance(name, d) + (f"\n\n*The 1-minute load average when the run began: "
                                f"{_marked(d['load_avg_1min_before'], name, 'load_avg_1min_before')} on "
                                f"{_num((d.get('machine') or {}).get('cpu_count'))} "
                                "CPUs; other work slows every timing, so each is a median.*"
                                if d.get("load_avg_1min_before") is not None else ""),
        _table(d["rows"], ["method", "width", "macs_per_pose", "gemm_gmacs", "ideal_poses_per_s", "poses_per_s",
                           "fraction_of_ideal", "fraction_met", "ms_products_one", "ms_solve_median", "ms_met"],
               labels, name, _indexed(d, "rows")[1])])


def _ae_scale(name: str, d: dict) -> str:
    data = d.get("data") or {}
    size = (f" ({data['frames']} frames, {data['clips']} clips)"
            if isinstance(data, dict) and "frames" in data and "clips" in data else "")
    return "\n\n".join([
        f"Lesson 03's autoencoder and latent solvers trained on the full Bandai Namco datasets and benchmarked "
        f"against FABRIK, protocol `{d.get('protocol')}`: {_settings(d.get('description', ''), name, 'description')}"
        f"{size}.",
        _provenance(name, d),
        _table(d["rows"], ["method", "effectors", "start", "cases", "mpjpe_mm_median", "effector_error_mm_median",
                           "natural_mm_median", "converged_fraction", "latency_ms_median"], None, name,
               _indexed(d, "rows")[1])])


def _generic(name: str, d: dict) -> str:
    rows = d.get("rows") if isinstance(d, dict) else d
    parts = [_provenance(name, d if isinstance(d, dict) else {})]
    if isinstance(rows, list) and rows and all(isinstance(r, dict) for r in rows):
        parts.append(_table(rows, _scalar_columns(rows), None, name,
                            [f"rows[{i}]" if isinstance(d, dict) else f"[{i}]" for i in range(len(rows))]))
    return "\n\n".join(parts)


def _nbgrader(name: str, d: dict) -> str:
    cols = ["lesson", "assignment", "autograde_s", "autograde_cpu_s", "load_avg_1min_before", "score", "max_score"]
    labels = {"autograde_s": "autograde s (wall)", "autograde_cpu_s": "CPU s", "load_avg_1min_before":
              "load before", "max_score": "of"}
    return "\n\n".join([_provenance(name, d), _num(d.get("what", "")),
                         _table(d["lessons"], cols, labels, name, _indexed(d, "lessons")[1]),
                         "How to grade a class: [grading with nbgrader](nbgrader.md)."])


SECTIONS = [
    ("bench_all.json", "Every solver on the same cases", _bench_all),
    (STUDIO_SESSIONS, "The studio for a class: sizing", _studio),
    ("bench_protores.json", "ProtoRes: speed against the roofline", _protores_speed),
    ("protores_ablation.json", "ProtoRes: ablations and width", _protores),
    ("protores_scaling.json", "ProtoRes: scaling", _protores),
    ("protores_seeds.json", "ProtoRes: runs that differ only in their seed", _protores),
    ("ae_scale_full.json", "Lesson 03 at full scale", _ae_scale),
    ("ae_scale_cross.json", "Lesson 03 across datasets", _ae_scale),
    ("nbgrader_autograde.json", "Autograding one submission of each lesson", _nbgrader),
]
"""The known results files, in the page's order: (file, title, renderer)."""


def _registered() -> str:
    """Every registered benchmark and the results file it writes (or that it only prints)."""
    from ..bench.plugin import benchmark_names, get_benchmark

    lines = ["| command | what it measures |", "|:--|:--|"]
    for n in benchmark_names():
        lines.append(f"| `posekit bench {n}` | {_num(get_benchmark(n).help)} |")
    return "\n".join(lines)


def markdown(folder=None) -> str:
    """The page, from the results files in ``folder`` (default :func:`results_dir`)."""
    folder = Path(folder) if folder is not None else results_dir()
    files = {p.name: p for p in sorted(folder.glob("*.json"))}
    out = [INTRO, "## Contents", ""]
    sections = []
    known = {f for f, _, _ in SECTIONS}
    for fname, title, render in SECTIONS + [(f, f, _generic) for f in files if f not in known]:
        if fname not in files:
            if fname == STUDIO_SESSIONS:
                sections.append((title, "No class-sizing results are shipped yet. They come from one command, "
                                 "which opens that many headless browsers against one server (it needs Debian's "
                                 f"`chromium`; `make test` installs it):\n\n```bash\n{STUDIO_COMMAND}\n"
                                 "posekit docs build\n```\n\nThis section then shows, for each class size, the "
                                 "worst p95 latency per session, the kernels' memory, the updates lost and the "
                                 "kernels left after the idle cull. How to read it for a class: "
                                 "[the studio for a class](studio.md)."))
            continue
        d = json.loads(files[fname].read_text(encoding="utf-8"))
        sections.append((title, render(fname, d)))
    for title, _ in sections:
        anchor = "".join(c for c in title.lower().replace(" ", "-") if c.isalnum() or c in "-_")
        out.append(f"- [{title}](#{anchor})")
    for title, text in sections:
        out += ["", f"## {title}", "", text]
    out += ["", "## Every benchmark command", "",
            "Each prints its tables (or `--json`); `bench all`, `bench ae-scale` and `bench studio --out` also write "
            "a results file, and `posekit train protores-studies` writes the ProtoRes study files. Options: "
            "[the command line](cli.md#posekit-bench).", "", _registered()]
    return "\n".join(out) + "\n"
