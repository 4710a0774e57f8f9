"""``posekit bench all``: every registered IK solver in one report — a table per effector set and start
condition, who wins where, and a speed/quality scatter.

Introduced in ``notebooks/06_posing_studio.ipynb``. Nothing is measured here that
:func:`posekit.bench.ik.run` does not measure: this module calls it with every registered solver that
honours position effectors (:func:`posekit.bench.ik.resolve_solvers` with ``"all"``), no extra methods
and no peers, so every row comes from the same held-out cases (:func:`posekit.data.cases.build_cases`),
the same start poses and the same metric code (:mod:`posekit.evaluation.pose_scores`) as ``posekit bench ik``.
The data is the Bandai mini set, which the learned solvers were trained on
(:func:`posekit.bench.ik.default_data`). Effector sets: any of ``posekit bench ik``'s, several in one report
(``2``, ``5`` and ``random``, lesson 05's mixed kinds, say how the ranking changes with how much the effectors
say); a solver is given the effectors of the kinds it honours and scored on all of them, and a solver that
refuses a set (a lesson 03 network exists for its trained joint sets only) is listed as not measured there.

What it writes (``out``, a folder; by default ``data_samples/results``):

* ``bench_all.json`` — the rows and how they were made (command, cases, seed, data, and the machine and date
  of the run: :func:`posekit.provenance.stamp`);
* ``bench_all.md`` — what was measured, one Markdown table per effector set and start condition sorted by
  MPJPE, the best solver of each (:func:`winners`), and how to read the scatter;
* ``bench_all.png`` — median time per solve (ms) against median MPJPE (mm), both log, one panel per effector
  set and start condition, one point per solver: a speed/quality scatter in the spirit of Fig. 5 of Victor
  et al. 2021.

Units: times in milliseconds on one thread; distances in millimetres (the library's metres times 1000).
"""

from __future__ import annotations

import json
import re
import time
import warnings
from pathlib import Path

from ..data.cases import START_CONDITIONS, start_condition
from ..ik.api import EFFECTOR_SETS
from ..ik.registry import solver_info
from .ik import RANDOM, TABLE_LABELS, TABLES as IK_TABLES, WEIGHTS_HELP, _group_title, default_data, effector_set_names, resolve_solvers
from .ik import run as run_ik
from .all_plot import pareto, plot
from .verdicts import footer as verdict_footer, verdicts
from .plugin import arg, register_benchmark
from ..provenance import machine, today

__all__ = ["run", "write_report", "markdown", "plot", "pareto", "winners", "verdicts", "default_out", "FILES", "KEYS"]

FILES = ("bench_all.json", "bench_all.md", "bench_all.png")
"""What :func:`write_report` writes into its folder."""

KEYS = ("method", "start", "effectors", "lesson", "kinds", "latency_ms_median", "mpjpe_mm_median",
        "effector_error_mm_median", "effector_error_deg_median", "natural_mm_median", "converged_fraction",
        "bone_length_error_mm_max", "cases", "refused_cases", "refused_reason", "learned_kept_fraction", "finish_rule",
        "data")
"""The keys of every row (definitions in :mod:`posekit.bench.ik`; ``refused_cases`` and ``refused_reason``: the
cases the solver refused and the first refusal's sentence; ``learned_kept_fraction``: for a learned solver with an
exact finish, the share of its cases finished from the learned pose, else None; ``finish_rule``: how such a finish
chose its answer, ``"natural"`` when a naturalness comparison ran, ``"learned"`` when none could, else None)."""

_DIGITS = {"latency_ms_median": 4, "mpjpe_mm_median": 3, "effector_error_mm_median": 3,
           "effector_error_deg_median": 3, "natural_mm_median": 3, "converged_fraction": 4,
           "bone_length_error_mm_max": 4, "learned_kept_fraction": 4}
"""Decimals kept in the rows (0.1 us, 1 um): beyond them the numbers are noise."""


