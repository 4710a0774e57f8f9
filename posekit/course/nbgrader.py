"""The lessons as an nbgrader course: a class's work collected, autograded and exported by nbgrader itself.

``posekit course nbgrader --out DIR`` writes an nbgrader course directory: ``DIR/nbgrader_config.py`` and one
assignment per lesson, ``DIR/source/<stem>/<stem>.ipynb`` (``00_skeletons_and_poses``, ``01_fabrik``, ...).
Each is the lesson with its exercises turned into nbgrader cells, from the same sources as the instructor
version (:mod:`posekit.course.solutions`):

* a checked exercise (``def exercise_...: raise NotImplementedError`` and its checker) becomes an
  *autograded answer* cell holding the reference solution of ``posekit/exercises/solutions/nbNN.py`` between
  nbgrader's ``### BEGIN SOLUTION`` / ``### END SOLUTION`` markers, then a read-only *autograder tests* cell
  that calls the lesson's checker and prints the points earned (nbgrader's partial credit: the cell's last
  value); a stub that still raises ``NotImplementedError`` is "not attempted yet" and earns 0 without an error,
  so the student version runs top to bottom;
* an open exercise becomes a *manually graded answer* cell (markdown) holding the instructor's notes of
  ``nbNN.md`` as the rubric between the same markers (students see ``YOUR ANSWER HERE``), and an ungraded
  scratch code cell for their working;
* every other cell is read-only (nbgrader "locked"), so a student cannot change or delete a lesson's cell.

Exercises are found by what the lesson says (``**Exercise N**`` cells, :func:`posekit.course.solutions.exercises`),
never by cell position; a cell's points are 1 unless the exercise's markdown cell says otherwise in its
metadata (``{"posekit": {"points": 2}}``).

nbgrader's own commands do the rest (``nbgrader generate_assignment``, ``autograde``, ``export``). One step is
added in front of ``autograde``: :func:`screen` reads each student's folder first, and ``posekit course autograde``
runs nbgrader's ``autograde`` without the folders it refuses (a notebook that is not JSON, another lesson's
notebook, a folder without a notebook), naming each; nbgrader then grades them as missing. One step is added after
it: every autograded exercise is checked again in a fresh process, whose verdict is the one the grade book keeps,
and what a person should read is flagged (:mod:`posekit.course.grading`).
"""

from __future__ import annotations

import ast
import copy
import inspect
import json
import os
import subprocess
import sys
import textwrap
import time
from dataclasses import dataclass
from pathlib import Path

from .lessons import Lesson, find_lesson, lessons, read_notebook
from .solutions import _CHECK, _stub, exercises, notes, solution_function

__all__ = ["assignment_notebook", "write_course", "screen", "Refused", "autograde", "trial", "CONFIG",
           "CELL_TIMEOUT_S"]

CELL_TIMEOUT_S = 300
"""Seconds one cell may run under ``autograde`` before nbgrader interrupts it (a student's endless loop)."""

CONFIG = '''\
# nbgrader course for posekit, written by `posekit course nbgrader`; edit freely, it is not rewritten
# unless you run the command again with --force.
c = get_config()  # noqa: F821

c.CourseDirectory.course_id = "posekit"

# A cell that runs longer than this (seconds) is interrupted, graded as an error, and the rest of the
# notebook goes on: a student's endless loop costs one timeout, not the batch.
c.Execute.timeout = {timeout}
c.Execute.interrupt_on_timeout = True
# On a busy machine a kernel can be slow to send a cell's last output after the cell has finished; wait for
# it (nbclient's default is 4 s, and running out fails the whole submission) rather than lose it.
c.Execute.iopub_timeout = 60

# A graded cell a student deleted is put back from the source version (and says so) before grading.
c.OverwriteCells.add_missing_cells = True

# On a JupyterHub, the exchange directory every student and the instructor can reach, e.g.
# c.Exchange.root = "/srv/nbgrader/exchange"

# `nbgrader collect` refuses a submission made in another student's name or holding a link, and keeps that
# student's own (nbgrader's collect only warns, and takes the newest): posekit.course.exchange
c.ExchangeFactory.collect = "posekit.course.exchange.OwnerCheckedCollect"
'''

