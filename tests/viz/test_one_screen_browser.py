"""Every view and the selection's controls on one 1280 x 800 screen (issue 57, item 3), measured in headless
Chromium: the studio app in Voila, and in JupyterLab with the file browser open lesson 06's studio and lesson 02's
rig view (the lesson's own cells, trimmed as ``tests/viz/test_browser.py`` trims them).

Each test scrolls the widget's top to the top of the area that scrolls it (Voila's page; JupyterLab's notebook, under
its menu and tabs), then asserts that every view's canvas, the *selected* list and the X/Y/Z sliders lie wholly in
that area and on the 1280 x 800 screen, and that no label, readout, button or text of the widget is cut off
(``scrollWidth <= clientWidth``) nor any of its boxes scrolls sideways. Screenshots go to ``$POSEKIT_SHOTS`` when it
is set.

Needs Debian's ``chromium`` and Playwright's Python package.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from posekit.bench.studio import CHROMIUM, blank_tab, open_studio, serve_voila
from tests.viz.screen_fit import MEASURE, SCREEN, off_screen
from tests.viz.test_browser import (RIG_NOTEBOOK, STUDIO_NOTEBOOK, _lab_page, _open_and_run_all, _wait_visible,
                                    chromium, lab)  # noqa: F401 - fixtures
from tests.viz.browser_helpers import wait_for

pytestmark = pytest.mark.browser


def _shot(page, name):
    shots = os.environ.get("POSEKIT_SHOTS")
    if shots:
        Path(shots).mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(Path(shots) / name))


def _check(m, what):
    print(what, {k: m[k] for k in ("root", "seen", "views", "selected", "sliders")})
    assert not off_screen(m), f"{what}: {off_screen(m)}"
    assert m["clipped"] == [], f"{what}: text cut off: {m['clipped']}"
    assert m["scrolled"] == [], f"{what}: a box scrolls sideways: {m['scrolled']}"


@pytest.fixture(scope="module")
def voila(tmp_path_factory):
    if not Path(CHROMIUM).exists():
        pytest.fail(f"{CHROMIUM} not found: install Debian's chromium (make test does)")
    with serve_voila(folder=tmp_path_factory.mktemp("voila"), cull_idle_s=600) as server:
        yield server


@pytest.fixture(scope="module")
def studio_page(voila, chromium):  # noqa: F811
    """The studio app at 1280 x 800 (its four views: FABRIK, DLS and the two learned solvers with an exact finish)."""
    page = open_studio(chromium, voila.url, page=blank_tab(chromium, (SCREEN["width"], SCREEN["height"])))
    try:
        voila.note_kernels()
        wait_for(lambda: page.locator(".posekit-views canvas").count() == 4 or None, 60, "four views")
        yield page
    finally:
        page.close()


def test_the_studio_app_fits_one_1280_by_800_screen(studio_page):
    page = studio_page
    page.locator(".posekit-target-x").first.wait_for(timeout=60_000)
    m = page.locator(".posekit-studio").first.evaluate(MEASURE)
    _shot(page, "voila_1280x800_studio.png")
    assert len(m["views"]) == 4
    _check(m, "the studio app")
    # one row of four views, each at least 250 px wide
    assert len({round(b["y"]) for b in m["views"]}) == 1 and min(b["width"] for b in m["views"]) >= 250, m["views"]


def _lab_widget(lab, chromium, notebook, find, what):  # noqa: F811
    """Run ``notebook`` in JupyterLab at 1280 x 800 with the file browser open; returns (page, the output area that
    holds ``find``)."""
    url, token, work = lab
    page = _lab_page(chromium, SCREEN)
    _open_and_run_all(page, url, token, work, notebook)
    if not page.locator("#filebrowser").is_visible():
        page.locator(".jp-SideBar li[data-id='filebrowser']").first.click()
    page.locator("#filebrowser").wait_for(state="visible", timeout=30_000)
    target = page.locator(find).first
    _wait_visible(page, target, 300, url, token, work, what)
    out = page.locator(".jp-OutputArea-output", has=target).first
    wait_for(lambda: out.locator(".posekit-target-x").count() >= 1 or None, 60, f"{what}'s sliders")
    assert out.bounding_box()["width"] < 1000, "the file browser is not open"
    return page, out


def test_the_studio_fits_one_screen_in_jupyterlab_with_the_file_browser_open(lab, chromium):  # noqa: F811
    page, out = _lab_widget(lab, chromium, STUDIO_NOTEBOOK, ".posekit-summary:has-text('update')", "the studio")
    try:
        wait_for(lambda: out.locator(".posekit-views canvas").count() == 4 or None, 60, "four views")
        m = out.locator(".posekit-studio").first.evaluate(MEASURE)
        _shot(page, "lab_1280x800_studio.png")
        assert len(m["views"]) == 4
        _check(m, "lesson 06's studio in JupyterLab")
    finally:
        page.close()


def test_the_rig_view_fits_one_screen_in_jupyterlab_with_the_file_browser_open(lab, chromium):  # noqa: F811
    page, out = _lab_widget(lab, chromium, RIG_NOTEBOOK, ".widget-html-content:has-text('rig at the learned')",
                            "lesson 02's rig view")
    try:
        m = out.evaluate(MEASURE)
        _shot(page, "lab_1280x800_rig.png")
        assert len(m["views"]) == 1
        _check(m, "lesson 02's rig view in JupyterLab")
    finally:
        page.close()
