"""The lessons as an nbgrader course (``posekit course nbgrader``), graded by nbgrader's own commands.

The fast tests read the source notebooks and the screening of bad folders; the slow ones run nbgrader
itself on one course of every lesson: ``generate_assignment``; ``autograde`` of a class for each lesson (the
source version, the released one, one answer wrong), graded with one ``autograde`` per lesson, one lesson a
core in copies of the course; for lesson 00 also a deleted cell, an answer that raises at import, an endless
loop and three folders nbgrader cannot grade; ``export`` of the grade book.
"""

from __future__ import annotations

import csv
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest

pytest.importorskip("nbgrader")

from posekit.course.lessons import lessons, read_notebook  # noqa: E402
from posekit.course.grading import lesson_imports  # noqa: E402
from posekit.course.nbgrader import assignment_notebook, screen, scripts_on_path  # noqa: E402
from posekit.course.solutions import exercises, notes  # noqa: E402
from tests.lesson_slice import independent, names, slice_for_grading  # noqa: E402

scripts_on_path()  # nbgrader's grade book runs `alembic` by name, also when the venv is not activated

ROOT = Path(__file__).resolve().parents[1]
LESSONS = lessons()
STEMS = [le.stem for le in LESSONS]
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
if os.environ.get("PYTEST_XDIST_WORKER"):  # two workers on two cores: the grading kernels take one thread each
    ENV.update(OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")


def _grading(cell) -> dict:
    return cell.metadata.get("nbgrader", {})


@pytest.mark.parametrize("lesson", LESSONS, ids=STEMS)
def test_source_version_marks_every_exercise_for_nbgrader(lesson):
    nb = assignment_notebook(lesson)
    lesson_nb = read_notebook(lesson.path)
    exs = exercises(lesson_nb)
    ids = [_grading(c)["grade_id"] for c in nb.cells if _grading(c)]
    assert len(ids) == len(set(ids)), "grade ids must be unique"
    answers = {_grading(c)["grade_id"]: c for c in nb.cells if _grading(c).get("solution")}
    tests = {_grading(c)["grade_id"]: c for c in nb.cells if _grading(c).get("grade") and not _grading(c)["solution"]}
    open_notes = notes(lesson)
    for ex in exs:
        if ex.open:
            cell = answers[f"exercise_{ex.number}_answer"]
            assert cell.cell_type == "markdown" and _grading(cell)["grade"] and _grading(cell)["points"] > 0
            assert open_notes[ex.number].splitlines()[0] in cell.source  # the instructor notes are the rubric
            assert cell.source.startswith("### BEGIN SOLUTION") and cell.source.endswith("### END SOLUTION")
        else:
            answer = answers[ex.function]
            assert answer.cell_type == "code" and not _grading(answer)["grade"] and not _grading(answer)["locked"]
            assert answer.source.startswith(f"def {ex.function}(")
            assert "### BEGIN SOLUTION" in answer.source and "NotImplementedError" not in answer.source
            test = tests[f"{ex.function}_tests"]
            assert _grading(test)["locked"] and _grading(test)["points"] > 0
            assert f"{ex.checker}({ex.function})" in test.source
    n_graded = sum(1 for c in nb.cells if _grading(c).get("grade"))
    assert n_graded == len(exs)  # one graded cell per exercise: the checked one's tests, the open one's answer
    # every lesson cell is read-only; only answers and the open exercises' scratch cells are not
    for c in nb.cells:
        g = _grading(c)
        if not g:
            assert c.source.startswith("# Your working for exercise"), c.source[:80]
        elif not g["solution"]:
            assert g["locked"], g
    # the lesson's own cells are all there, in order (the checked ones split around the answer)
    assert [c.source for c in nb.cells if _grading(c).get("grade_id", "").startswith("cell_")
            and not _grading(c)["grade_id"].endswith(("_before", "_after"))] == \
        [c.source for i, c in enumerate(lesson_nb.cells) if i not in {e.code_cell for e in exs}]


def test_an_exercise_cell_can_set_its_points(tmp_path):
    import dataclasses

    lesson = LESSONS[0]
    nb = read_notebook(lesson.path)
    exs = exercises(nb)
    checked, opened = next(e for e in exs if not e.open), next(e for e in exs if e.open)
    nb.cells[checked.text_cell].metadata["posekit"] = {"points": 3}
    nb.cells[opened.text_cell].metadata["posekit"] = {"points": 2.5}
    copy = tmp_path / lesson.path.name
    nbformat.write(nb, str(copy))
    out = assignment_notebook(dataclasses.replace(lesson, path=copy))
    points = {_grading(c)["grade_id"]: _grading(c)["points"] for c in out.cells if _grading(c).get("grade")}
    assert points[f"{checked.function}_tests"] == 3 and points[f"exercise_{opened.number}_answer"] == 2.5
    assert sum(points.values()) == 3 + 2.5 + len(exs) - 2
    tests = next(c for c in out.cells if _grading(c).get("grade_id") == f"{checked.function}_tests")
    assert tests.source.splitlines()[-1].startswith("3 if done else 0")
    nb.cells[checked.text_cell].metadata["posekit"] = {"points": "many"}
    nbformat.write(nb, str(copy))
    says = rf"{lesson.path.name}, exercise {checked.number}: .*positive number, not 'many'"
    with pytest.raises(ValueError, match=says):
        assignment_notebook(dataclasses.replace(lesson, path=copy))


# ---- screening what students hand in --------------------------------------------------------------------


def _released_like(stem: str, lesson: str) -> str:
    nb = nbformat.v4.new_notebook()
    nb.metadata["posekit"] = {"lesson": lesson}
    nb.cells = [nbformat.v4.new_markdown_cell("# hello")]
    return nbformat.writes(nb)


def test_screen_names_each_folder_it_cannot_grade(tmp_path):
    a = STEMS[0]
    sub = tmp_path / "submitted"
    good, other, renamed, broken, empty, cells = (sub / s / a for s in
                                                  ("good", "other", "renamed", "broken", "empty", "cells"))
    for d in (good, other, renamed, broken, empty, cells):
        d.mkdir(parents=True)
    (good / f"{a}.ipynb").write_text(_released_like(a, "00"))
    (other / f"{STEMS[1]}.ipynb").write_text(_released_like(STEMS[1], "01"))      # another lesson, its own name
    (renamed / f"{a}.ipynb").write_text(_released_like(a, "01"))                  # another lesson, renamed
    (broken / f"{a}.ipynb").write_text('{"cells": [\n  {"cell_type": "code",\n  oops\n')  # not JSON
    (empty / "notes.txt").write_text("I forgot")
    (cells / f"{a}.ipynb").write_text('{"metadata": {}}')                          # JSON, not a notebook
    refused = {r.student: str(r) for r in screen(tmp_path, a)}
    assert set(refused) == {"other", "renamed", "broken", "empty", "cells"}
    assert f"no {a}.ipynb; found {STEMS[1]}.ipynb" in refused["other"]
    assert "lesson 01's notebook, expected lesson 00" in refused["renamed"]
    assert re.search(r"broken/.+\.ipynb: not a Jupyter notebook \(not JSON: .* at line 3, column 3\)",
                     refused["broken"])
    assert "no notebook (expected" in refused["empty"] and "counts as missing" in refused["empty"]
    assert "JSON without a 'cells' list" in refused["cells"]


def test_autograde_command_refuses_a_folder_that_is_not_a_course(tmp_path, capsys):
    from posekit.cli import main

    assert main(["course", "autograde", "00", "--course", str(tmp_path)]) == 2
    assert "no nbgrader_config.py" in capsys.readouterr().err


# ---- nbgrader itself (slow: kernels run whole lessons) ----------------------------------------------------


def _run(cmd, cwd, ok=True):
    proc = subprocess.run(cmd, cwd=cwd, env=ENV, capture_output=True, text=True)
    if ok and proc.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} exited {proc.returncode}:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
    return proc