def default_out() -> Path:
    """Where the report goes by default: ``data_samples/results`` (:func:`posekit.paths.samples_dir`)."""
    from ..paths import samples_dir

    return samples_dir() / "results"


def _lesson(notebook: str) -> str:
    """``notebooks/05_protores.ipynb`` -> ``"05"`` (the notebook's name when it has no number)."""
    name = Path(notebook).name if notebook else ""
    m = re.match(r"(\d+)_", name)
    return m.group(1) if m else Path(name).stem


def _check(n_cases, starts, effectors) -> tuple:
    """The run's start conditions and effector sets, refused before any work with a sentence that says why."""
    if isinstance(n_cases, bool) or int(n_cases) != n_cases or int(n_cases) < 1:
        raise ValueError(f"cases must be a whole number of at least 1, got {n_cases!r}")
    names = starts.split(",") if isinstance(starts, str) else list(starts)
    names = tuple(dict.fromkeys(start_condition(n.strip()) for n in names if n.strip()))  # raises on unknown names
    if not names:
        raise ValueError(f"no start condition given; valid: {', '.join(START_CONDITIONS)}")
    return names, effector_set_names(effectors)


def _fall_back(motions, data: str, starts: tuple, seed: int) -> tuple:
    """``starts`` with ``other-clip`` replaced by ``same-clip`` (and a warning saying so) when the held-out frames
    of ``motions`` come from fewer than two clips, as with a one-clip data set (where ``posekit bench ik`` holds out
    the end of every clip): a start from another held-out clip cannot be drawn there."""
    if "other-clip" not in starts:
        return starts
    from ..data.cases import held_out_clips

    with warnings.catch_warnings():  # the split's own warning comes once, from the cases
        warnings.simplefilter("ignore")
        n = held_out_clips(motions, seed)
    if n >= 2:
        return starts
    kept = tuple(dict.fromkeys("same-clip" if s == "other-clip" else s for s in starts))
    warnings.warn(f"bench all: {data!r} has {n} held-out clip(s), too few for the other-clip start (a frame of "
                  f"another held-out clip); measuring from same-clip instead, as --start {','.join(kept)} would",
                  UserWarning, stacklevel=3)
    return kept


