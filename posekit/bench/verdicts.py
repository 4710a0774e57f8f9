"""Where learned solvers lose, in words: one sentence per effector set and start condition of a benchmark's rows,
saying whether any learned solver (lessons 03-05, their exact finishes) lands closer to the true pose than plain DLS
and FABRIK, and which learned solver is closest.

``posekit bench ik`` prints these sentences under its tables, ``posekit bench all`` under its tables and in
``bench_all.md`` (introduced in ``notebooks/06_posing_studio.ipynb``), and the benchmarks page
(``posekit docs build``) beside the shipped report. *Closer* compares median MPJPE (:mod:`posekit.bench.ik`) as
the tables show it, to 0.1 mm: a tie is not closer.
"""

from __future__ import annotations

from ..ik.registry import solver_info, solver_names

__all__ = ["verdicts", "footer"]

CLASSICAL = ("dls", "fabrik")
"""The plain solvers every learned one is held against."""


def _learned(name: str) -> bool:
    """Whether ``name`` is a registered solver with weights trained on data (lessons 03-05 and their finishes)."""
    return name in solver_names() and bool(solver_info(name).data)


def verdicts(rows: list[dict], sets=None, starts=None, mark=None) -> list[str]:
    """One sentence per effector set and start condition that holds learned solvers and plain DLS or FABRIK: whether
    a learned solver lands closer to the true pose (median MPJPE, shown to 0.1 mm: a tie is not closer) than the
    better of DLS and FABRIK, and which learned solver is closest (with how often an exact finish kept its learned
    pose). Cells without a learned solver, or without DLS and FABRIK, get none. ``mark(row, key)``, when given,
    returns the text written right after each figure (the benchmarks page's source marker,
    :mod:`posekit.docs.prose`)."""
    mark = mark or (lambda row, key: "")
    sets = list(dict.fromkeys(r["effectors"] for r in rows)) if sets is None else list(sets)
    starts = list(dict.fromkeys(r["start"] for r in rows)) if starts is None else list(starts)
    out = []
    for e in sets:
        for st in starts:
            cell = [r for r in rows if r["effectors"] == e and r["start"] == st
                    and r.get("mpjpe_mm_median") is not None]
            classic = [r for r in cell if r["method"] in CLASSICAL]
            learned = sorted((r for r in cell if _learned(r["method"])),
                             key=lambda r: (r["mpjpe_mm_median"], r["method"]))
            if not classic or not learned:
                continue
            ref = min(classic, key=lambda r: (r["mpjpe_mm_median"], r["method"]))
            bar = round(ref["mpjpe_mm_median"], 1)
            ahead = [r for r in learned if round(r["mpjpe_mm_median"], 1) < bar]
            best = learned[0]
            kept = best.get("learned_kept_fraction")
            kept = (f", keeping its learned pose in {100 * kept:.0f}%{mark(best, 'learned_kept_fraction')} of the "
                    "cases" if kept is not None else "")
            refs = " and ".join(f"`{r['method']}` ({r['mpjpe_mm_median']:.1f} mm{mark(r, 'mpjpe_mm_median')})"
                                for r in sorted(classic, key=lambda r: (r["mpjpe_mm_median"], r["method"])))
            closest = f"{best['mpjpe_mm_median']:.1f} mm{mark(best, 'mpjpe_mm_median')}{kept}"
            if ahead:
                out.append(f"Effectors `{e}` from {st}: {len(ahead)} of {len(learned)} learned solvers "
                           f"{'lands' if len(ahead) == 1 else 'land'} closer "
                           f"to the true pose than {refs}; the closest is `{best['method']}`, "
                           f"{closest}.")
            else:
                out.append(f"Effectors `{e}` from {st}: no learned solver lands closer to the true pose than {refs}; "
                           f"the closest learned one is `{best['method']}`, {closest}.")
    return out


def footer(rows: list[dict], args=None) -> str:
    """The sentences of :func:`verdicts` as a paragraph under a benchmark's text tables (empty when none)."""
    said = verdicts(rows)
    if not said:
        return ""
    return "Learned solvers against plain DLS and FABRIK (median MPJPE to 0.1 mm):\n" + "\n".join(said)
