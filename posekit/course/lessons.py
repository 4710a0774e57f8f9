"""The lessons as a course: which notebooks, and what each carries about itself.

Every lesson stores its facts in its own notebook metadata, under ``posekit``::

    {"lesson": "03", "duration_min": 120, "prerequisites": ["00", "01"],
     "paper": "victor2021", "references": ["victor2021", "aristidou2011", "kobayashi2023"],
     "reading": "..."}

``paper`` and ``references`` are keys of :mod:`posekit.references` (the one bibliography);
:attr:`Lesson.paper` is the paper's one-line citation drawn from it. ``reading`` is a key too, or a
short free text.

``duration_min`` is the planned class time (lecture and practical), an author's plan; the time the
notebook took to run is read from its stored execution timestamps (measured when its outputs were made).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

from ..paths import notebooks_dir

__all__ = ["Lesson", "lessons", "find_lesson", "read_notebook"]

_LESSON_FILE = re.compile(r"^(\d\d)_\w+\.ipynb$")


@dataclass(frozen=True)
class Lesson:
    """One lesson: its notebook and the facts it stores about itself."""

    number: str
    path: Path
    title: str
    duration_min: int
    prerequisites: tuple[str, ...]
    paper: str | None
    reading: str | None
    run_s: float | None
    """Seconds from the first cell's start to the last cell's end in the stored outputs (None if unknown)."""
    paper_key: str | None = None
    """The paper's key in :mod:`posekit.references` (None for a lesson without one)."""
    references: tuple[str, ...] = ()
    """The keys of the lesson's reference list, in its order."""

    @property
    def stem(self) -> str:
        return self.path.stem


def read_notebook(path):
    """Read a notebook with nbformat (version 4), naming the file in the error when it is not one."""
    import nbformat

    try:
        return nbformat.read(str(path), as_version=4)
    except Exception as e:  # nbformat raises several kinds for a broken file
        raise ValueError(f"{path}: not a readable Jupyter notebook ({type(e).__name__}: {e})") from e


def _run_seconds(nb) -> float | None:
    starts, ends = [], []
    for cell in nb.cells:
        ex = cell.get("metadata", {}).get("execution", {})
        if "iopub.execute_input" in ex and "shell.execute_reply" in ex:
            starts.append(ex["iopub.execute_input"])
            ends.append(ex["shell.execute_reply"])
    if not starts:
        return None

    def t(s):
        return datetime.fromisoformat(s.replace("Z", "+00:00"))
    return round((max(map(t, ends)) - min(map(t, starts))).total_seconds(), 1)


def _lesson(path: Path) -> Lesson:
    nb = read_notebook(path)
    meta = nb.metadata.get("posekit")
    if not isinstance(meta, dict):
        raise ValueError(f"{path}: no 'posekit' entry in the notebook metadata (lesson, duration_min, "
                         "prerequisites, paper)")
    number = _LESSON_FILE.match(path.name).group(1)
    if meta.get("lesson") != number:
        raise ValueError(f"{path}: metadata says lesson {meta.get('lesson')!r}, the file name says {number!r}")
    first = nb.cells[0].source.splitlines()[0] if nb.cells else ""
    if not first.startswith("# "):
        raise ValueError(f"{path}: the first cell must be the title ('# {number} — ...')")
    title = first[2:].split("—", 1)[-1].strip()
    for key in ("duration_min", "prerequisites"):
        if key not in meta:
            raise ValueError(f"{path}: the notebook metadata's 'posekit' entry lacks {key!r}")
    return Lesson(number, path, title, int(meta["duration_min"]), tuple(meta["prerequisites"]),
                  _cited(meta.get("paper")), _cited(meta.get("reading")), _run_seconds(nb),
                  meta.get("paper"), tuple(meta.get("references", ())))


def _cited(value: str | None) -> str | None:
    """A bibliography key as its one-line citation; free text (or None) as it is."""
    from ..references import REFERENCES, long_cite

    return long_cite(value) if value in REFERENCES else value


def lessons(folder=None) -> list[Lesson]:
    """Every lesson in ``folder`` (default :func:`posekit.paths.notebooks_dir`), in order.

    Files named ``NN_name.ipynb`` are lessons; ``_template.ipynb`` and others are not.
    """
    folder = Path(folder) if folder is not None else notebooks_dir()
    return [_lesson(p) for p in sorted(folder.glob("*.ipynb")) if _LESSON_FILE.match(p.name)]


def find_lesson(key, folder=None) -> Lesson:
    """The lesson named by ``key``: its number (``"3"``, ``"03"``) or its file stem or name."""
    all_ = lessons(folder)
    k = str(key).strip()
    for lesson in all_:
        if k in (lesson.number, lesson.stem, lesson.path.name) or (k.isdigit() and int(k) == int(lesson.number)):
            return lesson
    raise ValueError(f"no lesson {key!r}: expected one of {', '.join(le.number for le in all_)} "
                     f"(or a file name such as {all_[0].path.name if all_ else '00_name.ipynb'})")
