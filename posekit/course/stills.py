"""Stills of the lessons' 3D views for the slides: each view's poses and targets, recorded once, drawn off-screen.

A 3D view (:class:`posekit.viz.SkeletonViewer`, a solver panel, the effector editor, the studio) lives in a kernel;
a stored lesson keeps only its one-line description. ``python -m posekit.course.stills [NN ...]`` runs, for each view, the cells the
view's cell needs — found from the names it reads, back to the cells that last define them (the lesson's set-up
cell always), not the whole lesson — then reads every view's pose and targets from the widget and writes them to
``posekit/course/stills/NN_<cell id>.json`` with a fingerprint of those cells' sources. The slides draw each
recorded view with matplotlib (:func:`render_png`, the drawing of :func:`posekit.viz.plot.plot_pose`), so
``make slides`` runs no kernel; a still whose cells changed since it was recorded is not drawn (the slide keeps
the view's description and says the still is out of date) until that command records it again.

The still is the view as its cell draws it. Later cells of the lessons leave these views as they are, except where
a cell drives a view from code and then puts it back.
"""

from __future__ import annotations

import ast
import base64
import builtins
import hashlib
import io
import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from .cells import WIDGET_VIEW, _PROGRESS, _source

__all__ = ["STILLS", "view_cells", "needed_cells", "fingerprint", "record", "load", "render_png"]

STILLS = Path(__file__).with_name("stills")
_BUILTINS = set(dir(builtins))


def view_cells(nb) -> list[int]:
    """Indices of the code cells whose output is a 3D view or another live widget (not a progress bar)."""
    found = []
    for i, cell in enumerate(nb["cells"]):
        if cell["cell_type"] != "code":
            continue
        for o in cell.get("outputs", []):
            d = o.get("data", {})
            plain = d.get("text/plain", "")
            plain = plain if isinstance(plain, str) else "".join(plain)
            if WIDGET_VIEW in d and not _PROGRESS.search(plain):
                found.append(i)
                break
    return found


def _names(source: str) -> tuple[set, set]:
    """(names a cell reads before it defines them itself, names it defines)."""
    code = "\n".join(ln for ln in source.splitlines() if not ln.lstrip().startswith(("%", "!")))
    loads, stores = {}, {}
    for n in ast.walk(ast.parse(code)):
        line = getattr(n, "lineno", 0)
        if isinstance(n, ast.Name):
            d = loads if isinstance(n.ctx, ast.Load) else stores
            d[n.id] = min(d.get(n.id, line), line)
        elif isinstance(n, (ast.FunctionDef, ast.ClassDef)):
            stores[n.name] = min(stores.get(n.name, line), line)
        elif isinstance(n, ast.alias):
            name = (n.asname or n.name).split(".")[0]
            stores[name] = min(stores.get(name, line), line)
        elif isinstance(n, ast.arg):
            stores[n.arg] = 0  # a parameter: defined where it is read
    used = {k for k, at in loads.items() if k not in stores or at <= stores[k]}
    return used - _BUILTINS, set(stores)


def needed_cells(nb, view: int) -> list[int]:
    """The code cells to run, in order, so that cell ``view`` draws as in the lesson: walking back from it, every
    cell that last defines a name still needed, and the set-up cell (the first code cell)."""
    cells = nb["cells"]
    code = [i for i, c in enumerate(cells) if c["cell_type"] == "code"]
    need, _ = _names(_source(cells[view]))
    take = [view]
    for k in reversed([i for i in code if i < view]):
        used, defined = _names(_source(cells[k]))
        if defined & need or k == code[0]:
            take.append(k)
            need = (need - defined) | used
    return sorted(take)


def fingerprint(nb, view: int) -> str:
    """A hash of the sources of the cells :func:`needed_cells` runs for ``view``."""
    h = hashlib.sha1()
    for k in needed_cells(nb, view):
        h.update(_source(nb["cells"][k]).encode())
    return h.hexdigest()[:16]


_PROBE = """
import json as _json
from posekit.data.metrics import body_joints as _body_joints
from posekit.viz.viewer import SkeletonViewer as _SV

def _views(o, depth=0):
    if isinstance(o, _SV):
        return [("", o)]
    if depth < 3 and isinstance(getattr(o, "viewers", None), dict):
        return [(str(k), v) for k, v in o.viewers.items() if isinstance(v, _SV)]
    if depth < 3 and getattr(o, "editor", None) is not None:
        return _views(o.editor, depth + 1)
    return []

_found = []
for _name in {names!r}:
    _found = _views(globals().get(_name))
    if _found:
        break
_sk = _found[0][1].skeleton if _found else None
print("POSEKIT-STILL" + _json.dumps({{
    "parents": [int(p) for p in _sk.parents] if _sk is not None else [],
    "names": list(_sk.names) if _sk is not None else [],
    "body": [int(j) for j in _body_joints(_sk)] if _sk is not None else [],
    "views": [{{"title": t, "pose": _v.pose.round(4).tolist(),
               "targets": {{str(k): [round(float(x), 4) for x in p] for k, p in _v.targets.items()}}}}
              for t, _v in _found]}}))
"""