_TESTS = '''\
# autograder tests of exercise {number} ({points:g} point{s}): the lesson's checker runs on your function
import contextlib, sys
from posekit.exercises import {checker}
with contextlib.redirect_stderr(sys.stdout):  # a warning is shown, never counted as a failure
    {result} = {checker}({function})
{points:g} if {result} else 0  # the points earned (nbgrader reads this number)'''

_SCRATCH = ("# Your working for exercise {number} (not graded: write your answer in the cell above).\n")


def _nbgrader(grade_id: str, *, solution=False, grade=False, locked=False, points=None) -> dict:
    meta = {"grade": grade, "grade_id": grade_id, "locked": locked, "schema_version": 3, "solution": solution,
            "task": False}
    if grade:
        meta["points"] = points
    return meta


def _points(cell, default: float, where: str) -> float:
    value = cell.get("metadata", {}).get("posekit", {}).get("points", default)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value <= 0:
        raise ValueError(f"{where}: the cell metadata's posekit.points must be a positive number, not {value!r}")
    return float(value)


def _answer_source(lesson: Lesson, stub: ast.FunctionDef, stub_src: str, name: str) -> str:
    """The stub's ``def`` line(s) and, between nbgrader's markers, the reference solution's body."""
    solution = solution_function(lesson, name)
    sol_src = textwrap.dedent(inspect.getsource(solution)).rstrip("\n")
    sol = ast.parse(sol_src).body[0]
    sol_args, stub_args = [a.arg for a in sol.args.args], [a.arg for a in stub.args.args]
    if sol_args != stub_args:
        raise ValueError(f"{name}: the solution takes ({', '.join(sol_args)}), lesson {lesson.number}'s stub "
                         f"({', '.join(stub_args)})")
    lines = stub_src.splitlines()
    head = lines[stub.lineno - 1 - len(stub.decorator_list):stub.body[-1].lineno - 1]  # def line + any hints
    body = sol_src.splitlines()[sol.body[0].lineno - 1:]
    indent = " " * stub.body[-1].col_offset
    body = textwrap.indent(textwrap.dedent("\n".join(body)), indent).splitlines()
    return "\n".join(head + [f"{indent}### BEGIN SOLUTION"] + body + [f"{indent}### END SOLUTION"])