def _nbgrader(*args, cwd, ok=True):
    return _run([sys.executable, "-m", "nbgrader", *args, "--log-level=WARN"], cwd, ok)


def _release(root) -> None:
    """nbgrader's ``generate_assignment`` of every lesson of the course ``root`` (its Python API, in this process:
    one nbgrader start instead of seven)."""
    from nbgrader.apps import NbGraderAPI
    from traitlets.config.loader import PyFileConfigLoader

    scripts_on_path()  # nbgrader's grade book runs `alembic` by name, also when the venv is not activated
    config = PyFileConfigLoader("nbgrader_config.py", path=str(root)).load_config()
    config.CourseDirectory.root = str(root)
    api = NbGraderAPI(config=config)
    for stem in STEMS:
        result = api.generate_assignment(stem)
        assert result["success"], result.get("error") or result.get("log")


@pytest.fixture(scope="module")
def course(tmp_path_factory):
    """Every lesson written by the command and released by nbgrader's ``generate_assignment``."""
    root = tmp_path_factory.mktemp("course")
    _run([sys.executable, "-m", "posekit", "course", "nbgrader", "--out", str(root)], ROOT)
    _release(root)
    return root


@pytest.fixture(scope="module")
def graded_course(course, tmp_path_factory):
    """The course the classes are graded in: the command's course with each lesson cut to the cells its grading
    needs (:func:`tests.lesson_slice.slice_for_grading`: every exercise cell, and the lesson cells they read), then
    released. A class hands in, and nbgrader runs, each student's notebook top to bottom; the lesson cells left out
    (benchmarks, demo training runs) read nothing an exercise binds (:func:`tests.lesson_slice.independent`, asserted
    by ``test_the_graded_course_leaves_out_only_lesson_cells_no_exercise_reads``), so they would run the same in
    every submission, as they run under nbval in the lesson itself."""
    root = tmp_path_factory.mktemp("graded")
    shutil.copy(course / "nbgrader_config.py", root / "nbgrader_config.py")
    for stem in STEMS:
        src = nbformat.read(str(course / "source" / stem / f"{stem}.ipynb"), as_version=4)
        (root / "source" / stem).mkdir(parents=True)
        nbformat.write(slice_for_grading(src), str(root / "source" / stem / f"{stem}.ipynb"))
    _release(root)
    return root