def run(n_cases: int = 200, starts=("rest", "other-clip"), effectors=("2", "5", RANDOM), seed: int = 0, out=None,
        progress: bool = True, data: str | None = None) -> list[dict]:
    """Benchmark every registered solver on the same held-out cases; one row per solver and start condition.

    Parameters
    ----------
    n_cases : int
        Held-out (start, target) cases per start condition (the same targets under every start).
    starts : str or sequence of str
        Start conditions (comma-separated or a sequence): ``same-clip``, ``other-clip``, ``rest``.
    effectors : str or sequence of str
        Effector sets (comma-separated or a sequence; :data:`posekit.bench.ik.EFFECTOR_CHOICES`): ``2``, ``5``,
        ``5point``, ``random``.
    seed : int
        Seed of the case draw and of the naturalness index (:func:`posekit.bench.ik.run`).
    out : str, Path or None
        A folder to write :data:`FILES` into (created if missing); None writes nothing.
    progress : bool
        A progress bar (one step per solver and start condition).
    data : str, optional
        The data set (a shipped set's name, a BVH file or folder); default the one the learned solvers were
        trained on (:func:`posekit.bench.ik.default_data`). Learned solvers made for another skeleton are left
        out (``meta["skipped"]``); with :func:`posekit.paths.use_weights` the user's own models are measured.

    Returns
    -------
    list of dict
        The :data:`KEYS` of each row, sorted by effector set and start condition (in the order given), then
        by MPJPE.
        ``lesson`` is the number of the notebook that introduces the solver, ``kinds`` the effector kinds
        it honours; times in ms, distances in mm, ``converged_fraction`` in [0, 1].

    Raises
    ------
    ValueError
        For ``n_cases < 1``, an unknown start condition or an unknown effector set (before any work). A data set
        whose held-out frames come from one clip is measured from ``same-clip`` instead of ``other-clip``, with a
        warning.
        A solver that refuses a set's effectors is left out of that set (``meta["refused"]``), not an error.
    """
    from ..data.sources import open_dataset

    starts, sets = _check(n_cases, starts, effectors)
    from ..paths import user_weights_dir

    names = resolve_solvers("all")
    named = data is not None
    data = default_data(names) if data is None else str(data)
    t0 = time.perf_counter()
    motions = open_dataset(data)
    starts = _fall_back(motions, data, starts, int(seed))
    refused = {}
    with warnings.catch_warnings():  # the refusals go into the report instead
        warnings.filterwarnings("ignore", message="bench ik: not measured")
        raw = run_ik(motions, solvers="all", effector_sets=sets, n_cases=int(n_cases), start=starts,
                     seed=int(seed), baseline=False, batched=False, peers=False, methods="none", natural=True,
                     progress=progress, refused=refused)
    seconds = time.perf_counter() - t0
    rows = []
    for r in raw:
        info = solver_info(r["method"])
        row = {"method": r["method"], "start": r["start"], "effectors": r["effectors"],
               "lesson": _lesson(info.lesson), "kinds": ", ".join(info.kinds)}
        for k, digits in _DIGITS.items():
            v = r.get(k)
            row[k] = None if v is None else round(float(v), digits)
        row["cases"] = int(r["cases"])
        row["refused_cases"], row["refused_reason"] = int(r.get("refused_cases") or 0), r.get("refused_reason")
        row["finish_rule"] = r.get("finish_rule")
        row["data"] = data
        rows.append(row)
    rows.sort(key=lambda r: (sets.index(r["effectors"]), starts.index(r["start"]), r["mpjpe_mm_median"], r["method"]))
    if out is not None:
        floors = {}
        for r in raw:
            floors.setdefault(r["start"], round(float(r["natural_floor_mm_median"]), 3))
        meta = {"benchmark": "all",
                "command": (f"posekit bench all --cases {int(n_cases)} --start {','.join(starts)} "
                            f"--effectors {','.join(sets)} --seed {int(seed)}"
                            + (f" --data {data}" if named else "")
                            + (f" --weights {user_weights_dir()}" if user_weights_dir() is not None else "")),
                "cases": int(n_cases), "starts": list(starts), "effectors": list(sets),
                "effector_roles": {e: list(EFFECTOR_SETS[e]) for e in sets if e in EFFECTOR_SETS},
                "seed": int(seed), "data": data, "threads": 1,
                "solvers": list(names), "skipped": [n for n in names if n not in {r["method"] for r in rows}],
                "refused": {f"{n} / {e}": why for (n, e), why in refused.items()},
                "refused_cases": {f"{r['method']} / {r['effectors']} / {r['start']}":
                                  {"cases": r["refused_cases"], "of": r["cases"], "reason": r["refused_reason"]}
                                  for r in rows if r["refused_cases"]},
                "natural_floor_mm_median": floors, "seconds": round(seconds, 1), "machine": machine(),
                "date": today()}
        write_report(rows, meta, out)
    return rows


def write_report(rows: list[dict], meta: dict, out) -> list[Path]:
    """Write ``bench_all.json`` (``{**meta, "rows": rows}``), ``bench_all.md`` and ``bench_all.png`` into ``out``.

    Parameters
    ----------
    rows : list of dict
        :func:`run`'s rows.
    meta : dict
        How they were made (at least ``command``, ``cases``, ``starts``, ``effectors``, ``data``, ``machine``).
    out : str or Path
        The folder (created if missing).

    Returns
    -------
    list of Path
        The three files.
    """
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / f for f in FILES]
    paths[0].write_text(json.dumps({**meta, "rows": rows}, indent=1) + "\n")
    paths[1].write_text(markdown(rows, meta))
    plot(rows, meta, paths[2])
    return paths


