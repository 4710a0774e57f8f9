"""Grading that a student's kernel cannot talk round: every autograded exercise checked again in a fresh process.

Under ``nbgrader autograde`` the tests cell runs in the student's own kernel, after the student's cells. Whatever
those cells did to that kernel, the tests cell inherits: an answer cell that rebinds the checker
(``posekit.exercises.check_two_bone = lambda f: True``) or the function it compares against earns the points there.
So ``posekit course autograde`` does not take the kernel's word for it (:func:`regrade`):

* **a fresh check**: for each autograded exercise, the answer cell's source (from the submitted notebook) is run in
  a new Python process, with the lesson's imports (from its read-only cells) before it, and the lesson's checker
  judges it from another process that holds the expected answers and never runs the answer
  (:mod:`posekit.exercises._judge`); the points in the grade book are the fresh check's;
* **flags for a person**: the submission is flagged in the grade book (the formgrader lists flagged notebooks) and
  the answer cell gets an automatic comment when the fresh check and the kernel disagree, when a read-only cell
  (a lesson's cell, a tests cell) was changed or deleted in what the student handed in (nbgrader restores it before
  grading and only logs a warning), or when an answer reaches for the grading machinery (``sys.modules``,
  ``setattr`` on posekit, ``sys.setprofile``, frames, ``ctypes``, the instructor's folder).

The checkers themselves refuse an answer that calls the posekit function it is compared against or changes its
inputs (:mod:`posekit.exercises._check`). An answer can still attack its own process (and so what the kernel
prints); the points the grade book keeps come from the judge, and such code is in the answer cell, flagged, for the
instructor to read.
"""

from __future__ import annotations

import ast
import contextlib
import json
import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Finding", "fresh_check", "fresh_checks", "lesson_imports", "suspicious", "changed_read_only", "regrade"]

SUSPICIOUS = re.compile(
    r"sys\.modules|\bsetattr\s*\(|\bdelattr\s*\(|setprofile|settrace|_getframe|f_back|f_locals|\bctypes\b|"
    r"\bgc\.|\b__builtins__\b|\bbuiltins\b|\bimportlib\b|instructor|\bsolutions\b|posekit\.exercises|"
    r"\bcheck_\w+\s*=|\b_check\b|\bos\._exit\b")
"""What an answer needs no reason to touch: the grading machinery, the instructor's folder, other modules'
attributes. A match flags the submission for a person to read; it costs no points by itself."""


@dataclass
class Finding:
    """Something a person should look at in one submission."""

    student: str
    assignment: str
    cell: str
    reason: str

    def __str__(self) -> str:
        return f"{self.student} / {self.assignment} / {self.cell}: {self.reason}"


@dataclass
class Fresh:
    """The verdict of a fresh check: ``passed``, and what the checker printed (or why it could not run)."""

    passed: bool
    said: str = ""


def lesson_imports(cells) -> str:
    """The top-level ``import`` statements of ``cells`` (code cells' sources), in order, one per line."""
    lines = []
    for source in cells:
        try:
            tree = ast.parse(source)
        except SyntaxError:
            continue
        lines += [ast.unparse(node) for node in tree.body if isinstance(node, (ast.Import, ast.ImportFrom))]
    return "\n".join(dict.fromkeys(lines))


def suspicious(source: str) -> list[str]:
    """The lines of an answer that touch what :data:`SUSPICIOUS` names, as ``"line N: text"``."""
    return [f"line {k}: {line.strip()}" for k, line in enumerate(source.splitlines(), 1) if SUSPICIOUS.search(line)]


def fresh_check(lesson: str, checker: str, function: str, source: str, imports: str = "",
                timeout_s: float = 300) -> Fresh:
    """Run ``checker`` of lesson ``lesson`` on ``function`` as defined by ``source``, the key out of its reach.

    A judge process (``python -m posekit.exercises._judge --grade``, not dumpable) builds the checker's cases and
    expected answers and compares; the answer runs in a child of it that holds no expected answer and receives only
    each case's inputs (:mod:`posekit.exercises._judge`). Reading the judge's frames, patching the checker's module,
    threads, rebinding names: what the answer does happens in its own process and changes no comparison.

    Parameters
    ----------
    lesson : str
        Two digits, ``"01"``: the checker is ``posekit.exercises.nb01.<checker>``.
    checker, function : str
        ``check_...`` and ``exercise_...``.
    source : str
        The answer cell's source.
    imports : str
        Statements run before it (the lesson's imports, so that ``np`` means what the lesson says).
    timeout_s : float
        Seconds before the answer's process (and what it started) is killed (an endless loop fails the check).
    """
    job = {"lesson": lesson, "checker": checker, "function": function, "source": source, "imports": imports}
    return fresh_checks([job], timeout_s)[0]