@pytest.mark.parametrize("lesson", LESSONS, ids=STEMS)
def test_the_graded_course_leaves_out_only_lesson_cells_no_exercise_reads(lesson):
    nb = assignment_notebook(lesson)
    sliced = slice_for_grading(nb)
    assert independent(nb, sliced) == []
    # every exercise cell and every markdown cell is kept, in order; only read-only lesson code cells go
    def kept_whole(cells):
        return [c for c in cells if c.cell_type == "markdown" or not _grading(c).get("locked") or _grading(c)["grade"]
                or _grading(c)["grade_id"].endswith(("_before", "_after"))]
    assert kept_whole(sliced.cells) == kept_whole(nb.cells)
    assert sum(len(c.source) for c in sliced.cells) < sum(len(c.source) for c in nb.cells)
    # the lesson's imports are all there: the fresh check runs the same ones before each answer
    def imports(cells):
        return lesson_imports(c.source for c in cells if c.cell_type == "code" and _grading(c).get("locked"))
    assert imports(sliced.cells) == imports(nb.cells)
    # every lesson name a kept cell reads is bound by a kept cell before it (or by itself)
    lesson_binds = set().union(*(names(c.source)[0] for c in nb.cells if c.cell_type == "code"))
    bound = set()
    for c in sliced.cells:
        if c.cell_type == "code":
            binds, reads = names(c.source)
            assert (reads & lesson_binds) - bound - binds == set(), c.source[:200]
            bound |= binds


