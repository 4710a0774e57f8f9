"""A lesson's nbgrader source version cut to the cells its grading needs (tests/test_nbgrader.py's graded course).

Grading a class runs every submitted notebook top to bottom, once per student: a whole lesson (its benchmarks, its
short training runs) for each of the class's submissions. What the grading is about -- the points of each tests cell,
the errors an answer raises, what the fresh check and the flags say -- depends on the exercise cells and on the lesson
cells they read, not on the rest. :func:`slice_for_grading` keeps

* every exercise cell (answers, tests cells, the read-only cells before and after an answer, the open exercises'
  scratch cells) and every markdown cell;
* every read-only code cell that binds a name a kept cell reads, found backwards through the notebook: the latest
  binding before a read is the one kept (a cell that changes ``x.attr`` or ``x[k]`` counts as binding ``x``, and
  reads it);
* of every other code cell, its top-level imports: the kernel imports what it would, and the fresh check, which
  runs the lesson's imports before an answer (:func:`posekit.course.grading.lesson_imports`), gets the same ones.

The cells left out (or cut to their imports) are then the lesson's own (section cells before the exercises); :func:`independent` says that none
of them reads anything an exercise cell binds, so they run the same whatever a student answers -- as the lesson's
own notebook runs them under nbval.
"""

from __future__ import annotations

import ast

__all__ = ["names", "slice_for_grading", "independent"]


def _grading(cell) -> dict:
    return cell.get("metadata", {}).get("nbgrader", {}) or {}


class _Scope(ast.NodeVisitor):
    """The module-level names a cell binds, and the free names it reads (function bodies, lambdas and
    comprehensions read only what they do not bind themselves)."""

    def __init__(self):
        self.binds: set[str] = set()
        self.reads: set[str] = set()

    def visit_Name(self, node):
        (self.binds if isinstance(node.ctx, (ast.Store, ast.Del)) else self.reads).add(node.id)

    def visit_Attribute(self, node):  # x.attr = ... or x[k] = ...: a change of x
        self.generic_visit(node)
        if isinstance(node.ctx, (ast.Store, ast.Del)):
            base = node.value
            while isinstance(base, (ast.Attribute, ast.Subscript)):
                base = base.value
            if isinstance(base, ast.Name):
                self.binds.add(base.id)
                self.reads.add(base.id)

    visit_Subscript = visit_Attribute

    def visit_Import(self, node):
        for alias in node.names:
            self.binds.add((alias.asname or alias.name).split(".")[0])

    visit_ImportFrom = visit_Import

    def _inner(self, params: set[str], body) -> None:
        inner = _Scope()
        for node in body:
            inner.visit(node)
        self.reads |= inner.reads - inner.binds - params

    def visit_FunctionDef(self, node):
        for d in [*node.decorator_list, *node.args.defaults, *node.args.kw_defaults]:
            if d is not None:
                self.visit(d)
        a = node.args
        params = {p.arg for p in [*a.posonlyargs, *a.args, *a.kwonlyargs, a.vararg, a.kwarg] if p is not None}
        self._inner(params, node.body)
        self.binds.add(node.name)

    visit_AsyncFunctionDef = visit_FunctionDef

    def visit_ClassDef(self, node):
        for d in [*node.bases, *node.keywords, *node.decorator_list]:
            self.visit(d)
        self._inner(set(), node.body)
        self.binds.add(node.name)

    def visit_Lambda(self, node):
        a = node.args
        self._inner({p.arg for p in [*a.posonlyargs, *a.args, *a.kwonlyargs, a.vararg, a.kwarg] if p is not None},
                    [node.body])

    def _comprehension(self, node):
        inner = _Scope()
        for gen in node.generators:
            inner.visit(gen)
        for e in ([node.key, node.value] if isinstance(node, ast.DictComp) else [node.elt]):
            inner.visit(e)
        self.reads |= inner.reads - inner.binds

    visit_ListComp = visit_SetComp = visit_GeneratorExp = visit_DictComp = _comprehension


def names(source: str) -> tuple[set[str], set[str]]:
    """``(binds, reads)`` of a code cell's ``source`` (IPython's ``%`` and ``!`` lines left out)."""
    python = "\n".join(ln for ln in source.splitlines() if not ln.lstrip().startswith(("%", "!")))
    scope = _Scope()
    scope.visit(ast.parse(python))
    return scope.binds, scope.reads


def _exercise_cell(cell) -> bool:
    g = _grading(cell)
    return not g or bool(g.get("solution") or g.get("grade")) or g.get("grade_id", "").endswith(("_before", "_after"))


def slice_for_grading(nb):
    """``nb`` (an nbgrader source version, :func:`posekit.course.nbgrader.assignment_notebook`) without the
    read-only code cells its exercise cells do not need (module docstring); a new notebook, ``nb`` is unchanged."""
    import nbformat

    out = nbformat.from_dict(nb)
    keep, need = set(), set()
    for k in range(len(out.cells) - 1, -1, -1):
        cell = out.cells[k]
        if cell.cell_type != "code":
            keep.add(k)
            continue
        binds, reads = names(cell.source)
        if _exercise_cell(cell) or binds & need:
            keep.add(k)
            need = (need - (binds - reads)) | reads
    cells = []
    for k, cell in enumerate(out.cells):
        if k in keep:
            cells.append(cell)
            continue
        imports = _imports(cell.source)
        if imports:  # the lesson's imports stay whole: the kernel and the fresh check import what they would
            cell.source = imports
            cells.append(cell)
    out.cells = cells
    return out


def _imports(source: str) -> str:
    """The top-level import statements of ``source``, as ``posekit.course.grading.lesson_imports`` reads them."""
    try:
        tree = ast.parse(source)
    except SyntaxError:
        return ""
    return "\n".join(ast.unparse(n) for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom)))


def independent(nb, sliced) -> list[str]:
    """The grade ids of the cells ``sliced`` left out of ``nb`` that read (directly or through another cell) a name
    an exercise cell binds: none, when the cells left out run the same whatever the answers are."""
    kept = {_grading(c).get("grade_id"): c.source for c in sliced.cells}
    tainted: set[str] = set()
    out = []
    for cell in nb.cells:
        if cell.cell_type != "code":
            continue
        binds, reads = names(cell.source)
        if _exercise_cell(cell) or reads & tainted:
            tainted |= binds
            if not _exercise_cell(cell) and kept.get(_grading(cell)["grade_id"]) != cell.source:  # left out or cut
                out.append(_grading(cell).get("grade_id"))
    return out
