"""Every lesson has the same shape (aim, contents, references, exercises with checkers, summary), is
stored executed (nbval compares stored outputs) and carries no saved widget state."""

import json
from pathlib import Path

import pytest

NOTEBOOKS = sorted(p for p in (Path(__file__).resolve().parent.parent / "notebooks").glob("[0-9][0-9]_*.ipynb"))
FURTHER = sorted(p for p in (Path(__file__).resolve().parent.parent / "notebooks").glob("[0-9][0-9]x_*.ipynb"))
"""Going-further notebooks: a lesson's studies, beside it (``05x_protores_studies.ipynb`` beside lesson 05)."""
CORE_WORDS, CORE_CODE_CELLS = 3000, 25
"""A core lesson is one sitting or two: at most this many words of markdown and code cells."""


def _words(nb) -> int:
    import re

    text = " ".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "markdown")
    return len(re.sub(r"<!--.*?-->", "", text, flags=re.S).split())


def test_lessons_exist():
    assert [p.name[:2] for p in NOTEBOOKS] == [f"{i:02d}" for i in range(len(NOTEBOOKS))] and NOTEBOOKS


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_lesson_shape(path):
    nb = json.loads(path.read_text())
    text = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "markdown")
    code = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")
    for heading in ("**Aim.**", "**Contents**", "**Reference", "Exercises", "Summary"):
        assert heading in text, f"{path.name} lacks {heading!r}"
    assert "from posekit.exercises import" in code and "raise NotImplementedError" in code
    cells = [c for c in nb["cells"] if c["cell_type"] == "code" and "".join(c["source"]).strip()]
    assert all(c.get("execution_count") for c in cells), f"{path.name} is not stored executed"
    assert "widgets" not in nb.get("metadata", {}), f"{path.name} stores widget state (tools/strip_widget_state.py)"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_a_core_lesson_fits_one_sitting_or_two(path):
    nb = json.loads(path.read_text())
    code = sum(c["cell_type"] == "code" for c in nb["cells"])
    assert _words(nb) <= CORE_WORDS and code <= CORE_CODE_CELLS, (
        f"{path.name}: {_words(nb)} words of markdown, {code} code cells (a core lesson: at most {CORE_WORDS:,} "
        f"and {CORE_CODE_CELLS}); move its studies to a going-further notebook beside it")


@pytest.mark.parametrize("path", FURTHER, ids=lambda p: p.name)
def test_a_going_further_notebook_has_the_lessons_shape_and_is_linked(path):
    nb = json.loads(path.read_text())
    text = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "markdown")
    for heading in ("**Aim.**", "**Contents**", "**Reference", "Exercises", "Summary"):
        assert heading in text, f"{path.name} lacks {heading!r}"
    cells = [c for c in nb["cells"] if c["cell_type"] == "code" and "".join(c["source"]).strip()]
    assert all(c.get("execution_count") for c in cells), f"{path.name} is not stored executed"
    assert "widgets" not in nb.get("metadata", {})
    core = next(p for p in NOTEBOOKS if p.name[:2] == path.name[:2])
    core_text = "".join("".join(c["source"]) for c in json.loads(core.read_text())["cells"])
    assert path.name in core_text, f"{core.name} does not link {path.name}"
    readme = (path.parent.parent / "README.md").read_text()
    assert f"(notebooks/{path.name})" in readme, f"the README's lesson table does not list {path.name}"


@pytest.mark.parametrize("path", NOTEBOOKS + FURTHER, ids=lambda p: p.name)
def test_outputs_left_uncompared_are_tagged(path):
    """nbval's comment marker would show in the lesson's code; a cell tag does the same out of sight."""
    nb = json.loads(path.read_text())
    marked = [k for k, c in enumerate(nb["cells"]) if c["cell_type"] == "code" and "# NBVAL_" in "".join(c["source"])]
    assert marked == [], f"{path.name}: cells {marked} use a '# NBVAL_' comment; tag them nbval-ignore-output"


