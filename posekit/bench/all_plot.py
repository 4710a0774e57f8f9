"""The speed/quality scatter of ``posekit bench all``: one panel per effector set and start condition, one
labelled point per solver.

Introduced in ``notebooks/06_posing_studio.ipynb`` with :mod:`posekit.bench.all`, which writes it as
``bench_all.png``: median time per solve (ms) against median MPJPE (mm), both log, in the spirit of Fig. 5
of Victor et al. 2021. Rows are the effector sets, columns the start conditions, so a panel holds one point per
solver (about 20 labels, not twice that); the panels of a row share both axes, so a solver's two starts are read
at the same place. The lower-left edge (:func:`pareto`: no solver both faster and closer) is
drawn filled and joined; :func:`_label_points` places the solver names so that they overlap neither the points nor
each other, with a margin between labels; solvers whose points coincide share one label.
"""

from __future__ import annotations

import numpy as np

__all__ = ["plot", "pareto", "DPI", "LABEL_GAP_PX", "label_groups"]

DPI = 150
"""Resolution of the saved scatter, dots per inch."""

_STYLE = {"same-clip": ("o", "C0"), "other-clip": ("s", "C2"), "rest": ("^", "C3")}


def pareto(rows: list[dict]) -> list[dict]:
    """The rows no other row beats on both speed and MPJPE (no row is both faster and closer), fastest first."""
    xy = [(r["latency_ms_median"], r["mpjpe_mm_median"]) for r in rows]
    front = [r for r, (x, y) in zip(rows, xy) if not any(a <= x and b <= y and (a, b) != (x, y) for a, b in xy)]
    return sorted(front, key=lambda r: r["latency_ms_median"])


def plot(rows: list[dict], meta: dict, path=None):
    """The speed/quality scatter: median ms per solve against median MPJPE mm (both log), one panel per effector
    set (row) and start condition (column), one labelled point per solver; a row's panels share both axes.
    Rendered with Agg at :data:`DPI`; saved to ``path`` when given.

    Returns
    -------
    matplotlib.figure.Figure
        Its axes in row-major order (effector set, then start).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    sets = [meta["effectors"]] if isinstance(meta["effectors"], str) else list(meta["effectors"])
    sets = [e for e in sets if any(r.get("effectors", e) == e for r in rows)] or sets[:1]
    starts = [st for st in meta["starts"] if any(r["start"] == st for r in rows)] or list(meta["starts"])[:1]
    fig = Figure(figsize=(7.2 * len(starts), 5.6 * len(sets)), dpi=DPI)
    FigureCanvasAgg(fig)
    colours = {st: _STYLE.get(st, ("D", f"C{4 + i}"))[1] for i, st in enumerate(starts)}
    grid = []
    for i, e in enumerate(sets):
        of_set = [r for r in rows if r.get("effectors", e) == e]
        for k, st in enumerate(starts):
            ax = fig.add_subplot(len(sets), len(starts), i * len(starts) + k + 1)
            _panel(ax, [r for r in of_set if r["start"] == st], of_set, st, meta, e, k)
            grid.append((ax, [r for r in of_set if r["start"] == st]))
    fig.tight_layout()
    for ax, mine in grid:
        _label_points(fig, ax, mine, colours)
    if path is not None:
        fig.savefig(path, dpi=DPI)
    return fig


def _panel(ax, rows: list[dict], row_of_set: list[dict], start: str, meta: dict, effectors: str, column: int) -> None:
    """One effector set and start's scatter on ``ax``: its points (the lower-left edge filled and joined), axes
    spanning every start of the set (``row_of_set``) so the row's panels compare, a title naming both."""
    from matplotlib.lines import Line2D
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    marker, colour = _STYLE.get(start, ("D", f"C{4 + column}"))
    front = pareto(rows) if rows else []
    on = {id(r) for r in front}
    rest = [r for r in rows if id(r) not in on]
    ax.scatter([r["latency_ms_median"] for r in rest], [r["mpjpe_mm_median"] for r in rest], s=30, marker=marker,
               facecolors="white", edgecolors=colour, linewidths=1.1, zorder=3)
    ax.plot([r["latency_ms_median"] for r in front], [r["mpjpe_mm_median"] for r in front], color=colour, lw=1.0,
            alpha=0.6, zorder=2)
    ax.scatter([r["latency_ms_median"] for r in front], [r["mpjpe_mm_median"] for r in front], s=34, marker=marker,
               color=colour, zorder=3)
    ax.set_xscale("log")
    ax.set_yscale("log")  # both log: equal steps are equal ratios (twice as fast, half the error)
    # x spans decades (1, 2, 5 per decade); y spans less than one or two, so it is labelled at 1-1.5-2-3-...-8:
    # values such as 67.8 and 75.8 mm can be read off the grid
    for axis, subs in ((ax.xaxis, (1.0, 2.0, 5.0)), (ax.yaxis, (1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0))):
        axis.set_major_locator(LogLocator(base=10, subs=subs))
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(NullFormatter())
    x = np.array([r["latency_ms_median"] for r in row_of_set])
    y = np.array([r["mpjpe_mm_median"] for r in row_of_set])
    ax.set_xlim(x.min() / 1.8, x.max() * 1.8)
    ax.set_ylim(y.min() / 1.3, y.max() * 1.3)
    ax.grid(True, which="major", color="0.9", lw=0.6)
    ax.set_axisbelow(True)
    ax.set_xlabel("median time per solve, ms (one thread, log scale)", fontsize=8)
    if column == 0:
        ax.set_ylabel("median MPJPE, mm (pelvis-relative; log scale)", fontsize=8)
    ax.tick_params(labelsize=8)
    ax.set_title(f"Effector set {effectors}, start: {start} — {meta['data']}, {meta['cases']} held-out cases",
                 fontsize=9)
    handles = [Line2D([], [], marker=marker, color=colour, lw=1.0, alpha=0.8,
                      label="no solver both faster and closer"),
               Line2D([], [], marker=marker, ls="", markerfacecolor="white", markeredgecolor=colour,
                      label="another solver is")]
    ax.legend(handles=handles, loc="upper left", fontsize=7, frameon=False)


