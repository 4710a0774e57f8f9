"""The instructor kit: the slide convention, the slides and course page (built, then opened in Chromium from
disk), and the exercises' reference solutions (each passes its own checker; the instructor version runs)."""

from __future__ import annotations

import html
import importlib
import inspect
import re
import subprocess
from pathlib import Path

import nbformat
import pytest

from posekit.cli import main
from posekit.course import slides as rules
from posekit.course.lessons import find_lesson, lessons, read_notebook
from posekit.course.solutions import _module as solutions_module
from posekit.course.solutions import exercises, instructor_notebook, notes, solution_function
from posekit.paths import notebooks_dir

ROOT = Path(__file__).resolve().parents[1]
LESSONS = lessons()
NUMBERS = [le.number for le in LESSONS]


def test_the_course_has_every_lesson_in_order():
    assert NUMBERS == ["00", "01", "02", "03", "04", "05", "06"]
    for le in LESSONS:
        assert le.title and le.duration_min > 0
        assert all(p in NUMBERS and p < le.number for p in le.prerequisites), le.number
        assert le.paper or le.reading, f"lesson {le.number} names no paper and no reading"
        assert le.run_s is not None and le.run_s > 0  # read from the stored execution timestamps


# ---- the slide convention -------------------------------------------------------------------------------


def _cells(*specs):
    out = []
    for kind, text, *tags in specs:
        cell = nbformat.v4.new_markdown_cell(text) if kind == "md" else nbformat.v4.new_code_cell(text)
        if tags:
            cell.metadata["tags"] = tags
        out.append(cell)
    return out


def test_the_convention_types_each_kind_of_cell():
    cells = _cells(("md", "# 09 — Title\n\n**Aim.** x"), ("code", "import numpy"), ("md", "## 1. Theory"),
                   ("code", "a = 1"), ("code", "b = 2"), ("md", "A practical step"), ("code", "c = 3", "key-figure"),
                   ("code", "d = 4", "slide-skip"), ("md", "aside", "slide-notes"), ("md", "## 2. Summary"))
    assert rules.slide_types(cells) == ["slide", "skip", "slide", "-", "subslide", "subslide", "slide", "skip",
                                        "notes", "slide"]


def test_markdown_is_split_at_headings_and_exercises():
    cells = _cells(("md", "The end of section 6.\n\n## 7. Exercises\n\nIntro.\n\n**Exercise 1 — FK.** Do it.\n\n"
                          "**Exercise 2 (open).** Think.\n\n## 8. Summary\n\n- done"))
    parts = [c.source for c in rules.split_markdown(cells)]
    assert [p.split("\n")[0] for p in parts] == ["The end of section 6.", "## 7. Exercises",
                                                 "**Exercise 1 — FK.** Do it.", "**Exercise 2 (open).** Think.",
                                                 "## 8. Summary"]
    assert len({c.id for c in rules.split_markdown(cells)}) == 5  # every piece keeps a distinct cell id


@pytest.mark.parametrize("name", [le.path.name for le in LESSONS] + ["_template.ipynb"])
def test_every_notebook_is_stored_under_the_slide_convention(name):
    nb = read_notebook(notebooks_dir() / name)
    assert nbformat.from_dict(rules.mark(nb)) == nb, \
        f"{name} drifted from the slide convention: run `posekit course mark notebooks/{name}`"


@pytest.mark.parametrize("number", NUMBERS)
def test_every_lesson_has_one_key_figure_with_a_figure_or_table(number):
    nb = read_notebook(find_lesson(number).path)
    cell = nb.cells[rules.key_figure_cell(nb)]
    assert cell.metadata.slideshow.slide_type == "slide" and rules.key_outputs(cell)


def test_key_figure_errors_say_what_is_expected():
    nb = nbformat.v4.new_notebook(cells=_cells(("md", "# t"), ("code", "x = 1", "key-figure")))
    with pytest.raises(ValueError, match="figure .* or a printed table"):
        rules.key_figure_cell(nb)
    nb.cells[1].metadata["tags"] = []
    with pytest.raises(ValueError, match="exactly one cell tagged 'key-figure', found 0"):
        rules.key_figure_cell(nb)