def fresh_checks(jobs: list[dict], timeout_s: float = 300) -> list[Fresh]:
    """:func:`fresh_check` of many answers with one judge: ``jobs`` are dicts of its arguments (``lesson``,
    ``checker``, ``function``, ``source``, ``imports``); one :class:`Fresh` each, in order.

    The judge starts (and imports the checkers) once; each answer still runs in an executor process of its own, which
    the judge kills after ``timeout_s`` seconds. Should the judge itself stop answering (``timeout_s`` and a minute
    more for one verdict) or die, it is killed and a new one takes the jobs left.
    """
    import queue
    import threading

    def pump(stream, sink) -> None:
        for line in stream:
            sink(line)
        sink(None)

    out: list[Fresh] = []
    env = {k: v for k, v in os.environ.items() if not k.startswith("JPY_")}
    env.setdefault("MPLBACKEND", "Agg")
    while len(out) < len(jobs):  # a judge for the jobs left
        proc = subprocess.Popen([sys.executable, "-m", "posekit.exercises._judge", "--grade"], stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                                start_new_session=True)
        verdicts: queue.Queue = queue.Queue()
        said: list[str] = []
        threading.Thread(target=pump, args=(proc.stdout, verdicts.put), daemon=True).start()
        err = threading.Thread(target=pump, args=(proc.stderr, lambda x: said.append(x or "")), daemon=True)
        err.start()
        hung = False
        try:
            while len(out) < len(jobs):
                try:
                    proc.stdin.write(json.dumps({**jobs[len(out)], "timeout_s": timeout_s}) + "\n")
                    proc.stdin.flush()
                except OSError:  # the judge is gone: its verdicts so far are all there is
                    pass
                try:
                    line = verdicts.get(timeout=timeout_s + 60)
                except queue.Empty:
                    hung = True
                    out.append(Fresh(False, f"the fresh check ran past {timeout_s:g} s and was stopped"))
                    break
                try:
                    verdict = json.loads(line) if line else None
                except ValueError:
                    verdict = None
                if not isinstance(verdict, dict):  # the judge died (or wrote something else): why, and a new one
                    if line is None:
                        with contextlib.suppress(subprocess.TimeoutExpired):
                            proc.wait(timeout=10)
                        err.join(timeout=10)
                    out.append(Fresh(False, ("".join(said).strip().splitlines() or ["no verdict"])[-1]))
                    break
                out.append(Fresh(verdict.get("passed") is True, str(verdict.get("said", ""))))
        finally:
            with contextlib.suppress(OSError):
                proc.stdin.close()
            try:
                proc.wait(timeout=0 if hung else 30)
            except subprocess.TimeoutExpired:
                with contextlib.suppress(OSError):
                    os.killpg(proc.pid, 9)
                proc.wait()
    return out


def _grading(cell) -> dict:
    return cell.get("metadata", {}).get("nbgrader", {}) or {}


def changed_read_only(released, submitted) -> list[tuple[str, str]]:
    """The read-only cells (locked, or autograder tests) of ``released`` that ``submitted`` changed or deleted.

    Returns ``(grade_id, "changed" | "deleted")`` pairs. nbgrader puts them back before grading; this says that it
    had to.
    """
    theirs = {_grading(c).get("grade_id"): c for c in submitted.get("cells", []) if _grading(c).get("grade_id")}
    out = []
    for c in released.cells:
        g = _grading(c)
        if not g.get("grade_id") or g.get("solution") or not (g.get("locked") or g.get("grade")):
            continue
        mine = theirs.get(g["grade_id"])
        if mine is None:
            out.append((g["grade_id"], "deleted"))
        elif "".join(mine.get("source", "")).strip() != "".join(c.source).strip():
            out.append((g["grade_id"], "changed"))
    return out


