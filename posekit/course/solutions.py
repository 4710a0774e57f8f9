"""Instructor versions of the lessons: the exercises' reference solutions filled in, from one source.

A lesson's exercises are found in the notebook itself: a markdown cell opening with ``**Exercise N``;
a *checked* exercise is followed by a code cell holding a stub ``def exercise_...: raise
NotImplementedError`` and its checker call; an *open* one (``**Exercise N (open).**``) has no checker.
Their solutions live once, in the repository's ``instructor/solutions/`` folder — *outside* the ``posekit``
package that students install and import, so no student kernel can ``import`` them (on a class's hub that folder
is readable by the instructor only, ``deploy/jupyterhub``):

* checked: a function of the same name and parameters in ``instructor/solutions/nbNN.py``,
  self-contained so that its source can replace the stub;
* open: a ``## Exercise N`` section of ``instructor/solutions/nbNN.md``, the instructor's notes.

``POSEKIT_SOLUTIONS`` names another folder (an instructor's copy, when posekit is installed without its
repository).

:func:`instructor_notebook` pastes them in (and makes every checker call an ``assert``), and
:func:`render` executes the result, so a solution that stops passing its checker fails the build.
"""

from __future__ import annotations

import ast
import copy
import importlib
import importlib.util
import os
import inspect
import re
import textwrap
from dataclasses import dataclass
from pathlib import Path

from .lessons import Lesson, find_lesson, read_notebook

__all__ = ["Exercise", "exercises", "solution_function", "notes", "instructor_notebook", "render"]

_EXERCISE = re.compile(r"^\*\*Exercise (\d+)\b([^*]*)\*\*")
_CHECK = re.compile(r"^(\s*)(\w+)\s*=\s*(check_\w+)\((exercise_\w+)\)\s*$", re.MULTILINE)
SOLUTIONS_HOME = Path(__file__).resolve().parents[2] / "instructor" / "solutions"
"""Where the reference solutions live in the repository (outside the package)."""


def solutions_dir() -> Path:
    """The folder of reference solutions: ``POSEKIT_SOLUTIONS`` when set, else the repository's
    ``instructor/solutions/``.

    Raises
    ------
    LookupError
        When that folder does not exist (posekit installed without its repository), with what to set.
    """
    env = os.environ.get("POSEKIT_SOLUTIONS")
    path = Path(env).expanduser() if env else SOLUTIONS_HOME
    if not path.is_dir():
        raise LookupError(f"the exercises' reference solutions are not at {path}: they are not part of the posekit "
                          "package (students must not import them); they live in the repository's "
                          "instructor/solutions/ folder. Run from a checkout, or set POSEKIT_SOLUTIONS to an "
                          "instructor's copy of that folder")
    return path


@dataclass(frozen=True)
class Exercise:
    """One exercise of a lesson, as the notebook states it."""

    number: int
    open: bool
    text_cell: int
    """Index of the markdown cell that states it."""
    code_cell: int | None = None
    """Index of the code cell with the stub (checked exercises)."""
    function: str | None = None
    """The stub's name, ``exercise_...``."""
    checker: str | None = None
    """The checker the notebook calls on it, ``check_...``."""


def _stub(source: str) -> ast.FunctionDef | None:
    tree = ast.parse(source)
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name.startswith("exercise_"):
            last = node.body[-1]
            if isinstance(last, ast.Raise) and "NotImplementedError" in ast.unparse(last):
                return node
    return None


def exercises(nb) -> list[Exercise]:
    """Every exercise stated in notebook ``nb``, in order.

    Raises
    ------
    ValueError
        A checked exercise whose next code cell has no ``exercise_...`` stub or no checker call.
    """
    found = []
    for i, cell in enumerate(nb.cells):
        m = _EXERCISE.match(cell.source) if cell.cell_type == "markdown" else None
        if not m:
            continue
        number, is_open = int(m.group(1)), "(open)" in m.group(2)
        if is_open:
            found.append(Exercise(number, True, i))
            continue
        j = next((k for k in range(i + 1, len(nb.cells)) if nb.cells[k].cell_type == "code"), None)
        stub = _stub(nb.cells[j].source) if j is not None else None
        calls = [c for c in _CHECK.finditer(nb.cells[j].source) if c.group(4) == stub.name] if stub else []
        if not stub or not calls:
            raise ValueError(f"exercise {number} (cell {i}): the next code cell must define a stub "
                             "`def exercise_...: raise NotImplementedError` and call its checker "
                             "`done = check_...(exercise_...)`")
        found.append(Exercise(number, False, i, j, stub.name, calls[0].group(3)))
    return found


def _module(lesson: Lesson):
    """Lesson ``lesson``'s solutions module, loaded from its file (it is not an importable package)."""
    import sys

    path = solutions_dir() / f"nb{lesson.number}.py"
    if not path.is_file():
        raise LookupError(f"lesson {lesson.number}: no solutions file {path}")
    name = f"_posekit_solutions_nb{lesson.number}"
    mod = sys.modules.get(name)
    if mod is None or getattr(mod, "__file__", None) != str(path):
        spec = importlib.util.spec_from_file_location(name, path)
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod  # inspect.getsource finds the module's file through it
        spec.loader.exec_module(mod)
    return mod


