"""What every course page reads from a lesson's cells: the slide size, the cell tags of the slide convention, a
cell's source, what a stored 3D view or progress bar looks like, and the markers a page drops.

The bottom of :mod:`posekit.course`: the convention and the reveal.js build (:mod:`posekit.course.slides`), the
lecture deck (:mod:`posekit.course.lecture`), its layout (:mod:`posekit.course.layout`) and the 3D views' stills
(:mod:`posekit.course.stills`) all read these, and this module imports none of them.
"""

from __future__ import annotations

import re

__all__ = ["KEY_FIGURE", "PAPER_BESIDE", "SLIDE_WIDTH", "SLIDE_HEIGHT", "WIDGET_VIEW", "strip_source_markers",
           "strip_test_markers"]

KEY_FIGURE = "key-figure"
"""Cell tag: the lesson's key figure or table, a slide of its own (:func:`posekit.course.slides.key_figure_cell`)."""
PAPER_BESIDE = "paper-beside"
"""Cell tag: the cell shows the paper's figures beside the lesson's own (columns of one table); its slide follows the
key figure's (:mod:`posekit.course.lecture`)."""
SLIDE_WIDTH, SLIDE_HEIGHT = 1280, 720
"""The slide size reveal.js lays every slide out at (CSS pixels; it scales the whole slide to the screen): a
1280x720 projector shows it one to one."""


def _source(cell) -> str:
    """A cell's source as one string (a stored notebook may hold it as a list of lines)."""
    src = cell["source"]
    return src if isinstance(src, str) else "".join(src)


_SOURCE_MARKER = re.compile(r"<!--\s*(?:out|data|goal|paper|definition|setting):.*?-->", re.DOTALL)


def strip_source_markers(source: str) -> str:
    """Drop any source marker left after a figure of a markdown cell (``<!-- out: ... -->``): a lesson keeps its
    figures' bindings in the cells' metadata (``tests/test_prose_numbers.py`` refuses a marker in its text), so this
    is a guard: a marker is for the tests, not for the lecture, and would count as text when a slide is fitted."""
    return _SOURCE_MARKER.sub("", source)


def strip_test_markers(source: str) -> str:
    """Drop the ``# NBVAL_...`` lines nbval reads: they are for the tests, not for the lecture."""
    return "\n".join(ln for ln in source.splitlines() if not ln.strip().startswith("# NBVAL_"))


WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"
"""The MIME type of a stored widget's output (a 3D view, a panel, a progress bar): its state lives in the kernel."""
_PROGRESS = re.compile(r"\|.*\[\d\d:\d\d<")
"""A progress bar's text (``|####| 3/10 [00:01<00:02]``): a widget output that is not a view."""
