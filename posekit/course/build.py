"""The course build: slides (``make slides``) and a static course page (``make course``).

Everything is made from the lessons as stored — executed notebooks whose outputs nbval checks — so
slides and pages show the measured numbers. The output folder opens from disk with no server::

    build/course/index.html             the course page: lessons, slides, the benchmark report
    build/course/lessons/NN_name.html   each lesson as one page
    build/course/slides/NN_name.html    each lesson as reveal.js slides (a lecture deck: posekit/course/lecture.py)
    build/course/solutions/NN_name.html each lesson's instructor version: solutions and notes pasted in, not run
    build/course/report/bench_all.html  lesson 06's benchmark report (data_samples/results)
    build/course/_static/               reveal.js and MathJax, copied from ``make course-assets``
"""

from __future__ import annotations

import html
import shutil
from pathlib import Path

from ..paths import course_assets_dir, samples_dir
from . import slides as slide_rules
from .lessons import Lesson, lessons, read_notebook

__all__ = ["copy_assets", "build_slides", "build_pages", "build_solutions", "build_report", "build_course",
           "DEFAULT_OUT"]

DEFAULT_OUT = Path("build") / "course"
_REVEAL = ("dist", "plugin/notes")
_MATHJAX = "es5/tex-svg-full.js"


def _copy_if_changed(src: Path, dst: Path) -> None:
    if not dst.is_file() or dst.stat().st_size != src.stat().st_size:
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(src, dst)


def copy_assets(out) -> Path:
    """Copy reveal.js (``dist/``, the notes plugin) and MathJax's SVG build into ``out/_static``.

    Files already there with the same size are left alone, so every builder may call it.
    """
    src, static = course_assets_dir(), Path(out) / "_static"
    for part in _REVEAL:
        dst = static / "reveal.js" / part
        if not dst.exists():
            shutil.copytree(src / "reveal.js" / part, dst, ignore=shutil.ignore_patterns("*.map", "*.esm.js"))
    _copy_if_changed(src / "mathjax" / _MATHJAX, static / "mathjax" / Path(_MATHJAX).name)
    for pkg in ("reveal.js", "mathjax"):  # their licences travel with them
        _copy_if_changed(src / pkg / "LICENSE", static / f"{pkg.replace('.js', '')}-LICENSE.txt")
    return static


def _progress(items, desc, progress):
    if not progress:
        return items
    from tqdm.auto import tqdm
    return tqdm(items, desc=desc, unit="lesson")


def build_slides(out=DEFAULT_OUT, only=None, progress: bool = True, instructor: bool = False) -> list[dict]:
    """Write every lesson's reveal.js slides to ``out/slides/NN_name.html``.

    Parameters
    ----------
    out : path
        The course folder.
    only : list of Lesson, optional
        Default: every lesson.
    instructor : bool
        The instructor's decks: the exercises' solutions and notes in the speaker notes. Default: the students'
        decks, with none.

    Returns
    -------
    list of dict
        Per lesson: ``lesson``, ``path``, ``slides`` (count) and ``key_figure`` (whether the page holds the
        output of the cell tagged ``key-figure``).
    """
    out = Path(out)
    copy_assets(out)
    done = []
    for lesson in _progress(only or lessons(), "slides", progress):
        nb = read_notebook(lesson.path)
        page = slide_rules.export(nb, "slides", static="../_static", lesson=lesson, instructor=instructor)
        path = out / "slides" / f"{lesson.stem}.html"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(page, encoding="utf-8")
        key = nb.cells[slide_rules.key_figure_cell(nb)]
        done.append({"lesson": lesson.number, "path": path, "slides": slide_rules.count_slides(page),
                     "key_figure": all(html.escape(k, quote=False) in page or k in page
                                       for k in slide_rules.key_outputs(key))})
    return done