def solution_function(lesson: Lesson, name: str):
    """The reference solution ``name`` of ``lesson`` (a function of its solutions module)."""
    fn = getattr(_module(lesson), name, None)
    if not callable(fn):
        raise LookupError(f"lesson {lesson.number}: no solution {name!r} in instructor/solutions/"
                          f"nb{lesson.number}.py")
    return fn


def notes(lesson: Lesson) -> dict[int, str]:
    """The instructor's notes on ``lesson``'s open exercises: exercise number → Markdown."""
    path = solutions_dir() / f"nb{lesson.number}.md"
    if not path.is_file():
        return {}
    found, current, lines = {}, None, []
    for line in path.read_text(encoding="utf-8").splitlines() + ["## end"]:
        m = re.match(r"^## (?:Exercise (\d+)|end)\s*$", line) if line.startswith("## ") else None
        if line.startswith("## ") and not m:
            raise ValueError(f"{path}: level-2 headings must read '## Exercise N', not {line!r}")
        if m:
            if current is not None:
                found[current] = "\n".join(lines).strip()
            current, lines = (int(m.group(1)) if m.group(1) else None), []
        elif current is not None:
            lines.append(line)
    return found


def _paste(source: str, stub: ast.FunctionDef, solution) -> str:
    sol_src = textwrap.dedent(inspect.getsource(solution)).rstrip("\n")
    sol_args = [a.arg for a in ast.parse(sol_src).body[0].args.args]
    stub_args = [a.arg for a in stub.args.args]
    if sol_args != stub_args:
        raise ValueError(f"{solution.__name__}: the solution takes ({', '.join(sol_args)}), the notebook's stub "
                         f"({', '.join(stub_args)})")
    lines = source.splitlines()
    first = stub.lineno - 1 - len(stub.decorator_list)
    return "\n".join(lines[:first] + sol_src.splitlines() + lines[stub.end_lineno:])


def _asserted(call: re.Match, function: str) -> str:
    """A checker call ``done = check_x(exercise_x)`` followed by ``assert done`` when it checks ``function``."""
    indent, result, checker, checked = call.groups()
    if checked != function:
        return call.group(0)
    return f"{call.group(0)}\n{indent}assert {result}, \"the reference solution must pass {checker}\""


BANNER = ("**Instructor version** of lesson {n}: every exercise's reference solution is filled in and was run "
          "(made by `posekit exercises solutions {n}` from the lesson and `posekit/exercises/solutions/`; "
          "not for students).")


def instructor_notebook(lesson) -> dict:
    """The lesson with its solutions pasted in, not executed.

    Parameters
    ----------
    lesson : Lesson or str
        A lesson or its number.

    Returns
    -------
    nbformat.NotebookNode
        A banner cell first; each stub replaced by its solution and each checker call followed by
        ``assert``; each open exercise followed by a markdown cell with the instructor's notes.

    Raises
    ------
    LookupError
        An exercise with no solution (function or notes).
    """
    lesson = lesson if isinstance(lesson, Lesson) else find_lesson(lesson)
    nb = copy.deepcopy(read_notebook(lesson.path))
    open_notes = notes(lesson)
    extra = {}
    for ex in exercises(nb):
        if ex.open:
            if not open_notes.get(ex.number):
                raise LookupError(f"lesson {lesson.number}, exercise {ex.number} (open): no notes in "
                                  f"posekit/exercises/solutions/nb{lesson.number}.md")
            extra[ex.text_cell] = f"**Instructor notes — exercise {ex.number}.**\n\n{open_notes[ex.number]}"
            continue
        cell = nb.cells[ex.code_cell]
        src = _paste(cell.source, _stub(cell.source), solution_function(lesson, ex.function))
        cell.source = _CHECK.sub(lambda m: _asserted(m, ex.function), src)
        cell.outputs, cell.execution_count = [], None
    import nbformat

    cells = []
    for i, cell in enumerate(nb.cells):
        cells.append(cell)
        if i in extra:
            note = nbformat.v4.new_markdown_cell(extra[i])
            note.metadata["tags"] = ["instructor-notes"]
            cells.append(note)
    banner = nbformat.v4.new_markdown_cell(BANNER.format(n=lesson.number))
    banner.metadata["tags"] = ["instructor-banner"]
    nb.cells = [cells[0], banner] + cells[1:]
    nb.metadata.setdefault("posekit", {})["instructor"] = True
    return nb


def render(lesson, out_dir, execute: bool = True, timeout_s: int = 1800) -> Path:
    """Write ``lesson``'s instructor version to ``out_dir/NN_name.solutions.ipynb``, executed by default.

    The notebook runs in the lessons' folder (the lessons read and write paths relative to it), so it takes
    as long as the lesson itself (see the course page's "runs in" column). A solution that fails its checker
    stops the run with the checker's message.
    """
    import nbformat
    from nbconvert.preprocessors import ExecutePreprocessor

    lesson = lesson if isinstance(lesson, Lesson) else find_lesson(lesson)
    nb = instructor_notebook(lesson)
    if execute:
        ExecutePreprocessor(timeout=timeout_s, kernel_name="python3", store_widget_state=False).preprocess(
            nb, {"metadata": {"path": str(lesson.path.parent)}})
    out = Path(out_dir) / f"{lesson.stem}.solutions.ipynb"
    out.parent.mkdir(parents=True, exist_ok=True)
    nbformat.write(nb, str(out))
    return out