def _portable():
    import importlib.util

    spec = importlib.util.spec_from_file_location("test_portable_tool", NOTEBOOKS[0].parent.parent / "tools" / "test_portable.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_portable_variants_emulate_each_source_of_rounding(capsys):
    tool = _portable()
    envs = tool.VARIANTS.values()
    for knob in ("OPENBLAS_CORETYPE", "NPY_DISABLE_CPU_FEATURES", "ATEN_CPU_CAPABILITY", "NUMBA_CPU_NAME"):
        assert any(knob in env for env in envs), f"no variant sets {knob}"
    assert {env["OMP_NUM_THREADS"] for env in envs} == {"1", "2"}
    assert len({env["OPENBLAS_CORETYPE"] for env in envs}) == len(tool.VARIANTS)
    assert tool.main(["--list"]) == 0
    out = capsys.readouterr().out
    assert all(out.count(f"{name}:") == 1 for name in tool.VARIANTS)


def test_portable_refuses_an_unknown_variant(capsys):
    with pytest.raises(SystemExit) as e:
        _portable().main(["skylake"])
    assert e.value.code == 2 and "unknown variant(s) skylake; expected one of" in capsys.readouterr().err


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_every_library_name_the_prose_mentions_exists(path):
    """A student looks up what the text names: every ``posekit.a.b`` in a markdown cell is a module or an
    attribute of one (a moved module leaves no stale name behind)."""
    import importlib
    import re

    def resolves(name):
        parts = name.split(".")
        for k in range(len(parts), 0, -1):
            try:
                obj = importlib.import_module(".".join(parts[:k]))
            except ImportError:
                continue
            try:
                for a in parts[k:]:
                    obj = getattr(obj, a)
                return True
            except AttributeError:
                return False
        return False

    nb = json.loads(path.read_text())
    text = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "markdown")
    names = sorted({m.group(0) for m in re.finditer(r"posekit(\.[A-Za-z_]\w*)+", text)})
    assert [n for n in names if not resolves(n)] == []


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_stored_progress_bars_end_finished(path):
    """A stored tqdm bar shows how the loop ended (posekit.progress), never frozen at 0 % or midway."""
    import re

    nb = json.loads(path.read_text())
    bars = [("".join(o.get("data", {}).get("text/plain", "")), k) for k, c in enumerate(nb["cells"])
            for o in c.get("outputs", []) if re.search(r"\d+%\|", "".join(o.get("data", {}).get("text/plain", "")))]
    frozen = [(k, text) for text, k in bars
              if (m := re.search(r"(\d+)/(\d+) \[", text)) is None or m.group(1) != m.group(2)]
    assert frozen == [], f"{path.name}: progress bars not finished in cells {frozen}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_a_stored_widget_says_what_would_be_there(path):
    """Where a widget cannot draw (a saved notebook, a page without a kernel), its text says what it is and how to
    see it (posekit.viz.viewer.show_widget), never ipywidgets' ``VBox(children=(...``."""
    import re

    nb = json.loads(path.read_text())
    bare = [k for k, c in enumerate(nb["cells"]) for o in c.get("outputs", [])
            if "application/vnd.jupyter.widget-view+json" in o.get("data", {})
            and re.match(r"[A-Z]\w*\(", "".join(o["data"].get("text/plain", "")))]
    assert bare == [], f"{path.name}: cells {bare} store a widget as its Python repr"


@pytest.mark.parametrize("path", [p for p in NOTEBOOKS if p.name[:2] != "00"], ids=lambda p: p.name)
def test_goals_are_set_in_the_aim_and_judged_in_a_verdict_table(path):
    """Goals before verdicts: the Aim's cell sets **Goals**, and a later code cell prints the verdict table
    (posekit.evaluation.measures.verdict_table: goal, measured, met / not met). Lesson 00 judges no goal."""
    nb = json.loads(path.read_text())
    cells = nb["cells"]
    goals = [k for k, c in enumerate(cells) if c["cell_type"] == "markdown" and "**Goals**" in "".join(c["source"])]
    verdicts = [k for k, c in enumerate(cells) if c["cell_type"] == "code" and "verdict_table(" in "".join(c["source"])]
    assert goals and goals[0] <= 1, f"{path.name}: the Aim sets no **Goals**"
    assert verdicts and verdicts[-1] > goals[0], f"{path.name}: no verdict table after the goals"
    printed = "".join("".join(o.get("text", "")) for o in cells[verdicts[-1]].get("outputs", []))
    assert printed.startswith("goal") and any(v in printed for v in ("met", "not judged", "not shown")), \
        f"{path.name}: the verdict table cell is not stored executed"
