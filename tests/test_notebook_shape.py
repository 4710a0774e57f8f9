"""Every lesson has the same shape (aim, contents, references, exercises with checkers, summary), is
stored executed (nbval compares stored outputs) and carries no saved widget state."""

import json
from pathlib import Path

import pytest

NOTEBOOKS = sorted(p for p in (Path(__file__).resolve().parent.parent / "notebooks").glob("[0-9][0-9]_*.ipynb"))


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