def assignment_notebook(lesson, points_checked: float = 1, points_open: float = 1):
    """The nbgrader *source* version of ``lesson``: solutions filled in, every cell marked for nbgrader.

    Parameters
    ----------
    lesson : Lesson or str
        A lesson or its number.
    points_checked, points_open : float
        Points of a checked (autograded) and of an open (manually graded) exercise, unless its markdown
        cell's metadata says ``{"posekit": {"points": N}}``.

    Returns
    -------
    nbformat.NotebookNode
        Outputs cleared. ``nbgrader generate_assignment`` makes the student version from it.

    Raises
    ------
    LookupError
        An exercise with no solution (function or notes).
    """
    import nbformat

    lesson = lesson if isinstance(lesson, Lesson) else find_lesson(lesson)
    nb = copy.deepcopy(read_notebook(lesson.path))
    open_notes = notes(lesson)
    replace: dict[int, list] = {}  # cell index -> the cells that take its place

    def cell(kind, source, cid, **grading):
        c = getattr(nbformat.v4, f"new_{kind}_cell")(source, id=cid)
        if grading:  # a scratch cell has none: editable, not graded
            c.metadata["nbgrader"] = _nbgrader(**grading)
        return c

    for ex in exercises(nb):
        text = nb.cells[ex.text_cell]
        n = ex.number
        if ex.open:
            rubric = open_notes.get(n)
            if not rubric:
                raise LookupError(f"lesson {lesson.number}, exercise {n} (open): no notes in "
                                  f"posekit/exercises/solutions/nb{lesson.number}.md")
            pts = _points(text, points_open, f"{lesson.path}, exercise {n}")
            answer = cell("markdown", "### BEGIN SOLUTION\n"
                          f"**Rubric (instructor notes) — exercise {n}, {pts:g} point{'s' * (pts != 1)}.**\n\n"
                          f"{rubric}\n### END SOLUTION", f"exercise-{n}-answer",
                          grade_id=f"exercise_{n}_answer", solution=True, grade=True, points=pts)
            replace[ex.text_cell] = [text, answer, cell("code", _SCRATCH.format(number=n), f"exercise-{n}-scratch")]
            continue
        pts = _points(text, points_checked, f"{lesson.path}, exercise {n}")
        code = nb.cells[ex.code_cell]
        stub = _stub(code.source)
        lines = code.source.splitlines()
        first = stub.lineno - 1 - len(stub.decorator_list)
        calls = [m for m in _CHECK.finditer(code.source) if m.group(4) == ex.function]
        call_lines = {code.source[:m.start(2)].count("\n") for m in calls}
        before = "\n".join(lines[:first]).strip("\n")
        rest = "\n".join(ln for k, ln in enumerate(lines) if k >= stub.end_lineno and k not in call_lines).strip("\n")
        cid = code.get("id") or f"exercise-{n}"
        new = []
        if before.strip():  # the lesson's imports before the stub stay, read-only
            new.append(cell("code", before, f"{cid}-before", grade_id=f"cell_{cid}_before", locked=True))
        new.append(cell("code", _answer_source(lesson, stub, code.source, ex.function), f"{ex.function}"[:64],
                        grade_id=ex.function, solution=True))
        new.append(cell("code", _TESTS.format(number=n, points=pts, s="s" * (pts != 1), checker=ex.checker,
                                              function=ex.function, result=calls[0].group(2)),
                        f"{ex.function}-tests"[:64], grade_id=f"{ex.function}_tests", grade=True, locked=True,
                        points=pts))
        if rest.strip():  # the lesson's own assertions after the checker call (not graded)
            new.append(cell("code", rest, f"{cid}-after", grade_id=f"cell_{cid}_after", locked=True))
        replace[ex.code_cell] = new

    cells = []
    for i, c in enumerate(nb.cells):
        if i not in replace:
            c.metadata["nbgrader"] = _nbgrader(f"cell_{c.get('id') or i}", locked=True)
        for k in replace.get(i, [c]):
            if k is c and "nbgrader" not in k.metadata:  # an open exercise's statement
                k.metadata["nbgrader"] = _nbgrader(f"cell_{c.get('id') or i}", locked=True)
            cells.append(k)
    for c in cells:
        if c.cell_type == "code":
            c.outputs, c.execution_count = [], None
        c.metadata.pop("execution", None)
    nb.cells = cells
    nb.metadata.setdefault("posekit", {})["nbgrader"] = True
    return nb


def write_course(out, chosen=None, force: bool = False, cell_timeout_s: int = CELL_TIMEOUT_S) -> list[Path]:
    """Write the nbgrader course directory ``out``: ``nbgrader_config.py`` and ``source/<stem>/<stem>.ipynb``.

    Parameters
    ----------
    out : path
        The course directory (made if needed).
    chosen : list of Lesson, optional
        Default: every lesson.
    force : bool
        Rewrite an existing ``nbgrader_config.py`` (the source notebooks are always rewritten).
    cell_timeout_s : int
        ``Execute.timeout`` written into the config (seconds per cell).

    Returns
    -------
    list of Path
        The source notebooks written, in lesson order.
    """
    import nbformat

    out = Path(out)
    chosen = lessons() if chosen is None else chosen
    out.mkdir(parents=True, exist_ok=True)
    config = out / "nbgrader_config.py"
    if force or not config.exists():
        config.write_text(CONFIG.format(timeout=int(cell_timeout_s)),
                          encoding="utf-8")
    written = []
    for lesson in chosen:
        path = out / "source" / lesson.stem / f"{lesson.stem}.ipynb"
        path.parent.mkdir(parents=True, exist_ok=True)
        nbformat.write(assignment_notebook(lesson), str(path))
        written.append(path)
    return written