# ------------------------------------------------------------------------------------------- the report
def _ms(v: float) -> str:
    return f"{v:.0f}" if v >= 100 else f"{v:.1f}" if v >= 10 else f"{v:.2f}" if v >= 1 else f"{v:.3f}"


def _mm(v) -> str:
    return "" if v is None else f"{v:.2f}" if v < 10 else f"{v:.1f}"


EXACT = 0.99
"""A solver "meets its effectors" in a report cell when at least this share of the cases converged."""

SET_TEXT = {"2": "two hands", "5": "hands, feet and head", "5point": "chest, hands and feet",
            RANDOM: ("6-12 effectors of three kinds: a position on one joint of each main zone (legs, arms, hips, "
                     "head), the rest positions, rotations and look-ats on random body joints (lesson 05's "
                     "random benchmark rule, drawn on these cases)")}
"""What each effector set asks for, in words."""


def _columns(angular: bool, refused: bool = False, kept: bool = False) -> tuple:
    return ("solver", "lesson", "ms per solve", "MPJPE mm", "effector mm") + (("effector deg",) if angular else ()) \
        + ("natural mm", "converged") + (("refused",) if refused else ()) + (("learned kept",) if kept else ())


def _table(rows: list[dict]) -> str:
    angular = any(r.get("effector_error_deg_median") is not None for r in rows)
    refused = any(r.get("refused_cases") for r in rows)
    kept = any(r.get("learned_kept_fraction") is not None for r in rows)
    cols = _columns(angular, refused, kept)
    lines = ["| " + " | ".join(cols) + " |", "|:--|:-:|" + "--:|" * (len(cols) - 2)]
    for r in sorted(rows, key=lambda r: (r["mpjpe_mm_median"], r["method"])):
        cells = [f"`{r['method']}`", r["lesson"], _ms(r["latency_ms_median"]), f"{r['mpjpe_mm_median']:.1f}",
                 _mm(r["effector_error_mm_median"])]
        if angular:
            deg = r.get("effector_error_deg_median")
            cells.append("n/a" if deg is None or deg != deg else f"{deg:.2f}" if deg < 10 else f"{deg:.1f}")
        cells += [_mm(r["natural_mm_median"]), f"{100 * r['converged_fraction']:.0f}%"]
        if refused:
            cells.append(f"{r.get('refused_cases') or 0} of {r['cases']}")
        if kept:
            k = r.get("learned_kept_fraction")
            cells.append("" if k is None else f"{100 * k:.0f}%")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def winners(rows: list[dict], sets, starts) -> list[dict]:
    """Who wins where: per effector set and start condition, the solver with the closest pose (lowest median
    MPJPE), the closest among those that meet their effectors (converged in at least :data:`EXACT` of the
    cases), and plain DLS's and FABRIK's rows for reference (None when absent)."""
    out = []
    for e in sets:
        for st in starts:
            cell = [r for r in rows if r["effectors"] == e and r["start"] == st]
            if not cell:
                continue
            best = min(cell, key=lambda r: (r["mpjpe_mm_median"], r["method"]))
            exact = [r for r in cell if r["converged_fraction"] >= EXACT]
            by = {r["method"]: r for r in cell}
            out.append({"effectors": e, "start": st, "closest": best,
                        "closest_exact": min(exact, key=lambda r: (r["mpjpe_mm_median"], r["method"])) if exact else None,
                        "dls": by.get("dls"), "fabrik": by.get("fabrik")})
    return out


def _cell(r) -> str:
    if r is None:
        return "—"
    return f"`{r['method']}` {r['mpjpe_mm_median']:.1f} mm, {100 * r['converged_fraction']:.0f}%, {_ms(r['latency_ms_median'])} ms"