def build_pages(out=DEFAULT_OUT, only=None, progress: bool = True) -> list[Path]:
    """Write every lesson as one static page, ``out/lessons/NN_name.html``."""
    out = Path(out)
    copy_assets(out)
    paths = []
    for lesson in _progress(only or lessons(), "pages", progress):
        path = out / "lessons" / f"{lesson.stem}.html"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(slide_rules.export(read_notebook(lesson.path), "page", static="../_static",
                                                 back="../index.html"), encoding="utf-8")
        paths.append(path)
    return paths


SOLUTIONS_NOTE = ("**Not executed here**: the reference solutions and instructor notes are pasted in; "
                  "`make solutions` (or `posekit exercises solutions {n} --html`) runs this version and checks every "
                  "solution against its checker.")


def build_solutions(out=DEFAULT_OUT, only=None, progress: bool = True) -> list[Path]:
    """Write every lesson's instructor version as a page, ``out/solutions/NN_name.html``: the reference solutions
    and open-exercise notes pasted in (:func:`posekit.course.solutions.instructor_notebook`), not executed, so the
    course page stays quick to build; ``make solutions`` runs them."""
    import nbformat

    from .solutions import instructor_notebook

    out = Path(out)
    copy_assets(out)
    paths = []
    for lesson in _progress(only or lessons(), "solutions", progress):
        nb = instructor_notebook(lesson)
        note = nbformat.v4.new_markdown_cell(SOLUTIONS_NOTE.format(n=lesson.number))
        nb.cells.insert(2, note)
        nb.metadata["title"] = f"{lesson.number} — {lesson.title}: instructor version"
        path = out / "solutions" / f"{lesson.stem}.html"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(slide_rules.export(nb, "page", static="../_static", back="../index.html"), encoding="utf-8")
        paths.append(path)
    return paths