@dataclass(frozen=True)
class Refused:
    """A student's folder that ``autograde`` leaves out (nbgrader then grades the lesson as missing)."""

    student: str
    path: Path
    reason: str

    def __str__(self) -> str:
        return f"{self.path}: {self.reason} — not graded, counts as missing"


def _lesson_of(nb) -> str | None:
    meta = nb.get("metadata", {}).get("posekit", {}) if isinstance(nb, dict) else {}
    return meta.get("lesson") if isinstance(meta, dict) else None


def screen(course_dir, assignment: str) -> list[Refused]:
    """Read every student's ``submitted/<student>/<assignment>/`` folder; return those to leave out.

    A folder is refused when it holds no notebook, when ``<assignment>.ipynb`` is missing and the folder
    holds another lesson's notebook, when ``<assignment>.ipynb`` is not a Jupyter notebook (not JSON: the
    line is named), or when it is another lesson's notebook renamed (its ``posekit`` metadata says which).
    """
    course_dir = Path(course_dir)
    lesson = find_lesson(assignment)
    refused = []
    for folder in sorted((course_dir / "submitted").glob(f"*/{assignment}")):
        if not folder.is_dir():
            continue
        student = folder.parent.name
        expected = folder / f"{assignment}.ipynb"
        found = sorted(folder.glob("*.ipynb"))
        if not found:
            refused.append(Refused(student, folder, f"no notebook (expected {expected.name})"))
            continue
        if not expected.exists():
            refused.append(Refused(student, folder, f"no {expected.name}; found {', '.join(p.name for p in found)}"
                                   " (another lesson's notebook?)"))
            continue
        try:
            nb = json.loads(expected.read_text(encoding="utf-8"))
        except UnicodeDecodeError as e:
            refused.append(Refused(student, expected, f"not a Jupyter notebook (not UTF-8 text: {e})"))
            continue
        except json.JSONDecodeError as e:
            refused.append(Refused(student, expected, f"not a Jupyter notebook (not JSON: {e.msg} at line "
                                                      f"{e.lineno}, column {e.colno})"))
            continue
        if not isinstance(nb, dict) or not isinstance(nb.get("cells"), list):
            refused.append(Refused(student, expected, "not a Jupyter notebook (JSON without a 'cells' list)"))
            continue
        theirs = _lesson_of(nb)
        if theirs != lesson.number:
            said = f"lesson {theirs}'s notebook" if theirs else "a notebook that is not a posekit lesson"
            refused.append(Refused(student, expected, f"{said}, expected lesson {lesson.number} ({assignment})"))
    return refused


def scripts_on_path() -> None:
    """Put this interpreter's scripts folder first on ``PATH``, for this process and those it starts.

    nbgrader's grade book runs ``alembic`` by name (``nbgrader.api.get_alembic_version``), so it fails with
    "No such file or directory: 'alembic'" when the environment nbgrader is installed in is not activated —
    for example ``.venv/bin/posekit course autograde ...`` or ``make test``. Called by every function of this
    module that runs nbgrader; call it before using nbgrader's Python API yourself.
    """
    scripts = str(Path(sys.executable).parent)
    parts = os.environ.get("PATH", "").split(os.pathsep)
    if parts[:1] != [scripts]:
        os.environ["PATH"] = os.pathsep.join([scripts] + [p for p in parts if p and p != scripts])


def _nbgrader_cmd(*args) -> list[str]:
    scripts_on_path()
    return [sys.executable, "-m", "nbgrader", *args]