def _winners_table(rows, sets, starts) -> str:
    lines = ["| effectors | start | closest pose | closest that meets its effectors | `dls` | `fabrik` |",
             "|:-:|:--|:--|:--|:--|:--|"]
    for w in winners(rows, sets, starts):
        lines.append(f"| `{w['effectors']}` | {w['start']} | {_cell(w['closest'])} | {_cell(w['closest_exact'])} | "
                     f"{_cell(w['dls'])} | {_cell(w['fabrik'])} |")
    return "\n".join(lines)


def _sets(meta) -> list:
    e = meta["effectors"]
    return [e] if isinstance(e, str) else list(e)


def markdown(rows: list[dict], meta: dict) -> str:
    """The report ``bench_all.md``: how the numbers were measured, who wins where, a table per effector set
    and start condition (sorted by MPJPE) and a paragraph on reading ``bench_all.png``."""
    starts, sets = list(meta["starts"]), _sets(meta)
    solvers = list(dict.fromkeys(r["method"] for r in rows))
    floors = meta.get("natural_floor_mm_median", {})
    floor = next(iter(floors.values()), None)
    m = meta["machine"]
    set_list = "; ".join(f"`{e}`, {SET_TEXT.get(e, ', '.join(EFFECTOR_SETS.get(e, ())))}" for e in sets)
    out = ["# Every posekit IK solver on the same cases", "",
           f"Made by `{meta['command']}` (rows: `bench_all.json`; figure: `bench_all.png`). "
           "The numbers come from `posekit bench ik`'s cases and metric code.", "",
           f"**What was measured.** {len(solvers)} registered solvers, each on the same {meta['cases']} held-out "
           f"cases of `{meta['data']}` per start condition ({', '.join(f'`{s}`' for s in starts)}) and effector "
           f"set ({set_list}). A case's target is a real pose of a test clip; the effectors are placed at it "
           "(positions, rotations and look-ats of the true pose), the solver gets the effectors of the kinds it "
           "honours and the case's start pose, is scored on every effector, and is timed one solve at a time on "
           "one thread after a warm-up solve, in the thread's CPU time (other work's turns on a shared core left "
           "out).", "",
           "**Columns** (medians over the cases): *ms per solve*; *MPJPE mm*, the mean distance of the body "
           "joints to the true pose's, pelvis-relative; *effector mm*, the worst position effector of a case"
           + ("; *effector deg*, the worst rotation or look-at effector (n/a: the solver returns no rotations)"
              if RANDOM in sets else "")
           + "; *natural mm*, the distance to the nearest training pose"
           + (f" (the true poses' own: {floor:.1f} mm)" if floor is not None else "")
           + "; *converged*, the share of cases with every effector within its tolerance (1 mm, 1 degree)"
           + ("; *refused*, the cases the solver refused (counted as not converged; the other columns are over the "
              "cases it solved)" if any(r.get("refused_cases") for r in rows) else "")
           + _kept_text(rows, meta)
           + ". *lesson*: the notebook that introduces the solver.", "",
           f"Machine: {m['platform']}, {m['processor']}, {m['cpu_count']} CPUs"
           + (f"; made on {meta['date']}" if meta.get("date") else "") + "; the run took "
           + f"{meta.get('seconds', float('nan')) / 60:.1f} min. Times depend on the machine and its load; "
           "the errors do not (same seed, same numbers)."]
    if meta.get("skipped"):
        out += ["", "Not measured (the solver refused this data): "
                + ", ".join(f"`{n}`" for n in meta["skipped"]) + "."]
    refused = meta.get("refused") or {}
    if refused:
        by_set = {}
        for key in refused:
            n, e = key.split(" / ")
            by_set.setdefault(e, []).append(n)
        reason = next(iter(refused.values()))
        out += ["", "Not measured on a set (the solver refused its effectors): "
                + "; ".join(f"`{e}`: " + ", ".join(f"`{n}`" for n in ns) for e, ns in by_set.items())
                + f". The first refusal said: \"{reason[:300]}{'...' if len(reason) > 300 else ''}\""]
    partly = meta.get("refused_cases") or {}
    if partly:
        first = next(iter(partly.values()))
        out += ["", "Cases refused (counted in *refused*, not scored): "
                + "; ".join(f"`{k.split(' / ')[0]}` {v['cases']} of {v['of']} (`{k.split(' / ')[1]}`, "
                            f"{k.split(' / ')[2]})" for k, v in partly.items())
                + f". The first refusal said: \"{(first['reason'] or '')[:300]}\""]
    out += ["", "## Who wins where", "",
            f"Per effector set and start: the closest pose of any solver, the closest of those that meet their "
            f"effectors (converged in at least {100 * EXACT:.0f}% of the cases), and plain DLS and FABRIK "
            "(MPJPE, converged, ms per solve).", "", _winners_table(rows, sets, starts)]
    said = verdicts(rows, sets, starts)
    if said:
        out += ["", "Learned solvers against plain DLS and FABRIK (median MPJPE, shown to 0.1 mm: a tie is not "
                "closer):", ""] + [f"- {v}" for v in said]
    for e in sets:
        for st in starts:
            cell = [r for r in rows if r["effectors"] == e and r["start"] == st]
            if cell:
                out += ["", f"## Effectors {e}, start {st} — {START_CONDITIONS.get(st, st)}", "", _table(cell)]
    out += ["", "## Reading the scatter", "", "![time per solve against MPJPE](bench_all.png)", "",
            _reading(rows, starts, sets)]
    return "\n".join(out) + "\n"