def regrade(course_dir, assignment: str, students=None, timeout_s: float = 300) -> list[Finding]:
    """Check every autograded exercise of ``assignment`` again in a fresh process, set the grade book's points
    to the fresh verdicts, and flag what a person should read.

    Run after ``nbgrader autograde`` (``posekit course autograde`` does). For each autograded submission
    (``autograded/<student>/<assignment>/``) and each tests cell ``<exercise>_tests``: the answer cell
    ``<exercise>`` is checked by :func:`fresh_check`; the tests cell's automatic score becomes its points when it
    passes, else 0. The submitted notebook is flagged when the fresh check and the kernel disagree, when a read-only
    cell was changed or deleted, or when an answer matches :data:`SUSPICIOUS`; the answer cell's automatic comment
    says why.

    Returns
    -------
    list of Finding
        Everything flagged, for the command to print.
    """
    import nbformat
    from nbgrader.api import Gradebook, MissingEntry

    from .lessons import find_lesson

    course_dir = Path(course_dir)
    lesson = find_lesson(assignment)
    released = nbformat.read(str(course_dir / "release" / assignment / f"{assignment}.ipynb"), as_version=4)
    tests = [c for c in released.cells if _grading(c).get("grade") and c.cell_type == "code"]
    findings = []
    with Gradebook(f"sqlite:///{course_dir / 'gradebook.db'}") as gb:
        todo = []  # per submission: (student, its notebook, read-only findings, [(function, grade, job, source)])
        jobs = []
        for folder in sorted((course_dir / "autograded").glob(f"*/{assignment}")):
            student = folder.parent.name
            if students and student not in students:
                continue
            path = folder / f"{assignment}.ipynb"
            if not path.is_file():
                continue
            graded = nbformat.read(str(path), as_version=4)
            try:
                sub_nb = gb.find_submission_notebook(assignment, assignment, student)
            except MissingEntry:
                continue
            handed = course_dir / "submitted" / student / assignment / f"{assignment}.ipynb"
            try:
                handed_in = json.loads(handed.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                handed_in = {"cells": []}
            changed = [Finding(student, assignment, grade_id,
                               f"read-only cell {how} by the student (nbgrader put it back before grading)")
                       for grade_id, how in changed_read_only(released, handed_in)]
            cells = graded.cells
            checks = []
            for test in tests:
                test_id = _grading(test)["grade_id"]
                function = test_id[:-len("_tests")] if test_id.endswith("_tests") else None
                checker = re.search(r"\b(check_\w+)\(", test.source)
                k = next((i for i, c in enumerate(cells) if _grading(c).get("grade_id") == function), None)
                grade = gb.find_grade(test_id, assignment, assignment, student)
                if function is None or checker is None:
                    continue
                if k is None:
                    checks.append((function, grade, Fresh(False, "no answer cell"), ""))
                    continue
                source = cells[k].source
                imports = lesson_imports(c.source for c in cells[:k]  # the lesson's own cells, not answers
                                         if c.cell_type == "code" and not _grading(c).get("solution")
                                         and _grading(c).get("locked"))
                checks.append((function, grade, len(jobs), source))
                jobs.append({"lesson": lesson.number, "checker": checker.group(1), "function": function,
                             "source": source, "imports": imports})
            todo.append((student, sub_nb, changed, checks))
        verdicts = fresh_checks(jobs, timeout_s) if jobs else []  # one judge for the lesson, an executor per answer
        for student, sub_nb, changed, checks in todo:
            findings += changed
            notes: dict[str, list[str]] = {}
            for function, grade, job, source in checks:
                fresh = job if isinstance(job, Fresh) else verdicts[job]
                for line in suspicious(source):
                    notes.setdefault(function, []).append(f"the answer touches the grading machinery ({line})")
                kernel_points = grade.auto_score or 0
                points = grade.max_score
                fresh_points = points if fresh.passed else 0
                if fresh_points != kernel_points:
                    notes.setdefault(function, []).append(
                        f"the kernel's tests cell gave {kernel_points:g} of {points:g}, "
                        f"a fresh process {fresh_points:g}"
                        f" (kept): {fresh.said.strip().splitlines()[-1] if fresh.said.strip() else 'no verdict'}")
                grade.auto_score = fresh_points
            for function, reasons in notes.items():
                for reason in reasons:
                    findings.append(Finding(student, assignment, function, reason))
                try:
                    comment = gb.find_comment(function, assignment, assignment, student)
                    comment.auto_comment = "Flagged for the instructor: " + "; ".join(reasons)
                except MissingEntry:
                    pass
            if any(f.student == student for f in findings):
                sub_nb.flagged = True
            gb.db.commit()
    return findings