def autograde(course_dir, assignment: str, student: str | None = None, force: bool = False,
              extra: tuple[str, ...] = (), log=None, cell_timeout_s: float | None = None):
    """Screen the submissions of ``assignment`` (:func:`screen`), run ``nbgrader autograde`` on the rest, then
    check every autograded exercise again in a fresh process (:func:`posekit.course.grading.regrade`).

    Returns
    -------
    returncode : int
        nbgrader's exit status (non-zero when it could not grade a submission; its log names which).
    refused : list of Refused
        The folders left out, each with its reason (nbgrader grades them as missing).
    findings : list of posekit.course.grading.Finding
        What was flagged in the grade book for a person to read (a changed read-only cell, a kernel that
        disagreed with the fresh check, an answer touching the grading machinery).
    """
    import re

    from .grading import regrade

    refused = screen(course_dir, assignment)
    cmd = _nbgrader_cmd("autograde", assignment, *extra)
    if student:
        cmd.append(f"--student={student}")
    if force:
        cmd.append("--force")
    if refused:
        cmd.append("--CourseDirectory.student_id_exclude=" + ",".join(sorted({r.student for r in refused})))
    proc = subprocess.run(cmd, cwd=course_dir, stdout=log, stderr=subprocess.STDOUT if log else None)
    if cell_timeout_s is None:
        said = re.search(r"^c\.Execute\.timeout = (\d+)", (Path(course_dir) / "nbgrader_config.py").read_text(), re.M)
        cell_timeout_s = float(said.group(1)) if said else CELL_TIMEOUT_S
    findings = regrade(course_dir, assignment, students=[student] if student else None, timeout_s=cell_timeout_s)
    return proc.returncode, refused, findings


def trial(course_dir, chosen=None, progress: bool = False, command: str = "posekit course nbgrader --trial") -> dict:
    """Autograde one submission of each lesson, its source version (every answer right), and time it.

    In the course directory ``course_dir`` (written by :func:`write_course`), runs ``nbgrader
    generate_assignment``, puts the source version in ``submitted/trial-solution/<stem>/`` and times
    ``nbgrader autograde`` on it (through :func:`autograde`); the score is read from nbgrader's grade book.

    Returns
    -------
    dict
        ``{"command", "machine", "cell_timeout_s", "what", "lessons": [{"lesson", "assignment", "autograde_s",
        "autograde_cpu_s", "load_avg_1min_before", "score", "max_score"}, ...]}``; times in seconds.
    """
    import re
    import shutil

    from nbgrader.api import Gradebook
    from tqdm.auto import tqdm

    course_dir = Path(course_dir)
    chosen = lessons() if chosen is None else chosen
    timeout = re.search(r"^c\.Execute\.timeout = (\d+)", (course_dir / "nbgrader_config.py").read_text(), re.M)
    rows = []
    for lesson in tqdm(chosen, desc="autograde one submission per lesson", disable=not progress):
        a = lesson.stem
        subprocess.run(_nbgrader_cmd("generate_assignment", a, "--force"), cwd=course_dir, check=True,
                       capture_output=True)
        dest = course_dir / "submitted" / "trial-solution" / a
        dest.mkdir(parents=True, exist_ok=True)
        shutil.copy(course_dir / "source" / a / f"{a}.ipynb", dest / f"{a}.ipynb")
        load = os.getloadavg()[0]
        t0, cpu0 = time.perf_counter(), _children_cpu_s()
        rc, _, _ = autograde(course_dir, a, student="trial-solution", force=True, extra=("--log-level=ERROR",),
                             log=subprocess.DEVNULL)
        seconds, cpu = time.perf_counter() - t0, _children_cpu_s() - cpu0
        if rc != 0:
            raise RuntimeError(f"nbgrader autograde failed on {a} (exit {rc}); run it in {course_dir} to see why")
        with Gradebook(f"sqlite:///{course_dir / 'gradebook.db'}") as gb:
            sub = gb.find_submission(a, "trial-solution")
            rows.append({"lesson": lesson.number, "assignment": a, "autograde_s": round(seconds, 1),
                         "autograde_cpu_s": round(cpu, 1), "load_avg_1min_before": round(load, 2),
                         "score": sub.code_score, "max_score": sub.max_code_score})
    from ..provenance import stamp

    return {**stamp(command),
            "cell_timeout_s": int(timeout.group(1)) if timeout else None,
            "what": "autograde_s: wall time of `nbgrader autograde` on one submission (the lesson's source version) "
                    "of each lesson, nbgrader's and the kernel's start included; autograde_cpu_s: CPU time of "
                    "nbgrader and its kernel (less dependent on what else the machine runs); "
                    "load_avg_1min_before: the machine's load average when it started; score / max_score: the "
                    "autograded points",
            "lessons": rows}


def _children_cpu_s() -> float:
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime
