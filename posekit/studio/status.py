"""What the studio says about a solve, as text: each view's status, the summary's rows, a reached mark.

Introduced in ``notebooks/01_fabrik.ipynb`` (the panel's labels) and ``notebooks/06_posing_studio.ipynb`` (the
studio's *All solvers* table). Plain HTML strings, no widgets: :class:`~posekit.studio.session.PosingSession`
decides them and the views (:mod:`posekit.viz.compare`) only show them. With no effectors every text says so —
nothing is called reached that was not solved.
"""

from __future__ import annotations

import html

import numpy as np

__all__ = ["NO_EFFECTORS", "NO_EFFECTORS_SUMMARY", "kinds_text", "reached_mark", "worst_errors", "status_table",
           "status_line", "view_status", "summary_rows"]

NO_EFFECTORS = "add an effector"
"""A view's status with no effectors: nothing was solved."""
NO_EFFECTORS_SUMMARY = "no effectors: nothing solved (add one)"
"""The summary's row for each solver with no effectors."""


def _error(text: str) -> str:
    return f"<span style='color:#b03a2e'>{html.escape(text)}</span>"


def kinds_text(kinds) -> str:
    """Effector kinds as a person writes them, each once, in order: ``"rotation, look-at"``."""
    return ", ".join(dict.fromkeys(k.replace("_", "-") for k in kinds))


def reached_mark(result, ignored=()) -> str:
    """Whether a solver reached its effectors, as HTML: ``"✓ reached"``, ``"✗ not reached"``, or with effectors it
    ignored (not given, their kind not honoured) ``"◐ 3 of 5 reached · look-at, rotation ignored"`` — never a
    ✓ then, since an ignored effector is unmet."""
    if not ignored:
        return "✓ reached" if result.converged else "✗ not reached"
    used = len(result.effector_error)
    mark = f"◐ {used} of {used + len(ignored)} reached" if result.converged else "✗ not reached"
    return mark + f" · <span style='color:#b9770e'>{kinds_text(e.kind for e in ignored)} ignored</span>"


def worst_errors(result, joints=None, sep: str = ", ") -> str:
    """A result's worst effector errors as text: mm for positions, degrees for rotation and look-at effectors
    (each when there are any), each followed by its joint when ``joints`` (one name per effector, in the
    result's order) is given, e.g. ``"2.1 mm (Hand_L), 0.7° (Head)"``; ``sep`` joins the two."""
    err = np.asarray(result.effector_error, dtype=float)
    kinds = tuple(result.kinds or ("position",) * len(err))
    angular = np.array([k != "position" for k in kinds], dtype=bool)
    parts = []
    for mask, scale, unit in ((~angular, 1000.0, " mm"), (angular, None, "°")):
        if mask.any():
            k = int(np.flatnonzero(mask)[np.argmax(err[mask])])
            value = err[k] * scale if scale else np.degrees(err[k])
            parts.append(f"{value:.1f}{unit}" + (f" ({html.escape(str(joints[k]))})" if joints is not None else ""))
    return sep.join(parts)


def status_table(title: str, rows) -> str:
    """A title over an HTML table of ``(label, value, ...)`` rows. Two-cell rows: the value right-aligned. Rows of
    more cells (the studio's summary: name, mark, errors, time) keep each column aligned: the second cell left, the
    others right-aligned in monospace; a shorter row's last cell spans the columns it lacks."""
    width = max((len(r) for r in rows), default=2)

    def cells(row):
        out = [f"<td style='padding-right:10px'>{row[0]}</td>"]
        for k, value in enumerate(row[1:], start=1):
            span = width - len(row) + 1 if k == len(row) - 1 else 1
            left = width > 2 and (k == 1 or span > 1)
            style = "padding-right:10px" + ("" if left else ";text-align:right;font-family:monospace")
            out.append(f"<td{f' colspan={span}' if span > 1 else ''} style='{style}'>{value}</td>")
        return "".join(out)

    body = "".join(f"<tr>{cells(row)}</tr>" for row in rows)
    return f"{title}<table style='border-collapse:collapse'>{body}</table>"


def status_line(result, ms: float, joints=None, ignored=()) -> str:
    """One solver's status under its view, as a small HTML table: reached or not, the worst effector error and its
    joint, iterations and time (ms). ``ignored``: effectors the solver was not given because it does not honour
    their kind — the view says so and never calls them reached."""
    it = result.iterations
    excluded = f"<br>{kinds_text(e.kind for e in ignored)} not measured" if ignored else ""
    return status_table(f"<b>{reached_mark(result, ignored)}</b>",
                        [("worst effector", worst_errors(result, joints, sep="<br>") + excluded),
                         (f"iteration{'' if it == 1 else 's'}", str(it)), ("time", f"{ms:.2f} ms")])


def view_status(name: str, solver, solved, effectors, joints) -> str:
    """The status under solver ``name``'s view after a solve (:class:`~posekit.studio.solve.Solved` ``solved``
    of ``effectors``, whose joint names are ``joints``)."""
    if not effectors:
        return NO_EFFECTORS
    res = solved.result
    if res is None:
        return (f"<b>nothing to solve</b><br>{html.escape(name)} honours {kinds_text(solver.kinds)} effectors only: "
                f"{kinds_text(e.kind for e in solved.ignored)} ignored")
    if isinstance(res, Exception):
        what = "" if isinstance(res, ValueError) else f"{type(res).__name__}: "
        return f"<b>✗ cannot solve</b><br>{html.escape(what + str(res))}"
    return status_line(res, solved.ms, [joints[k] for k in solved.used], solved.ignored)


def summary_rows(solved: dict, effectors) -> list:
    """The summary's rows, one per solver (``solved``: name -> :class:`~posekit.studio.solve.Solved` of the last
    solve): name, mark, worst errors, time; with no effectors each row says nothing was solved."""
    rows = []
    for name, s in solved.items():
        res, label = s.result, html.escape(name)
        if not effectors:
            rows.append((label, NO_EFFECTORS_SUMMARY))
        elif res is None:
            rows.append((label, "nothing to solve · <span style='color:#b9770e'>"
                         f"{html.escape(kinds_text(e.kind for e in s.ignored))} ignored</span>"))
        elif isinstance(res, Exception):
            rows.append((label, _error(f"failed: {res}")))
        else:
            rows.append((label, reached_mark(res, s.ignored), worst_errors(res), f"{s.ms:.2f} ms"))
    return rows