def _kept_text(rows: list[dict], meta: dict) -> str:
    """The *learned kept* column's definition, saying how the finishes chose — a naturalness comparison only where
    one ran (``finish_rule``)."""
    finished = [r for r in rows if r.get("learned_kept_fraction") is not None]
    if not finished:
        return ""
    text = ("; *learned kept*, for a learned solver with an exact finish (`+dls`), the share of cases whose answer "
            "is DLS's from the learned pose — in the rest DLS from the start pose gave the answer kept and the "
            "learned pose was discarded")
    rules = {r.get("finish_rule") for r in finished}
    natural = sorted({r["method"] for r in finished if r.get("finish_rule") == "natural"})
    learned = sorted({r["method"] for r in finished if r.get("finish_rule") == "learned"})
    if rules == {"natural"}:
        return text + (f" (the more natural of two exact answers: nearer a training pose of `{meta['data']}`'s "
                       "training split; or the only exact one)")
    if natural:
        text += (" (" + ", ".join(f"`{n}`" for n in natural) + f": the more natural of two exact answers, nearer a "
                 f"training pose of `{meta['data']}`'s training split, or the only exact one)")
    if learned:
        text += (" (" + ", ".join(f"`{n}`" for n in learned) + ": no naturalness comparison ran, no training poses "
                 "of this skeleton; the start's answer only where DLS got stuck from the learned pose)")
    return text


def _reading(rows: list[dict], starts: list, sets: list) -> str:
    text = ("One panel per effector set (rows) and start condition (columns); a row's panels share their axes, so "
            "a solver sits at the same place in both when its start does not matter. Each point is one solver. Left "
            "is faster and lower is closer to the true pose (both axes log: equal steps are equal ratios), so the "
            "useful solvers sit on the lower-left edge, drawn filled and joined, where no other solver is both "
            "faster and closer: ")
    fronts = []
    for e in sets:
        for st in starts:
            cell = [r for r in rows if r["start"] == st and r["effectors"] == e]
            if cell:
                fronts.append(f"`{e}` from `{st}`, "
                              + ", ".join(f"`{r['method']}` ({_ms(r['latency_ms_median'])} ms, "
                                          f"{r['mpjpe_mm_median']:.1f} mm)" for r in pareto(cell)))
    text += "; ".join(fronts) + ". "
    free = []
    for n in dict.fromkeys(r["method"] for r in rows):
        if solver_info(n).needs_start:
            continue
        if all(len({r["mpjpe_mm_median"] for r in rows if r["method"] == n and r["effectors"] == e}) <= 1
               for e in sets):
            free.append(n)
    if free and len(starts) > 1:
        text += (f"Solvers that predict a whole pose without a start pose ({', '.join(f'`{n}`' for n in free)}) "
                 "give the same MPJPE under every start: they sit at the same height in every column of a row. ")
    text += ("A solver that moves up or down from one column to the next depends on where it starts. MPJPE and "
             "*effector mm* tell "
             "different stories: the effectors do not determine the pose, so a solver can meet every effector "
             "(converged) and still be far from the true pose, and a learned solver can land close to it while "
             "missing the effectors by centimetres.")
    return text