def test_count_slides_counts_leaf_sections():
    assert rules.count_slides("<section><section>a</section><section>b</section></section><section>c</section>") == 3
    assert rules.count_slides("<div></div>") == 0


def test_mark_command_checks_and_writes(tmp_path, capsys):
    nb = read_notebook(find_lesson("00").path)
    nb.cells[2].source += "\n\n## Ninety-nine. A new section"
    nb.cells[3].metadata.slideshow.slide_type = "fragment"
    path = tmp_path / "00_edit.ipynb"
    nbformat.write(nb, str(path))
    assert main(["course", "mark", "--check", str(path)]) == 1
    assert "differ from the slide convention" in capsys.readouterr().out
    assert main(["course", "mark", str(path)]) == 0
    assert main(["course", "mark", "--check", str(path)]) == 0
    assert any(c.source == "## Ninety-nine. A new section" for c in read_notebook(path).cells)


# ---- slides and the course page --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def course(tmp_path_factory):
    """The course page as an instructor builds it for themselves: ``make course INSTRUCTOR=1`` (built once for
    every test below; the students' version differs only by what it leaves out, tested on its own)."""
    out = tmp_path_factory.mktemp("course")
    r = subprocess.run(["make", "-C", str(ROOT), "course", "INSTRUCTOR=1", f"COURSE_OUT={out}"], capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    return out


@pytest.mark.slow
def test_course_build_writes_every_part(course):
    assert (course / "index.html").is_file() and (course / "report" / "bench_all.html").is_file()
    assert (course / "report" / "bench_all.png").is_file()
    for le in LESSONS:
        for part in ("slides", "lessons"):
            page = (course / part / f"{le.stem}.html").read_text(encoding="utf-8")
            # a link a reader may follow (<a href>, e.g. a paper's DOI) is fine; nothing may load from the internet
            loads = re.search(r"""src=["']https?://|<link\b[^>]*href=["']https?://""", page)
            assert not loads, f"{part}/{le.stem} loads from the internet: {loads.group(0)}"
    index = (course / "index.html").read_text(encoding="utf-8")
    for target in re.findall(r'href="([^"#]+)"', index):
        assert (course / target).is_file(), f"index.html links to a missing {target}"
    assert "CC BY-NC 4.0" in index
    for le in LESSONS:  # every lesson's page, slides and solutions, linked with titles that name the lesson
        for part in ("lessons", "slides", "solutions"):
            assert re.search(rf'href="{part}/{le.stem}.html" title="{re.escape(html.escape(le.number + " — " + le.title))}',
                             index), f"index.html does not link {part}/{le.stem}.html with the lesson's name"


@pytest.mark.slow
@pytest.mark.parametrize("number", NUMBERS)
def test_each_lesson_yields_sane_slides_with_its_key_figure(course, number):
    le = find_lesson(number)
    page = (course / "slides" / f"{le.stem}.html").read_text(encoding="utf-8")
    n = rules.count_slides(page)
    assert 12 <= n <= 60, f"lesson {number}: {n} slides"
    nb = read_notebook(le.path)
    key = rules.key_outputs(nb.cells[rules.key_figure_cell(nb)])
    # the key figure opens a column of slides: its <section> is the first inside a top-level <section>
    at = [page.find(k) if k in page else page.find(html.escape(k, quote=False)) for k in key]
    assert min(at) > 0, f"lesson {number}: the key figure's output is not in the slides"
    inner = page.rfind("<section", 0, min(at))
    outer = page.rfind("<section", 0, inner)
    assert page[page.index(">", outer) + 1:inner].strip() == "", f"lesson {number}: the key figure is not a slide"
    assert "# NBVAL_" not in page  # test markers stay out of the lecture


@pytest.mark.browser
def test_course_opens_from_disk_in_chromium(course, chromium):
    page = chromium.new_page(viewport={"width": 1280, "height": 800})
    try:
        requests, errors = [], []
        page.on("request", lambda r: requests.append(r.url))
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto((course / "index.html").as_uri())
        assert page.locator("table.posekit-lessons tbody tr").count() == len(LESSONS)
        page.locator("a", has_text="slides").nth(3).click()  # lesson 03's slides, by the index's link
        page.wait_for_function("() => window.Reveal && Reveal.isReady()", timeout=30_000)
        html = (course / "slides" / f"{find_lesson('03').stem}.html").read_text(encoding="utf-8")
        assert page.evaluate("Reveal.getTotalSlides()") == rules.count_slides(html)
        page.wait_for_function("() => document.querySelectorAll('mjx-container svg').length > 5", timeout=30_000)
        page.keyboard.press("ArrowRight")
        assert page.evaluate("Reveal.getIndices().h") == 1
        page.screenshot(path=str(course / "slides-03.png"))
        page.goto((course / "lessons" / f"{find_lesson('06').stem}.html").as_uri())
        img = page.locator("img").last  # the report's scatter, stored in the notebook
        assert img.evaluate("i => i.complete && i.naturalWidth") > 400
        assert page.locator(".posekit-widget-note").count() >= 1  # the studio's place, explained
        page.goto((course / "report" / "bench_all.html").as_uri())
        assert page.locator("table tbody tr").count() >= 16
        assert page.evaluate("document.querySelector('img').naturalWidth") > 400
    finally:
        page.close()
    assert [u for u in requests if not u.startswith(("file:", "data:"))] == []
    assert errors == []


@pytest.mark.slow
def test_make_course_and_slides_targets(tmp_path, course):
    out = tmp_path / "c"
    r = subprocess.run(["make", "-C", str(ROOT), "slides", f"COURSE_OUT={out}"], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    assert re.search(r"^06\s+\d+\s+yes", r.stdout, re.MULTILINE)
    assert len(list((out / "slides").glob("*.html"))) == len(LESSONS)
    # make course: the fixture ran it
    assert (course / "index.html").is_file() and len(list((course / "lessons").glob("*.html"))) == len(LESSONS)


def test_solutions_pages_hold_the_solutions_and_notes(tmp_path):
    from posekit.course.build import build_solutions

    le = find_lesson("01")
    (path,) = build_solutions(tmp_path, only=[le], progress=False)
    page = path.read_text(encoding="utf-8")
    assert re.search(r"<title>\s*01 — FABRIK[^<]*instructor version", page)
    assert "Instructor notes — exercise 3" in page and "exercise_fabrik_planted" in page
    assert "raise NotImplementedError" not in page  # the stubs are replaced by the solutions
    assert "Not executed here" in page


# ---- solutions ------------------------------------------------------------------------------------------


def _checked():
    for le in LESSONS:
        for ex in exercises(read_notebook(le.path)):
            if not ex.open:
                yield pytest.param(le.number, ex, id=f"{le.number}-{ex.function}")


@pytest.mark.parametrize("number, ex", list(_checked()))
def test_every_checked_exercise_has_a_solution_that_passes_its_checker(number, ex, capsys):
    fn = solution_function(find_lesson(number), ex.function)
    namespace = {}
    exec(inspect.getsource(fn), namespace)  # alone, as pasted into the notebook: it must be self-contained
    checker = getattr(importlib.import_module("posekit.exercises"), ex.checker)
    assert checker(namespace[ex.function]) is True
    assert capsys.readouterr().out.startswith(f"✓ {ex.checker}")


@pytest.mark.parametrize("number", NUMBERS)
def test_every_open_exercise_has_instructor_notes(number):
    le = find_lesson(number)
    open_ones = {ex.number for ex in exercises(read_notebook(le.path)) if ex.open}
    written = notes(le)
    assert set(written) == open_ones, f"lesson {number}: notes for {sorted(written)}, open exercises {sorted(open_ones)}"
    assert all(len(text.split()) >= 40 for text in written.values())


@pytest.mark.parametrize("number", NUMBERS)
def test_instructor_notebook_fills_every_exercise(number):
    le = find_lesson(number)
    nb = instructor_notebook(le)
    exs = exercises(read_notebook(le.path))
    code = "\n".join(c.source for c in nb.cells if c.cell_type == "code")
    assert "raise NotImplementedError" not in code
    for ex in exs:
        if not ex.open:
            assert f"assert done, \"the reference solution must pass {ex.checker}\"" in code
    assert sum("instructor-notes" in c.metadata.get("tags", []) for c in nb.cells) == sum(e.open for e in exs)
    for c in nb.cells:
        if c.cell_type == "code":
            python = "\n".join(ln for ln in c.source.splitlines() if not ln.lstrip().startswith(("%", "!")))
            compile(python, f"lesson {number}", "exec")  # pasted code parses (IPython magics aside)


@pytest.mark.slow
def test_solutions_command_runs_the_instructor_version(tmp_path, capsys):
    assert main(["exercises", "solutions", "00", "--out", str(tmp_path), "--html"]) == 0
    out = capsys.readouterr().out
    for checker in ("check_local_from_global", "check_matrix_to_quat", "check_bone_drift"):
        assert f"✓ {checker}" in out
    assert "✗" not in out
    nb = read_notebook(tmp_path / "00_skeletons_and_poses.solutions.ipynb")
    assert "Instructor version" in nb.cells[1].source
    assert (tmp_path / "00_skeletons_and_poses.solutions.html").is_file()


@pytest.mark.slow
def test_a_solution_that_fails_its_checker_fails_the_run(tmp_path, monkeypatch, capsys):
    module = solutions_module(find_lesson("00"))

    def exercise_bone_drift(parents, clip):
        import numpy as np
        return np.ones(len(parents))
    monkeypatch.setattr(module, "exercise_bone_drift", exercise_bone_drift)
    assert main(["exercises", "solutions", "00", "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "the reference solution must pass check_bone_drift" in err


def test_solutions_refuse_an_unknown_lesson_or_a_missing_solution(monkeypatch, capsys):
    assert main(["exercises", "solutions", "9"]) == 2
    assert "no lesson '9': expected one of 00, 01" in capsys.readouterr().err
    module = solutions_module(find_lesson("06"))
    monkeypatch.delattr(module, "exercise_slerp")
    with pytest.raises(LookupError, match="no solution 'exercise_slerp' in instructor/solutions/nb06.py"):
        instructor_notebook("06")
    assert main(["exercises", "list"]) == 1
    assert re.search(r"06\s+2\s+checked exercise_slerp\s+check_slerp\s+MISSING", capsys.readouterr().out)


def test_the_solutions_are_not_in_the_package_students_import(monkeypatch, tmp_path):
    import posekit

    assert not (Path(posekit.__file__).parent / "exercises" / "solutions").exists()
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("posekit.exercises.solutions")
    assert (ROOT / "instructor" / "solutions" / "nb01.py").is_file()
    # an instructor's copy elsewhere is found through POSEKIT_SOLUTIONS; a missing folder says what to set
    monkeypatch.setenv("POSEKIT_SOLUTIONS", str(tmp_path / "nowhere"))
    with pytest.raises(LookupError, match="not part of the posekit package.*POSEKIT_SOLUTIONS"):
        solution_function(find_lesson("01"), "exercise_fabrik_planted")


def test_the_students_slides_and_course_page_hold_no_solution(tmp_path):
    from posekit.course.build import _row, build_slides

    le = find_lesson("01")
    said = inspect.getdoc(solution_function(le, "exercise_fabrik_planted")).splitlines()[0]  # one highlighted span
    (students,) = build_slides(tmp_path / "students", only=[le], progress=False)
    (teacher,) = build_slides(tmp_path / "instructor", only=[le], progress=False, instructor=True)
    page, notes_page = students["path"].read_text(encoding="utf-8"), teacher["path"].read_text(encoding="utf-8")
    assert html.escape(said) in notes_page or html.escape(said, quote=False) in notes_page
    assert said not in page and html.escape(said) not in page and html.escape(said, quote=False) not in page
    assert "reference solution" not in page and "Instructor notes — exercise" not in page
    assert "solutions/" not in _row(le, 20) and "solutions/01_fabrik.html" in _row(le, 20, instructor=True)