@pytest.mark.slow
@pytest.mark.parametrize("stem", STEMS)
def test_generate_assignment_releases_every_lesson_without_its_solutions(course, stem):
    released = nbformat.read(str(course / "release" / stem / f"{stem}.ipynb"), as_version=4)
    source = assignment_notebook(stem[:2])
    text = "\n".join(c.source for c in released.cells)
    assert "BEGIN SOLUTION" not in text and "Rubric (instructor notes)" not in text
    for ex in exercises(read_notebook(ROOT / "notebooks" / f"{stem}.ipynb")):
        if not ex.open:
            answer = next(c for c in released.cells if _grading(c).get("grade_id") == ex.function)
            assert answer.source.startswith(f"def {ex.function}(") and "raise NotImplementedError()" in answer.source
    # read-only cells stay so for the student (nbgrader's lock), and the lesson keeps all its cells
    assert all(c.metadata.get("deletable") is False for c in released.cells if _grading(c).get("locked"))
    assert len(released.cells) == len(source.cells)


def _answer(nb, function) -> nbformat.NotebookNode:
    return next(c for c in nb.cells if _grading(c).get("grade_id") == function)


def _copy(nb) -> nbformat.NotebookNode:
    return nbformat.from_dict(json.loads(json.dumps(nb)))


def _checked(stem) -> list:
    return [ex for ex in exercises(read_notebook(ROOT / "notebooks" / f"{stem}.ipynb")) if not ex.open]


def _wrong_exercise(stem) -> str:
    """The exercise a lesson's "wrong" student gets wrong: the first, a middle or the last, by lesson number."""
    checked = _checked(stem)
    return checked[int(stem[:2]) % len(checked)].function


_SLIP = """

def {function}(*args, **kwargs):  # the student's slip: every number of the answer 0.01 off
    return _off(_{function}_right(*args, **kwargs))


def _off(value):
    import numpy as np

    if value is None:
        return None
    if isinstance(value, tuple):
        return tuple(_off(v) for v in value)
    return np.asarray(value, dtype=float) + 0.01
"""


def _slip(answer_source: str, function: str) -> str:
    """The answer, right in shape and type, wrong in value: the reference solution's result 0.01 off."""
    renamed, n = re.subn(rf"\bdef {function}\(", f"def _{function}_right(", answer_source, count=1)
    assert n == 1, answer_source[:200]
    return renamed + _SLIP.format(function=function)


HANDED_IN = "2026-01-05 09:00:00.000000 UTC"