def record(lesson, timeout_s: int = 900, progress: bool = True) -> list[Path]:
    """Run each 3D view's cells of ``lesson`` in a fresh kernel and write its still (see the module docstring).

    Raises
    ------
    RuntimeError
        A view whose widget holds no :class:`~posekit.viz.SkeletonViewer` (the probe found none).
    """
    import nbformat
    from nbclient import NotebookClient

    from .lessons import read_notebook

    nb = read_notebook(lesson.path)
    written = []
    for view in view_cells(nb):
        cells = [nbformat.v4.new_code_cell(_source(nb.cells[k])) for k in needed_cells(nb, view)]
        last_expr = _source(nb.cells[view]).strip().splitlines()[-1].strip()
        names = [last_expr] if last_expr.isidentifier() else []
        names += sorted(_names(_source(nb.cells[view]))[1])
        cells.append(nbformat.v4.new_code_cell(_PROBE.format(names=names)))
        run = nbformat.v4.new_notebook(cells=cells, metadata=nb.metadata)
        if progress:
            print(f"lesson {lesson.number}, cell {view}: running {len(cells) - 1} cells ...", flush=True)
        NotebookClient(run, timeout=timeout_s, kernel_name="python3",
                       resources={"metadata": {"path": str(lesson.path.parent)}}).execute()
        text = "".join(o.get("text", "") for o in run.cells[-1].outputs if o.get("output_type") == "stream")
        line = next((ln for ln in text.splitlines() if ln.startswith("POSEKIT-STILL")), None)
        data = json.loads(line[len("POSEKIT-STILL"):]) if line else {"views": []}
        if not data["views"]:
            raise RuntimeError(f"lesson {lesson.number}, cell {view}: its widget holds no SkeletonViewer to draw")
        data.update({"lesson": lesson.number, "cell_id": nb.cells[view].get("id"), "cell": view,
                     "fingerprint": fingerprint(nb, view), "cells_run": needed_cells(nb, view),
                     "command": f"python -m posekit.course.stills {lesson.number}"})
        STILLS.mkdir(exist_ok=True)
        path = STILLS / f"{lesson.number}_{nb.cells[view].get('id')}.json"
        path.write_text(json.dumps(data) + "\n", encoding="utf-8")
        written.append(path)
    return written


def load(number: str, nb, view: int) -> tuple[dict | None, str]:
    """The recorded still of cell ``view`` and its state: ``"ok"``, ``"missing"`` or ``"stale"``."""
    path = STILLS / f"{number}_{nb['cells'][view].get('id')}.json"
    if not path.is_file():
        return None, "missing"
    data = json.loads(path.read_text(encoding="utf-8"))
    if data.get("fingerprint") != fingerprint(nb, view):
        return None, "stale"
    return data, "ok"


def render_png(still: dict, height_in: float = 4.2) -> str:
    """Draw a still's views side by side (one 3D axes each, bones coloured by side, targets as red crosses, from
    :func:`posekit.viz.plot.plot_pose`'s front-left camera); base64 PNG."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    from ..viz.plot import plot_pose

    views = still["views"][:4]
    parents = np.asarray(still["parents"])
    names = still.get("names")  # the side colours read them (posekit.viz.plot); a still without them: one colour
    skeleton = SimpleNamespace(parents=parents, n_joints=len(parents),
                               names=names if names is not None and len(names) == len(parents) else None)
    fig = Figure(figsize=(height_in * len(views), height_in), dpi=100)
    for k, v in enumerate(views):
        ax = fig.add_subplot(1, len(views), k + 1, projection="3d")
        targets = np.asarray(list(v["targets"].values())) if v["targets"] else None
        plot_pose(skeleton, np.asarray(v["pose"]), ax=ax, targets=targets, title=v["title"] or None,
                  body=still.get("body") or None)  # a helper root is no bone (stills recorded before: every joint)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", bbox_inches="tight")  # the side key stands above the panels
    return base64.b64encode(buf.getvalue()).decode()


def main(argv=None) -> int:
    """``python -m posekit.course.stills [LESSON ...]``: record the stills of the lessons named (default all)."""
    import sys

    from .lessons import find_lesson, lessons

    args = sys.argv[1:] if argv is None else argv
    for lesson in [find_lesson(a) for a in args] or lessons():
        for path in record(lesson):
            print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