LABEL_GAP_PX = 3.0
"""Least space between two labels of the scatter, pixels at :data:`DPI`."""


def label_groups(rows: list[dict], pts, within_px: float) -> list[list[int]]:
    """Rows of one start whose points lie within ``within_px`` of each other (drawn as one point): one label
    names them all. Returns lists of row indices, each list in the rows' order."""
    groups: list[list[int]] = []
    for i, r in enumerate(rows):
        for g in groups:
            j = g[0]
            if rows[j]["start"] == r["start"] and np.hypot(*(np.asarray(pts[i]) - pts[j])) <= within_px:
                g.append(i)
                break
        else:
            groups.append([i])
    return groups


def _label_points(fig, ax, rows: list[dict], colours: dict, fontsize: float = 6.5) -> None:
    """Name every point (in a darker shade of its start's colour); solvers whose points of one start coincide
    share one label ("neural-raw / neural-chained-raw"). Each label takes the nearest spot (a greedy search over
    16 directions and 7 distances, the most crowded points first) that overlaps no other label (nor comes
    within :data:`LABEL_GAP_PX` of one), point, the legend or the frame, and is nearer its own point than any
    other; a leader line joins a label that is not next to its point."""
    from matplotlib.colors import to_rgb

    renderer = fig.canvas.get_renderer()
    pts = ax.transData.transform([(r["latency_ms_median"], r["mpjpe_mm_median"]) for r in rows])
    pt_r = 4.0 * DPI / 72  # half a marker and a little air, px
    groups = label_groups(rows, pts, 0.5 * pt_r)
    names = [" / ".join(rows[i]["method"] for i in g) for g in groups]
    rows, pts = [rows[g[0]] for g in groups], pts[[g[0] for g in groups]]
    frame = ax.get_window_extent(renderer)
    taken = [(p[0] - pt_r, p[1] - pt_r, p[0] + pt_r, p[1] + pt_r) for p in pts]
    if ax.get_legend() is not None:
        lb = ax.get_legend().get_window_extent(renderer)
        taken.append((lb.x0, lb.y0, lb.x1, lb.y1))
    dirs = [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, 1), (1, -1), (-1, -1),
            (2, 1), (-2, 1), (2, -1), (-2, -1), (1, 2), (-1, 2), (1, -2), (-1, -2)]
    align = {-1: "right", 0: "center", 1: "left"}, {-1: "top", 0: "center", 1: "bottom"}
    ink = {st: tuple(0.6 * np.array(to_rgb(c))) for st, c in colours.items()}

    def overlap(a, b) -> float:
        w, h = min(a[2], b[2]) - max(a[0], b[0]), min(a[3], b[3]) - max(a[1], b[1])
        return w * h if w > 0 and h > 0 else 0.0

    def gap(box, p) -> float:  # distance from a point to a box, px
        return float(np.hypot(max(box[0] - p[0], 0, p[0] - box[2]), max(box[1] - p[1], 0, p[1] - box[3])))

    def cost(box, i) -> float:
        outside = (max(0, frame.x0 - box[0]) + max(0, box[2] - frame.x1) + max(0, frame.y0 - box[1])
                   + max(0, box[3] - frame.y1))
        own = gap(box, pts[i])
        nearer = sum(1 for j, p in enumerate(pts) if j != i and gap(box, p) < own + 4)
        return sum(overlap(box, t) for j, t in enumerate(taken) if j != i) + 1e3 * outside + 400 * nearer

    crowd = [int(np.sum(np.hypot(*(pts - p).T) < 60)) for p in pts]
    for i in sorted(range(len(rows)), key=lambda k: -crowd[k]):
        r = rows[i]
        text = ax.annotate(names[i], (r["latency_ms_median"], r["mpjpe_mm_median"]), fontsize=fontsize,
                           textcoords="offset points", xytext=(0, 0), zorder=4, color=ink[r["start"]])
        best = None
        for dist in (5, 11, 19, 30, 45, 65, 90):
            for dx, dy in dirs:
                step = dist / np.hypot(dx, dy)
                text.set_position((dx * step, dy * step))
                text.set_ha(align[0][int(np.sign(dx))])
                text.set_va(align[1][int(np.sign(dy))])
                b = text.get_window_extent(renderer)
                g = LABEL_GAP_PX / 2  # each label keeps half the gap: two labels stay LABEL_GAP_PX apart
                box = (b.x0 - g, b.y0 - g, b.x1 + g, b.y1 + g)
                c = cost(box, i)
                if best is None or c < best[0]:
                    best = (c, dx * step, dy * step, dx, dy, box)
                if c == 0:
                    break
            if best[0] == 0:
                break
        _, ox, oy, dx, dy, box = best
        text.set_position((ox, oy))
        text.set_ha(align[0][int(np.sign(dx))])
        text.set_va(align[1][int(np.sign(dy))])
        if np.hypot(ox, oy) > 6:
            ax.annotate("", (r["latency_ms_median"], r["mpjpe_mm_median"]), textcoords="offset points",
                        xytext=(ox, oy), zorder=2, arrowprops={"arrowstyle": "-", "color": ink[r["start"]],
                                                               "lw": 0.8, "shrinkA": 1, "shrinkB": 3})
        taken.append(box)


# ------------------------------------------------------------------------------------------- the CLI