def _page(title: str, body: str, css: str = "") -> str:
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1.0">
<title>{html.escape(title)}</title>
<style>
body {{ font-family: system-ui, sans-serif; max-width: 72rem; margin: 2rem auto; padding: 0 1rem; color: #222; }}
table {{ border-collapse: collapse; margin: 1rem 0; }}
th, td {{ border: 1px solid #ccc; padding: 0.3rem 0.6rem; vertical-align: top; }}
th {{ background: #f0f0f0; }}
code {{ background: #f4f4f4; padding: 0 0.2em; }}
img {{ max-width: 100%; }}
{css}
</style>
</head>
<body>
{body}
</body>
</html>
"""


def build_report(out=DEFAULT_OUT) -> Path:
    """Lesson 06's benchmark report (``data_samples/results/bench_all.md`` and its figure) as a page."""
    import mistune

    src = samples_dir() / "results"
    md_path = src / "bench_all.md"
    if not md_path.is_file():
        raise FileNotFoundError(f"{md_path} not found: `posekit bench all` writes it (lesson 06)")
    dst = Path(out) / "report"
    dst.mkdir(parents=True, exist_ok=True)
    for name in ("bench_all.png", "bench_all.json"):
        if (src / name).is_file():
            shutil.copy(src / name, dst / name)
    body = mistune.create_markdown(plugins=["table"])(md_path.read_text(encoding="utf-8"))
    body = '<p><a href="../index.html">← course page</a></p>\n' + body
    path = dst / "bench_all.html"
    path.write_text(_page("Every posekit IK solver on the same cases", body), encoding="utf-8")
    return path


def _minutes(seconds) -> str:
    if seconds is None:
        return "—"
    return f"{seconds:.0f} s" if seconds < 90 else f"{seconds / 60:.1f} min"


def _row(lesson: Lesson, n_slides, instructor: bool = False) -> str:
    e = html.escape
    prereq = ", ".join(lesson.prerequisites) or "—"
    source = e(lesson.paper) if lesson.paper else "—"
    if lesson.reading:
        source += f"<br><small>{e(lesson.reading)}</small>"
    name = e(f"{lesson.number} — {lesson.title}")
    return (f"<tr><td>{lesson.number}</td><td><a href=\"lessons/{lesson.stem}.html\" title=\"{name}: the lesson as one "
            f"page\">{e(lesson.title)}</a></td>"
            f"<td><a href=\"slides/{lesson.stem}.html\" title=\"{name}: lecture slides\">slides</a> ({n_slides})</td>"
            + (f"<td><a href=\"solutions/{lesson.stem}.html\" title=\"{name}: reference solutions and instructor "
               f"notes\">solutions</a></td>" if instructor else "")
            + f"<td>{lesson.duration_min} min</td><td>{_minutes(lesson.run_s)}</td><td>{prereq}</td>"
            f"<td>{source}</td></tr>")


def build_course(out=DEFAULT_OUT, progress: bool = True, instructor: bool = False) -> Path:
    """Write the whole course folder (pages, slides, report, ``index.html``); returns the index's path.

    ``instructor``: also the lessons' instructor versions (``solutions/``) and the solutions in the slides' speaker
    notes. The default course is the students': no solution anywhere in it, so it can be published."""
    out = Path(out)
    all_ = lessons()
    slides = {s["lesson"]: s["slides"] for s in build_slides(out, all_, progress, instructor=instructor)}
    build_pages(out, all_, progress)
    if instructor:
        build_solutions(out, all_, progress)
    elif (out / "solutions").is_dir():  # an instructor build's pages left in the folder would be published too
        import shutil

        shutil.rmtree(out / "solutions")
    build_report(out)
    rows = "\n".join(_row(le, slides[le.number], instructor) for le in all_)
    solutions_head = "<th>for instructors</th>" if instructor else ""
    notes_said = ("what each figure shows, the exercises' solutions and notes, a time per section" if instructor
                  else "what each figure shows, a time per section; this is the students' course: no exercise "
                       "solution is in it, the instructor's is built by <code>make course INSTRUCTOR=1</code>")
    solutions_said = ("<em>Solutions</em>: the lesson with its reference solutions and instructor notes pasted in, not "
                      "run here (<code>make solutions</code> runs and checks them).\n" if instructor else "")
    body = f"""<h1>posekit — data-driven character posing, a course in notebooks</h1>
<p>From classical inverse kinematics to learned pose models: {len(all_)} lessons, each reproducing its
paper's key claim with a measured table on real data. Every page here is the lesson as it is stored — executed,
its outputs checked by the tests — so the numbers are the measured ones. The 3D views are live only in a
running notebook: <code>make lab</code> opens the lessons in JupyterLab, <code>make studio</code> serves
lesson 06 as a browser app.</p>
<h2>Lessons</h2>
<table class="posekit-lessons">
<thead><tr><th>#</th><th>lesson (one page)</th><th>lecture slides</th>{solutions_head}<th>planned time</th>
<th>runs in<br><small>measured, CPU</small></th><th>prerequisites</th><th>paper it reproduces</th></tr></thead>
<tbody>
{rows}
</tbody>
</table>
<p><small><em>Lecture slides</em>: press <code>s</code> for the speaker notes ({notes_said}).
{solutions_said}<em>Planned time</em>: lecture and practical together, the authors' plan. <em>Runs in</em>: from the
first cell to the last when the stored outputs were made (one CPU thread, a 2-core machine).</small></p>
<h2>Benchmark</h2>
<p><a href="report/bench_all.html">Every solver on the same held-out cases, speed against quality</a>
(lesson 06, <code>posekit bench all</code>).</p>
<h2>Licence</h2>
<p>Code: MIT. The Bandai mini set used by lessons 03–06 (frames of the Bandai Namco Research Motion Datasets,
© Bandai Namco Research Inc.; Kobayashi et al. 2023, arXiv 2306.08861), the weights trained on it, and the
figures, tables and benchmark report drawn from it on these pages: <strong>CC BY-NC 4.0</strong>, non-commercial
use only, with attribution (see <code>data_samples/bandai_mini/README.md</code>). The DeepMimic clips of
lessons 00–02: see <code>data_samples/README.md</code>. reveal.js (MIT) and MathJax (Apache 2.0) are copied into
<code>_static/</code> with their licences.</p>
"""
    index = out / "index.html"
    index.write_text(_page("posekit course: lessons, lecture slides and solutions", body), encoding="utf-8")
    return index