def _class(course, stem) -> dict[str, str]:
    """Hand in a class's submissions of ``stem``: for every lesson the source version ("right"), the released
    one ("untouched") and the source with one exercise wrong ("wrong"); for lesson 00 also a deleted cell, an
    answer raising at import, an endless loop and three folders nbgrader cannot grade. Returns the exercises
    the mistakes are in."""
    src = nbformat.read(str(course / "source" / stem / f"{stem}.ipynb"), as_version=4)
    released = course / "release" / stem / f"{stem}.ipynb"
    checked = _checked(stem)

    def hand_in(student, nb=None, raw=None, name=f"{stem}.ipynb"):
        d = course / "submitted" / student / stem
        d.mkdir(parents=True, exist_ok=True)
        (d / "timestamp.txt").write_text(HANDED_IN)  # as `nbgrader collect` leaves it
        if raw is not None:
            (d / name).write_text(raw, encoding="utf-8")
        elif nb is not None:
            nbformat.write(nb, str(d / name))

    hand_in("right", src)
    shutil.copytree(released.parent, course / "submitted" / "untouched" / stem)
    (course / "submitted" / "untouched" / stem / "timestamp.txt").write_text(HANDED_IN)
    slip = _wrong_exercise(stem)
    wrong = _copy(src)
    _answer(wrong, slip).source = _slip(_answer(wrong, slip).source, slip)
    hand_in("wrong", wrong)
    if stem == CHEATED:
        _cheats(src, hand_in)
    if stem != STEMS[0]:
        return {"wrong": slip}
    first, second = checked[0].function, checked[1].function
    deleted = _copy(src)   # the first tests cell and the second answer gone
    deleted.cells = [c for c in deleted.cells if _grading(c).get("grade_id") not in (f"{first}_tests", second)]
    hand_in("deleted", deleted)
    raises = _copy(src)
    _answer(raises, first).source = "import posekit_has_no_such_module\n\n" + _answer(raises, first).source
    hand_in("raises", raises)
    loops = _copy(src)  # loops forever, asleep: the timeout ends it, without a busy core meanwhile
    _answer(loops, second).source = _answer(loops, second).source.replace(
        "### BEGIN SOLUTION\n", "### BEGIN SOLUTION\n    import time\n    while True:\n        time.sleep(1)\n")
    hand_in("loops", loops)
    hand_in("other", nbformat.read(str(course / "release" / STEMS[1] / f"{STEMS[1]}.ipynb"), as_version=4))
    hand_in("broken", raw='{"cells": [\n  {"cell_type": "code",\n  oops\n')
    hand_in("empty")
    (course / "submitted" / "empty" / stem / "notes.txt").write_text("I forgot")
    return {"wrong": slip, "first": first, "second": second}


CHEATED = "01_fabrik"
"""The lesson whose class also holds the cheats of :func:`_cheats`."""
CHEATS = ("patches", "borrows")


def _cheats(src, hand_in) -> None:
    """Two students of lesson 01 who try to earn points without the work (the three cheats an instructor saw):

    * ``patches``: exercise 1's answer cell rebinds the checker to one that always passes (the kernel's tests
      cell then gives the point); exercise 2 calls posekit's own ``two_bone_ik``, the function it is compared
      against;
    * ``borrows``: exercise 1 imports the reference solution from where it used to ship; exercise 2 is left as
      released, but its tests cell is edited to award the point whatever happens.
    """
    stub1 = "def exercise_fabrik_planted(positions, target, tolerance, max_iter):\n    raise NotImplementedError\n"
    patches = _copy(src)
    _answer(patches, "exercise_fabrik_planted").source = (
        "import posekit.exercises\nposekit.exercises.check_fabrik_planted = lambda f: True\n\n" + stub1)
    _answer(patches, "exercise_two_bone_swivel").source = (
        "def exercise_two_bone_swivel(root, mid, end, target, swivel):\n"
        "    from posekit.exercises.nb01 import swivel_pole\n"
        "    from posekit.ik.two_bone import two_bone_ik\n"
        "    return two_bone_ik(root, mid, end, target, swivel_pole(root, mid, target, swivel))[:2]\n")
    hand_in("patches", patches)
    borrows = _copy(src)
    _answer(borrows, "exercise_fabrik_planted").source = (
        "from posekit.exercises.solutions.nb01 import exercise_fabrik_planted\n")
    _answer(borrows, "exercise_two_bone_swivel").source = (
        "def exercise_two_bone_swivel(root, mid, end, target, swivel):\n    raise NotImplementedError\n")
    _answer(borrows, "exercise_two_bone_swivel_tests").source = "1  # the points earned"
    hand_in("borrows", borrows)


CLASS_00 = ("right", "untouched", "wrong", "deleted", "raises", "loops", "other", "broken", "empty")
LOOP_TIMEOUT_S = 10
"""Lesson 00's cells take about a second each: a 10 s limit (not the course's 300 s) bounds what its endless loop costs."""


