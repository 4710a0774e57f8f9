"""The instructor kit's commands, registered on ``posekit``'s command line by :func:`add_commands`.

``posekit exercises list [--json]``
    Every lesson's exercises: checked (function, checker) or open, and whether its solution exists.
``posekit exercises solutions LESSON|all [--out DIR] [--no-execute] [--html]``
    The instructor version of a lesson, solutions filled in and executed (``build/instructor/``).
``posekit course slides [--out DIR]``
    Every lesson as reveal.js slides (``build/course/slides/``), with slide counts and key figures.
``posekit course build [--out DIR]``
    The static course page with every lesson, its slides and the benchmark report (``build/course/``).
``posekit course mark NOTEBOOK ... [--check]``
    Apply the slide convention to notebooks (``--check``: only say which differ, exit 1 if any).
``posekit course nbgrader [--out DIR] [--lesson N ...] [--force] [--cell-timeout S] [--trial [--results FILE]]``
    The lessons as an nbgrader course directory (``build/nbgrader/``); ``--trial`` also autogrades one
    submission of each lesson with nbgrader and writes the times (``DIR/autograde_trial.json``).
``posekit course autograde LESSON [--course DIR] [--student ID] [--force] [--cell-timeout S]``
    ``nbgrader autograde LESSON`` after refusing, by name, the student folders it cannot grade.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

__all__ = ["add_commands"]


def _exercises_list(args) -> int:
    from .lessons import lessons, read_notebook
    from .solutions import exercises, notes, solution_function

    rows = []
    for lesson in lessons():
        open_notes = notes(lesson)
        for ex in exercises(read_notebook(lesson.path)):
            if ex.open:
                has = bool(open_notes.get(ex.number))
            else:
                try:
                    solution_function(lesson, ex.function)
                    has = True
                except (LookupError, ImportError):
                    has = False
            rows.append({"lesson": lesson.number, "exercise": ex.number, "kind": "open" if ex.open else "checked",
                         "function": ex.function, "checker": ex.checker, "solution": has})
    if args.json:
        print(json.dumps(rows, indent=2))
    else:
        print(f"{'lesson':<7}{'ex':>3}  {'kind':<8}{'function':<26}{'checker':<24}solution")
        for r in rows:
            print(f"{r['lesson']:<7}{r['exercise']:>3}  {r['kind']:<8}{r['function'] or '—':<26}"
                  f"{r['checker'] or '(instructor notes)':<24}{'yes' if r['solution'] else 'MISSING'}")
    return 0 if all(r["solution"] for r in rows) else 1


def _verdicts(nb) -> list[str]:
    lines = []
    for cell in nb.cells:
        for o in cell.get("outputs", []):
            text = o.get("text", "") if o.get("output_type") == "stream" else ""
            lines += [ln for ln in text.splitlines() if ln.startswith(("✓ check_", "✗ check_", "… check_"))]
    return lines


def _exercises_solutions(args) -> int:
    import nbformat

    from . import slides as slide_rules
    from .build import copy_assets
    from .lessons import find_lesson, lessons
    from .solutions import render

    chosen = lessons() if args.lesson == "all" else [find_lesson(args.lesson)]
    out = Path(args.out)
    for lesson in chosen:
        if not args.no_execute:
            print(f"lesson {lesson.number}: executing the instructor version (the lesson ran in "
                  f"{lesson.run_s or '?'} s when its outputs were made) ...", file=sys.stderr)
        try:
            path = render(lesson, out, execute=not args.no_execute)
        except LookupError as e:
            print(f"posekit: error: {e}", file=sys.stderr)
            return 2
        except Exception as e:  # nbconvert's CellExecutionError: a cell (a solution's assert) failed
            if type(e).__name__ != "CellExecutionError":
                raise
            print(f"posekit: lesson {lesson.number}'s instructor version failed to run:\n{e}", file=sys.stderr)
            return 1
        nb = nbformat.read(str(path), as_version=4)
        for line in _verdicts(nb):
            print(f"  {line}")
        print(f"wrote {path}")
        if args.html:
            copy_assets(out)
            page = path.with_suffix(".html")
            page.write_text(slide_rules.export(nb, "page", static="_static"), encoding="utf-8")
            print(f"wrote {page}")
    return 0


def _course_slides(args) -> int:
    from .build import build_slides

    rows = build_slides(args.out, progress=sys.stderr.isatty(), instructor=args.instructor)
    print(f"{'lesson':<7}{'slides':>7}  {'key figure':<11}file")
    for r in rows:
        print(f"{r['lesson']:<7}{r['slides']:>7}  {'yes' if r['key_figure'] else 'MISSING':<11}{r['path']}")
    return 0 if all(r["key_figure"] for r in rows) else 1


def _course_build(args) -> int:
    from .build import build_course

    index = build_course(args.out, progress=sys.stderr.isatty(), instructor=args.instructor)
    print(f"wrote {index} (open it in a browser: file://{index.resolve()})")
    return 0


def _course_mark(args) -> int:
    import nbformat

    from .lessons import read_notebook
    from .slides import mark

    differ = []
    for name in args.notebooks:
        nb = read_notebook(name)
        marked = nbformat.from_dict(mark(nb))
        if marked != nb:
            differ.append(name)
            if not args.check:
                nbformat.write(marked, name)
    verb = "differ from the slide convention" if args.check else "marked"
    print(f"{verb}: {', '.join(differ) if differ else 'none'}")
    return 1 if args.check and differ else 0


def _course_nbgrader(args) -> int:
    from .lessons import find_lesson
    from .nbgrader import trial, write_course

    chosen = [find_lesson(k) for k in args.lesson] if args.lesson else None
    for path in write_course(args.out, chosen, force=args.force, cell_timeout_s=args.cell_timeout):
        print(f"wrote {path}")
    print(f"course directory: {args.out} (next: cd {args.out} && nbgrader generate_assignment <lesson>)")
    if not args.trial:
        return 0
    results = trial(args.out, chosen, progress=sys.stderr.isatty(),
                    command="posekit " + " ".join(sys.argv[1:]))
    out = Path(args.results) if args.results else Path(args.out) / "autograde_trial.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n", encoding="utf-8")
    print(f"{'lesson':<25}{'autograde s':>12}{'score':>8}")
    for r in results["lessons"]:
        print(f"{r['assignment']:<25}{r['autograde_s']:>12.1f}{r['score']:>5g}/{r['max_score']:g}")
    print(f"wrote {out}")
    return 0 if all(r["score"] == r["max_score"] for r in results["lessons"]) else 1


def _course_autograde(args) -> int:
    from .lessons import find_lesson
    from .nbgrader import autograde

    course = Path(args.course)
    if not (course / "nbgrader_config.py").is_file():
        print(f"posekit: error: {course} is not a course directory (no nbgrader_config.py; make one with "
              "`posekit course nbgrader --out DIR`)", file=sys.stderr)
        return 2
    extra = (f"--Execute.timeout={args.cell_timeout}",) if args.cell_timeout else ()
    rc, refused, findings = autograde(course, find_lesson(args.lesson).stem, student=args.student,
                                      force=args.force, extra=extra, cell_timeout_s=args.cell_timeout)
    for r in refused:
        print(f"refused {r.student}: {r}", file=sys.stderr)
    for f in findings:
        print(f"flagged {f}", file=sys.stderr)
    if findings:
        print(f"{len(findings)} finding(s) flagged in the grade book: the formgrader lists the flagged notebooks; "
              "the points kept are the fresh process's", file=sys.stderr)
    return rc or (1 if refused else 0)


def add_commands(sub) -> None:
    """Register the ``exercises`` and ``course`` command groups on ``posekit``'s subparsers ``sub``."""
    ex = sub.add_parser("exercises", help="the lessons' exercises and their reference solutions (instructors)")
    esub = ex.add_subparsers(dest="cmd", required=True)
    p = esub.add_parser("list", help="every exercise, checked or open, and whether its solution exists")
    p.add_argument("--json", action="store_true")
    p.set_defaults(fn=_exercises_list)
    p = esub.add_parser("solutions", help="a lesson's instructor version: solutions filled in and executed")
    p.add_argument("lesson", help="lesson number (00-06), notebook name, or 'all'")
    p.add_argument("--out", default=str(Path("build") / "instructor"), help="folder (default build/instructor)")
    p.add_argument("--no-execute", action="store_true", help="fill the solutions in without running the lesson")
    p.add_argument("--html", action="store_true", help="also write a static HTML page next to the notebook")
    p.set_defaults(fn=_exercises_solutions)

    course = sub.add_parser("course",
                            help="lecture slides, the static course page and the nbgrader course (instructors)")
    csub = course.add_subparsers(dest="cmd", required=True)
    instructor_help = ("the instructor's version: the exercises' reference solutions and notes in the speaker notes "
                       "(and, for build, the lessons' instructor pages); never give it to students. Default: the "
                       "students' version, with no solution in it")
    p = csub.add_parser("slides", help="every lesson as reveal.js slides, from its stored outputs")
    p.add_argument("--out", default=str(Path("build") / "course"), help="course folder (default build/course)")
    p.add_argument("--instructor", action="store_true", help=instructor_help)
    p.set_defaults(fn=_course_slides)
    p = csub.add_parser("build", help="the course page: lessons, slides, benchmark report, openable from disk")
    p.add_argument("--out", default=str(Path("build") / "course"), help="course folder (default build/course)")
    p.add_argument("--instructor", action="store_true", help=instructor_help)
    p.set_defaults(fn=_course_build)
    p = csub.add_parser("mark", help="apply the slide convention to notebooks (cell metadata)")
    p.add_argument("notebooks", nargs="+")
    p.add_argument("--check", action="store_true", help="write nothing; exit 1 if a notebook differs")
    p.set_defaults(fn=_course_mark)
    p = csub.add_parser("nbgrader", help="the lessons as an nbgrader course directory (one assignment per lesson)")
    p.add_argument("--out", default=str(Path("build") / "nbgrader"), help="course folder (default build/nbgrader)")
    p.add_argument("--lesson", action="append", help="only this lesson (number or name; repeat for more)")
    p.add_argument("--force", action="store_true", help="also rewrite an existing nbgrader_config.py")
    p.add_argument("--cell-timeout", type=int, default=300,
                   help="seconds a cell may run under autograde before it is interrupted (default 300)")
    p.add_argument("--trial", action="store_true",
                   help="then autograde each lesson's source version with nbgrader and write the times")
    p.add_argument("--results", help="where --trial writes its JSON (default OUT/autograde_trial.json)")
    p.set_defaults(fn=_course_nbgrader)
    p = csub.add_parser("autograde", help="nbgrader autograde LESSON, refusing by name the folders it cannot grade, "
                                         "then every exercise checked again in a fresh process, flags in the grade book")
    p.add_argument("lesson", help="the assignment: a lesson's number or notebook stem (01 or 01_fabrik)")
    p.add_argument("--course", default=str(Path("build") / "nbgrader"), help="course folder (default build/nbgrader)")
    p.add_argument("--student", help="only this student's submission")
    p.add_argument("--force", action="store_true", help="grade again a submission already autograded")
    p.add_argument("--cell-timeout", type=int,
                   help="seconds a cell may run before it is interrupted (default: the course's nbgrader_config.py)")
    p.set_defaults(fn=_course_autograde)
