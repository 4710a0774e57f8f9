"""Printing benchmark rows as aligned text tables or as JSON.

Every ``posekit bench`` command prints its rows through :func:`format_table`; tables are kept
under 100 columns by short headers (``labels``) and by splitting wide results into several tables
(:func:`format_tables`).
"""

from __future__ import annotations

import json

__all__ = ["format_table", "format_tables", "to_json"]


def _cell(v) -> str:
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, float):
        return f"{v:,.3g}" if abs(v) < 1000 else f"{v:,.0f}"
    if isinstance(v, int):
        return f"{v:,}" if abs(v) >= 10_000 else str(v)
    return "" if v is None else str(v)


def format_table(rows: list[dict], columns: list[str] | None = None, labels: dict | None = None) -> str:
    """Rows of dicts as an aligned text table (floats with 3 significant digits).

    Parameters
    ----------
    rows : list of dict
    columns : list of str, optional
        Keys to show, in order (default: the first row's keys). Columns empty in every row are dropped.
    labels : dict, optional
        Key -> short header (default: the key itself).
    """
    if not rows:
        return "(no rows)"
    columns = [c for c in (columns or list(rows[0])) if any(r.get(c) is not None for r in rows)]
    labels = labels or {}
    table = [[labels.get(c, c) for c in columns]] + [[_cell(r.get(c)) for c in columns] for r in rows]
    widths = [max(len(row[i]) for row in table) for i in range(len(columns))]
    lines = ["  ".join(v.ljust(w) for v, w in zip(row, widths)).rstrip() for row in table]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def _selects(where, row: dict) -> bool:
    if callable(where):
        return bool(where(row))
    return all(row.get(k) == v for k, v in where.items())


def format_tables(rows: list[dict], tables: list[tuple], labels: dict | None = None) -> str:
    """Several tables over the same rows: ``tables`` is a list of (title, columns) or
    (title, columns, where). A row enters a table when ``where`` selects it (a dict of required
    values, or a predicate), or, without ``where``, when it has a value in one of the table's
    columns besides the first two (the row's name)."""
    out = []
    for title, columns, *where in tables:
        if where and where[0] is not None:
            keep = [r for r in rows if _selects(where[0], r)]
        else:
            keep = [r for r in rows if any(r.get(c) is not None for c in columns[2:])]
        if keep:
            out.append(f"{title}\n{format_table(keep, columns, labels)}")
    return "\n\n".join(out)


def to_json(rows: list[dict]) -> str:
    """Rows as indented JSON."""
    return json.dumps(rows, indent=2)
