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

    rows = build_slides(args.out, progress=sys.stderr.isatty())
    print(f"{'lesson':<7}{'slides':>7}  {'key figure':<11}file")
    for r in rows:
        print(f"{r['lesson']:<7}{r['slides']:>7}  {'yes' if r['key_figure'] else 'MISSING':<11}{r['path']}")
    return 0 if all(r["key_figure"] for r in rows) else 1


def _course_build(args) -> int:
    from .build import build_course

    index = build_course(args.out, progress=sys.stderr.isatty())
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

    course = sub.add_parser("course", help="lecture slides and the static course page (instructors)")
    csub = course.add_subparsers(dest="cmd", required=True)
    p = csub.add_parser("slides", help="every lesson as reveal.js slides, from its stored outputs")
    p.add_argument("--out", default=str(Path("build") / "course"), help="course folder (default build/course)")
    p.set_defaults(fn=_course_slides)
    p = csub.add_parser("build", help="the course page: lessons, slides, benchmark report, openable from disk")
    p.add_argument("--out", default=str(Path("build") / "course"), help="course folder (default build/course)")
    p.set_defaults(fn=_course_build)
    p = csub.add_parser("mark", help="apply the slide convention to notebooks (cell metadata)")
    p.add_argument("notebooks", nargs="+")
    p.add_argument("--check", action="store_true", help="write nothing; exit 1 if a notebook differs")
    p.set_defaults(fn=_course_mark)