# ------------------------------------------------------------------------------------------- the figure
def _out(value):
    """``--out``: None (not given) -> :func:`default_out`; ``""``, ``none``, ``false`` or ``-`` -> write nothing."""
    if value is None:
        return default_out()
    if str(value).strip().lower() in ("", "none", "false", "-"):
        return None
    return Path(value)


def _cli_run(args) -> list[dict]:

    from .ik import weights_and_data

    _check(args.cases, args.start, args.effectors)  # refuse before loading anything
    weights, data = weights_and_data(args, resolve_solvers("all"))
    with weights:
        return run(n_cases=args.cases, starts=args.start, effectors=args.effectors, seed=args.seed,
                   out=_out(args.out), progress=True, data=data)


def _header(rows, args) -> str:
    data = rows[0]["data"] if rows else "bandai-mini"
    out = _out(args.out)
    files = f"report: {out / FILES[1]} (and .json, .png)" if out is not None else "report: not written (--out none)"
    return (f"Every registered IK solver: {data}, {args.cases} held-out cases per start condition (the same "
            f"targets), effector sets {args.effectors}, one thread; {files}\n"
            "errors in mm and degrees; MPJPE and natural: body joints, pelvis-relative; effector: the worst of a "
            "case; converged: every effector within its tolerance (1 mm, 1 degree); sorted by MPJPE")


TABLES = [("Speed and quality (medians over cases)",
           ["method", "effectors", "latency_ms_median", "mpjpe_mm_median", "effector_error_mm_median",
            "effector_error_deg_median", "natural_mm_median", "converged_fraction"]), IK_TABLES[-1]]
"""The table ``posekit bench all`` prints per start condition (fits 100 columns)."""

register_benchmark(
    "all", _cli_run,
    help="every registered IK solver on the same held-out cases: tables, a Markdown report and a speed/quality "
         "scatter",
    args=[
        arg("--cases", type=int, default=200, help="held-out (start, target) cases per start condition"),
        arg("--start", default="rest,other-clip",
            help="comma-separated start conditions: " + ", ".join(START_CONDITIONS)),
        arg("--effectors", default="2,5,random",
            help="comma-separated effector sets: 2 (hands), 5 (hands, feet, head), 5point (hands, feet, chest), "
                 "random (6-12 effectors of three kinds, lesson 05's rule)"),
        arg("--seed", type=int, default=0, help="seed of the case draw"),
        arg("--data", default=None,
            help="sample, bandai-mini, bandai1, bandai2, or a BVH file/folder (default: the data the shipped learned "
                 "solvers were trained on, bandai-mini); learned solvers made for another skeleton are skipped"),
        arg("--weights", default=None, help=WEIGHTS_HELP),
        arg("--out", default=None,
            help="folder for bench_all.json, .md and .png (default: data_samples/results; none or '': "
                 "do not write)"),
    ],
    tables=TABLES, labels={**TABLE_LABELS, "lesson": "lesson", "method": "solver"}, header=_header,
    group_by="start", group_title=_group_title, footer=verdict_footer, lesson="notebooks/06_posing_studio.ipynb")
