"""The speed/quality scatter of ``posekit bench all`` (posekit.bench.all_plot): its labels keep apart and name
every solver, one label for solvers drawn on one spot."""

import json

import numpy as np

from posekit.bench.all_plot import label_groups, plot
from posekit.paths import samples_dir


def _labels(ax):
    return [t for t in ax.texts if t.get_text()]


def test_coincident_points_of_one_start_share_a_label():
    rows = [{"method": "a", "start": "rest"}, {"method": "b", "start": "rest"}, {"method": "c", "start": "other-clip"},
            {"method": "d", "start": "rest"}]
    pts = np.array([[10.0, 10.0], [10.5, 10.2], [10.0, 10.0], [40.0, 10.0]])
    assert label_groups(rows, pts, 2.0) == [[0, 1], [2], [3]]  # c lies there too, but it is another start's point


def test_the_shipped_scatter_names_every_solver_and_no_two_labels_touch():
    shipped = json.loads((samples_dir() / "results" / "bench_all.json").read_text())
    rows = [r for r in shipped["rows"] if "mpjpe_mm_median" in r and "latency_ms_median" in r]
    meta = {"effectors": list(dict.fromkeys(r["effectors"] for r in rows)),
            "starts": list(dict.fromkeys(r["start"] for r in rows)), "data": shipped["data"], "cases": shipped["cases"]}
    fig = plot(rows, meta)
    renderer = fig.canvas.get_renderer()
    cells = [(e, st) for e in meta["effectors"] for st in meta["starts"]]
    assert len(fig.axes) == len(cells) == 6      # one panel per effector set and start: about 20 labels each, not 40
    for ax, (e, st) in zip(fig.axes, cells):
        assert f"set {e}, start: {st}" in ax.get_title()
        texts = _labels(ax)
        named = [n for t in texts for n in t.get_text().split(" / ")]
        mine = [r for r in rows if r["effectors"] == e and r["start"] == st]
        assert sorted(named) == sorted(r["method"] for r in mine)  # every point named once
        half = 0.5  # at least a pixel between any two labels (LABEL_GAP_PX wherever the crowd leaves room)
        boxes = [t.get_window_extent(renderer) for t in texts]
        boxes = [(b.x0 - half, b.y0 - half, b.x1 + half, b.y1 + half) for b in boxes]
        touching = [(texts[i].get_text(), texts[j].get_text()) for i in range(len(boxes)) for j in range(i)
                    if min(boxes[i][2], boxes[j][2]) > max(boxes[i][0], boxes[j][0])
                    and min(boxes[i][3], boxes[j][3]) > max(boxes[i][1], boxes[j][1])]
        assert touching == [], f"set {e}: labels touch"
        assert len(texts) < len(mine) or e != "2"  # set 2 has solvers drawn on one spot: they share labels
    # the panels of one effector set share their axes: a solver's two starts are read at the same place
    for i in range(0, len(cells), 2):
        a, b = fig.axes[i], fig.axes[i + 1]
        assert a.get_xlim() == b.get_xlim() and a.get_ylim() == b.get_ylim()