GRADED_AT_ONCE = max(1, len(os.sched_getaffinity(0)) // int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")))
"""Lessons graded side by side, each class in its own copy of the graded course (its own grade book, so that two
nbgrader processes never write one SQLite file): the cores this test file has to itself, one per core (two when it
runs alone on two cores; one under ``make test``, whose two workers already hold a core each, where a second
grading would only slow the other worker's tests)."""


def _grade_class(graded_course, stem, root):
    """Hands in the class of ``stem`` (:func:`_class`) in a copy of the graded course at ``root``, autogrades all of
    it with one ``posekit course autograde`` (nbgrader's ``autograde`` behind the screening) and exports the grade
    book (``nbgrader export`` for lesson 00, its CSV plugin in this process for the others: :func:`_export`).
    Returns ``(the course folder, what the class did, the finished command)``."""
    from nbgrader.api import Gradebook

    course = root / "course"
    shutil.copytree(graded_course, course)
    did = _class(course, stem)
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gb:  # the class list
        for student in CLASS_00 + CHEATS:
            gb.update_or_create_student(student)
    extra = ["--cell-timeout", str(LOOP_TIMEOUT_S)] if stem == STEMS[0] else []
    proc = _run([sys.executable, "-m", "posekit", "course", "autograde", stem, "--course", str(course), *extra],
                ROOT, ok=False)
    if stem == STEMS[0]:
        _nbgrader("export", cwd=course)  # grades.csv, read by _grades
    else:
        _export(course)
    return course, did, proc


def _export(course) -> None:
    """What ``nbgrader export`` does, in this process: nbgrader's CSV export plugin writes ``grades.csv`` from the
    course's grade book. The command itself runs for lesson 00's class; for the other lessons it would add about 5 s
    each (most of it nbgrader's start), to write the same file the same code writes here."""
    from nbgrader.api import Gradebook
    from nbgrader.plugins import CsvExportPlugin

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gb:
        CsvExportPlugin(to=str(course / "grades.csv")).export(gb)


def _stems_to_grade(items) -> list[str]:
    """The lessons whose classes the selected tests read (a test's ``stem`` parameter, or its ``grades`` mark), in
    the order the tests run."""
    out = []
    for item in items:
        if "graded" not in getattr(item, "fixturenames", ()):
            continue
        params = getattr(getattr(item, "callspec", None), "params", {})
        stems = [params["stem"]] if "stem" in params else [m.args[0] for m in item.iter_markers("grades")]
        out += [s for s in stems if s not in out]
    return out


@pytest.fixture(scope="module")
def graded(graded_course, request, tmp_path_factory):
    """``grade(stem)``: the class of ``stem`` graded (:func:`_grade_class`), once per lesson. On the first call every
    lesson the selected tests read is queued, :data:`GRADED_AT_ONCE` at a time, so the next lesson's class is being
    graded while a test reads this one's. ``grade.done()``: the lessons graded so far, ``{stem: result}``."""
    from concurrent.futures import ThreadPoolExecutor

    pool = ThreadPoolExecutor(max_workers=GRADED_AT_ONCE)
    futures = {}

    def queue(stem):
        if stem not in futures:
            futures[stem] = pool.submit(_grade_class, graded_course, stem, tmp_path_factory.mktemp(f"class-{stem}"))

    def grade(stem):
        for s in _stems_to_grade(request.session.items) + [stem]:
            queue(s)
        return futures[stem].result()

    grade.done = lambda: {s: f.result() for s, f in futures.items() if f.done()}
    yield grade
    pool.shutdown(wait=True, cancel_futures=True)


def _points(course, stem) -> dict[str, float]:
    """The autograded cells of ``stem`` and their points, as the source version gives them."""
    src = nbformat.read(str(course / "source" / stem / f"{stem}.ipynb"), as_version=4)
    return {_grading(c)["grade_id"]: float(_grading(c)["points"]) for c in src.cells
            if c.cell_type == "code" and _grading(c).get("grade")}


def _grades(course) -> dict[tuple[str, str], dict]:
    """The grade book as ``nbgrader export`` (or :func:`_export`, its CSV plugin) wrote it to ``grades.csv``
    (:func:`_grade_class` runs it after grading), by ``(assignment, student)``."""
    with open(course / "grades.csv", newline="") as fh:
        return {(r["assignment"], r["student_id"]): r for r in csv.DictReader(fh)}


def _cell_scores(course, stem, student) -> dict[str, float]:
    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gb:
        nb = gb.find_submission_notebook(stem, stem, student)
        return {g.name: g.auto_score for g in nb.grades if g.cell.cell_type == "code"}


def _code_score(course, stem, student) -> tuple[float, float]:
    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gb:
        sub = gb.find_submission(stem, student)
        return sub.code_score, sub.max_code_score


def _errors(course, stem, student) -> list[str]:
    nb = nbformat.read(str(course / "autograded" / student / stem / f"{stem}.ipynb"), as_version=4)
    return [f"{_grading(c).get('grade_id')}: {o.get('ename')}" for c in nb.cells if c.cell_type == "code"
            for o in c.outputs if o.output_type == "error"]


def _outputs(course, stem, student, grade_id) -> str:
    nb = nbformat.read(str(course / "autograded" / student / stem / f"{stem}.ipynb"), as_version=4)
    cell = next(c for c in nb.cells if _grading(c).get("grade_id") == grade_id)
    return "\n".join(o.get("ename", "") + o.get("text", "") + str(o.get("data", {}).get("text/plain", ""))
                     for o in cell.outputs)


@pytest.mark.slow
@pytest.mark.parametrize("stem", STEMS)
def test_autograde_gives_the_source_full_marks_the_released_none_and_one_wrong_answer_loses_its_points(graded, stem):
    course, did, proc = graded(stem)
    assert proc.returncode == (1 if stem == STEMS[0] else 0), proc.stdout + proc.stderr  # 00: 3 folders refused
    points = _points(course, stem)
    total = sum(points.values())
    assert len(points) == len(_checked(stem)) and total > 0
    # the source version earns every autograded point, and runs top to bottom without an error
    assert _cell_scores(course, stem, "right") == points
    assert _code_score(course, stem, "right") == (total, total)
    assert _errors(course, stem, "right") == []
    # the released version earns none: each answer is "not attempted yet", and it too runs without an error
    assert _cell_scores(course, stem, "untouched") == dict.fromkeys(points, 0)
    assert _code_score(course, stem, "untouched") == (0, total)
    assert _errors(course, stem, "untouched") == []
    for test in points:
        assert "not attempted yet" in _outputs(course, stem, "untouched", test)
    # one answer wrong in value (right in shape): exactly that exercise's points are lost, the checker says why
    slip = f"{did['wrong']}_tests"
    assert _cell_scores(course, stem, "wrong") == {**points, slip: 0}
    assert _code_score(course, stem, "wrong") == (total - points[slip], total)
    assert _errors(course, stem, "wrong") == []
    assert "✗ check_" in _outputs(course, stem, "wrong", slip)


@pytest.mark.slow
@pytest.mark.grades(STEMS[0])
def test_autograde_reports_a_students_mistakes_and_bad_folders_and_export_writes_every_grade(graded):
    a = STEMS[0]
    course, did, proc = graded(a)
    for student in ("other", "broken", "empty"):  # named on the terminal, each with its reason
        assert re.search(rf"refused {student}: .*submitted/{student}/{a}.*counts as missing", proc.stderr), \
            proc.stderr
    assert re.search(r"refused broken: .*not JSON: .* at line 3", proc.stderr), proc.stderr
    assert re.search(r"refused other: .*lesson 01's notebook, expected lesson 00", proc.stderr), proc.stderr
    points = _points(course, a)
    total = sum(points.values())
    first, second = f"{did['first']}_tests", f"{did['second']}_tests"
    # a deleted tests cell is put back by nbgrader and graded; a deleted answer is an error worth 0
    assert _cell_scores(course, a, "deleted") == {**points, second: 0}
    assert "NameError" in _outputs(course, a, "deleted", second)
    # an answer raising at import: its error is shown, the rest is graded
    assert _cell_scores(course, a, "raises") == {**points, first: 0}
    assert "ModuleNotFoundError" in _outputs(course, a, "raises", did["first"])
    # an endless loop is interrupted after the per-cell timeout; the cells after it still run
    assert _cell_scores(course, a, "loops") == {**points, second: 0}
    assert re.search(r"KeyboardInterrupt|CellTimeoutError", _outputs(course, a, "loops", second))
    assert {e.split(":")[0] for e in _errors(course, a, "loops")} == {second}  # only that cell's error
    # export: one row per student of the class list, the refused folders graded as missing (0, no timestamp)
    grades = _grades(course)
    expected = {"right": total, "untouched": 0, "wrong": total - points[f"{did['wrong']}_tests"],
                "deleted": total - points[second], "raises": total - points[first], "loops": total - points[second],
                "other": 0, "broken": 0, "empty": 0}
    assert {s: float(grades[(a, s)]["raw_score"]) for s in CLASS_00} == expected
    for student in ("other", "broken", "empty"):
        assert grades[(a, student)]["timestamp"] == ""
        assert not (course / "autograded" / student / a).exists()
    assert all(grades[(a, s)]["timestamp"].startswith(HANDED_IN[:10]) for s in CLASS_00[:6])
    for stem, (other, _, _) in graded.done().items():  # and every other lesson graded (all of them in a full run)
        exported = _grades(other)
        for student in ("right", "untouched", "wrong"):
            assert float(exported[(stem, student)]["raw_score"]) == _code_score(other, stem, student)[0]


def _flagged(course, stem, student) -> bool:
    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gb:
        return bool(gb.find_submission_notebook(stem, stem, student).flagged)


@pytest.mark.slow
@pytest.mark.grades(CHEATED)
def test_the_three_cheats_score_nothing_and_are_flagged_and_an_honest_class_is_not(graded):
    course, did, proc = graded(CHEATED)
    points = _points(course, CHEATED)
    assert set(points) == {"exercise_fabrik_planted_tests", "exercise_two_bone_swivel_tests"}
    for student in CHEATS:
        assert _cell_scores(course, CHEATED, student) == dict.fromkeys(points, 0), student
        assert _code_score(course, CHEATED, student)[0] == 0
        assert _flagged(course, CHEATED, student), student
    # the rebound checker fooled the student's own kernel: the fresh process did not take its word
    assert re.search(r"flagged patches / 01_fabrik / exercise_fabrik_planted: the kernel's tests cell gave 1 of 1, a "
                     r"fresh process 0 \(kept\)", proc.stderr), proc.stderr
    assert re.search(r"flagged patches / 01_fabrik / exercise_fabrik_planted: the answer touches the grading "
                     r"machinery \(line 2: posekit\.exercises\.check_fabrik_planted = ", proc.stderr), proc.stderr
    # calling the function the checker compares against is refused, in the kernel as in the fresh check
    assert "calls posekit.ik.two_bone.two_bone_ik, the function it is compared against" in \
        _outputs(course, CHEATED, "patches", "exercise_two_bone_swivel_tests")
    # the solutions are not in the package a student imports
    assert "ModuleNotFoundError" in _outputs(course, CHEATED, "borrows", "exercise_fabrik_planted")
    # an edited tests cell is put back by nbgrader, and flagged by name
    assert re.search(r"flagged borrows / 01_fabrik / exercise_two_bone_swivel_tests: read-only cell changed",
                     proc.stderr), proc.stderr
    for student in ("right", "untouched", "wrong"):  # honest work is never flagged
        assert not _flagged(course, CHEATED, student), student
        assert f"flagged {student} /" not in proc.stderr
    grades = _grades(course)
    assert all(float(grades[(CHEATED, s)]["raw_score"]) == 0 for s in CHEATS)
