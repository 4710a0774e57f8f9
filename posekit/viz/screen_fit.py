"""Views and controls that fit one screen: every view of a panel or of the studio in one row, sized from the width
the page gives them, and controls that wrap onto another line rather than cut their text off.

Introduced with the posing studio (``notebooks/06_posing_studio.ipynb``, served by Voila) and used by every
:class:`~posekit.viz.SkeletonViewer` (lesson 00 on), lesson 01's :class:`~posekit.viz.compare.SolverPanel` and
lesson 02's rig view. A renderer draws a canvas of the pixel size the kernel gave it (``width`` x ``height``); the
kernel does not know how wide the page is (Voila's whole window, or JupyterLab's notebook beside an open file
browser), so the page scales each canvas to the width of its box (:data:`FIT_CSS`: ``width: 100%``, the height
following the canvas's own aspect ratio). A view's box grows to the canvas's own width at most and gives way first
when the row is narrow (:func:`view_box_layout`); four views sit in one row from 4 x 168 px of width on. Mouse
picking and dragging read the canvas's shown size, so they work on a scaled canvas (pythreejs normalises by it).

On a 1280 x 800 screen the studio app's four views, the *selected* list and the X/Y/Z sliders lie on the screen
with the studio's top at the screen's top, and so do the studio and lesson 02's rig view in JupyterLab with the file
browser open (``tests/viz/test_one_screen_browser.py`` measures them).
"""

from __future__ import annotations

__all__ = ["FIT_CSS", "MIN_VIEW_WIDTH", "ROOM_UNDER_VIEWS", "stylesheet", "view_box_layout", "VIEWER_LAYOUT", "WRAP_ROW"]

MIN_VIEW_WIDTH = 160
"""A view's box never gets narrower than this (pixels): below it the row wraps."""

FIT_CSS = """
.posekit-canvas { width: auto; align-self: stretch; min-width: 0; }
.posekit-canvas > canvas, .posekit-canvas > img { width: 100% !important; height: auto !important; display: block; }
.posekit-viewer .widget-slider { max-width: calc(100% - 2 * var(--jp-widgets-margin, 2px)); }
.posekit-viewer button, .posekit-viewer .widget-toggle-button { flex-shrink: 0; }
"""
"""The page's rules: a renderer (class ``posekit-canvas``) as wide as its box (stretched, its margins inside), its canvas (or the picture pythreejs
shows in place of a frozen view) scaled to that width with its own aspect ratio; inside a viewer's controls (class
``posekit-viewer``), a slider never wider than its box (its track gives way, its label and readout keep their
width) and a button never squeezed below its text."""

WRAP_ROW = {"flex_flow": "row wrap", "align_items": "center"}
"""A row of controls that wraps onto the next line when the page is narrow."""

VIEWER_LAYOUT = {"flex": "0 1000 auto", "min_width": "0"}
"""A viewer's whole widget (canvas and controls) in a row of a lesson's own widgets (lesson 02: the view beside the
rig's sliders): it gives way before its neighbours (a flex shrink of 1,000 against their 1), its canvas scaling
down, so the neighbours keep their width and their text."""


def view_box_layout(width: int, height: int | None = None) -> dict:
    """The layout of one view's box (title, canvas, status) in a row of views: the views share the row's width
    evenly, each at least :data:`MIN_VIEW_WIDTH` wide; they grow with the window (a canvas drawn ``width`` pixels
    wide is scaled up beyond it), as wide as the canvas's height still fits the window's height with room for the
    controls under it (``height``: the canvas's; without it, no wider than ``width``)."""
    most = (f"max({int(width)}px, calc((100vh - {ROOM_UNDER_VIEWS}px) * {width / height:.4f}))" if height
            else f"{int(width)}px")
    return {"flex": f"1 1 {MIN_VIEW_WIDTH}px", "min_width": f"{MIN_VIEW_WIDTH}px", "max_width": most,
            "margin": "0 8px 8px 0"}


ROOM_UNDER_VIEWS = 400
"""Pixels of the window's height kept for what a view grown with the window must leave on the first screen: its
title and status, the *selected* list, the X/Y/Z sliders and the readout."""


def stylesheet():
    """The shared ``ipywidgets.HTML`` that carries :data:`FIT_CSS` into the page (it takes no room). A widget that
    holds views shows it among its children; the rules apply to the whole page, once however many hold it."""
    import ipywidgets as w

    from .shared import _shared, widget

    return _shared(("stylesheet", FIT_CSS), lambda: widget(w.HTML, f"<style>{FIT_CSS}</style>",
                                                           layout={"margin": "0", "height": "0", "overflow": "hidden"}))
