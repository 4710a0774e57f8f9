"""Every view and the selection's controls on one 1280 x 800 screen (issue 57, item 3), measured in headless
Chromium: the studio app in Voila, and in JupyterLab with the file browser open lesson 06's studio and lesson 02's
rig view (the lesson's own cells, trimmed as ``tests/viz/test_browser.py`` trims them).

Each test scrolls the widget's top to the top of the area that scrolls it (Voila's page; JupyterLab's notebook, under
its menu and tabs), then asserts that every view's canvas, the *selected* list and the X/Y/Z sliders lie wholly in
that area and on the 1280 x 800 screen, and that no label, readout, button or text of the widget is cut off
(``scrollWidth <= clientWidth``) nor any of its boxes scrolls sideways. Screenshots go to ``$POSEKIT_SHOTS`` when it
is set.

The same Voila page checks *views as PNG* (issue 57, item 4): the picture it exports holds every view's own canvas
pixels, titles and status lines.

Needs Debian's ``chromium`` and Playwright's Python package.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from posekit.bench.browser import blank_tab, chromium_missing, serve_voila
from posekit.bench.studio import open_studio
from tests.viz.screen_fit import MEASURE, SCREEN, off_screen
from tests.viz.test_browser import (RIG_NOTEBOOK, STUDIO_NOTEBOOK, _lab_page, _open_and_run_all, _wait_visible,
                                    lab)  # noqa: F401 - a fixture (chromium: tests/conftest.py)
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
    missing = chromium_missing()
    if missing:
        pytest.fail(missing)
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


_TEXTS = """(root) => [...root.querySelectorAll('.posekit-view')].filter(b => b.offsetParent !== null).map(b => [
  b.querySelector('.posekit-view-title .widget-html-content').innerText.trim(),
  b.querySelector('.posekit-view-label .widget-html-content').innerText.trim(),
  b.querySelector('canvas').width, b.querySelector('canvas').height])"""


def _registered_difference(region, shot):
    """Mean absolute difference (of 255) between a view of the PNG, ``region`` (the canvas's own pixels), scaled to
    the screenshot ``shot`` of a canvas on the page, at the best of the sub-pixel offsets 0 and +-0.5 px on each axis
    (where the page paints a canvas scaled to a fractional size and where the screenshot crops it differ by up to
    half a pixel, with the page's layout above it); 3 px of border left out."""
    from PIL import Image

    image = Image.fromarray(region.astype(np.uint8))
    best = np.inf
    for dx in (-0.5, 0.0, 0.5):
        for dy in (-0.5, 0.0, 0.5):
            moved = image.transform(image.size, Image.AFFINE, (1, 0, dx, 0, 1, dy), Image.BILINEAR)
            scaled = np.asarray(moved.resize(shot.shape[1::-1], Image.BILINEAR)).astype(int)
            best = min(best, float(np.abs(scaled - shot)[3:-3, 3:-3].mean()))
    return best


def test_views_as_png_holds_the_views_own_pixels_and_labels(studio_page):
    """Issue 57, item 4: *views as PNG* in the app gives one picture whose every view is that view's canvas (mean
    absolute difference to a screenshot of the canvas, scaled to the same size and registered to half a pixel,
    under 2.5 of 255 and under half its difference to any other view's screenshot), not blank, with each view's title and status lines around it."""
    from PIL import Image

    from posekit.viz.canvas_capture import decode_data_url
    from posekit.viz.views_picture import compose_views
    from tests.viz.browser_helpers import BACKGROUND, wait_still

    page = studio_page
    canvases = page.locator(".posekit-views canvas").all()
    shots = [wait_still(c, 30, "a view to stand still") for c in canvases]
    texts = page.locator(".posekit-studio").first.evaluate(_TEXTS)
    page.get_by_role("button", name="views as PNG").click()
    link = page.locator(".posekit-message-export a[download='views.png']")
    link.wait_for(timeout=60_000)
    raw = decode_data_url(link.get_attribute("href"))
    image = Image.open(__import__("io").BytesIO(raw)).convert("RGB")
    if os.environ.get("POSEKIT_SHOTS"):
        image.save(Path(os.environ["POSEKIT_SHOTS"]) / "voila_views_export.png")
    a = np.asarray(image).astype(int)
    # where compose_views put each view, given the texts and canvas sizes the page shows
    _, boxes = compose_views([np.zeros((h, w, 3)) for _, _, w, h in texts], [t[0] for t in texts],
                             [t[1] for t in texts])
    assert image.size[0] >= sum(w for _, _, w, _ in texts) and image.size[1] > max(h for *_, h in texts) + 40
    assert [b[2:] for b in boxes] == [(w, h) for *_, w, h in texts]
    diffs = []
    for k, ((x, y, w, h), shot) in enumerate(zip(boxes, shots)):
        region = a[y:y + h, x:x + w]
        assert (np.abs(region - BACKGROUND).sum(-1) > 60).mean() > 0.002, f"view {k + 1} is blank in the PNG"
        diffs.append([_registered_difference(region, s) for s in shots])
        assert (a[:y, x:x + w] < 100).all(-1).any(), f"no title above view {k + 1}"
        assert (a[y + max(b[3] for b in boxes):, x:x + w] < 100).all(-1).sum() > 50, f"no status under view {k + 1}"
    print("mean absolute difference, PNG view k vs screenshot of canvas j:", np.round(diffs, 2).tolist())
    for k, row in enumerate(diffs):  # its own canvas: about 1 here
        others = min(d for j, d in enumerate(row) if j != k)  # another view's canvas: 4-6 here
        assert row[k] < 2.5 and row[k] < others / 2, f"view {k + 1} of the PNG vs the screenshots: {row}"


_ARRIVAL = """(root) => {
  // where the parts lie as the page opens, nothing scrolled (the page's own scroll position: the top)
  const box = (el) => { const r = el.getBoundingClientRect();
    return {x: r.x, y: r.y, right: r.right, bottom: r.bottom, width: r.width, height: r.height}; };
  const visible = (el) => el.offsetParent !== null;
  const first = (list) => list.filter(visible).map(box)[0] ?? null;
  const views = [...root.querySelectorAll('.posekit-views canvas')].filter(visible).map(box);
  const selected = first([...root.querySelectorAll('.widget-dropdown')].filter(d => d.textContent.includes('selected')));
  const sliders = ['x', 'y', 'z'].map(a => first([...root.querySelectorAll(`.posekit-target-${a}`)]));
  const readout = first([...root.querySelectorAll('.widget-html-content')].filter(d => d.querySelector('th')
    && d.textContent.includes('x m')));
  return {views, parts: {selected, 'slider x': sliders[0], 'slider y': sliders[1], 'slider z': sliders[2], readout},
          scrolled: scrollY + (document.scrollingElement?.scrollTop ?? 0), width: innerWidth, height: innerHeight};
}"""


def _arrival(voila, chromium, size):  # noqa: F811
    """The studio app opened in a fresh tab of ``size`` (width, height): :data:`_ARRIVAL` measured as it opens."""
    page = open_studio(chromium, voila.url, page=blank_tab(chromium, size))
    try:
        wait_for(lambda: page.locator(".posekit-views canvas").count() == 4 or None, 60, "four views")
        page.locator(".posekit-target-x").first.wait_for(timeout=60_000)
        wait_for(lambda: page.locator(".posekit-views .widget-html-content th", has_text="x m").count() or None, 60,
                 "the readout")
        m = page.locator(".posekit-studio").first.evaluate(_ARRIVAL)
        _shot(page, f"voila_{size[0]}x{size[1]}_arrival.png")
        return m
    finally:
        page.close()


@pytest.mark.parametrize("size", [(1280, 800), (1366, 768)])
def test_the_app_shows_views_list_sliders_and_readout_on_the_first_screen_on_arrival(voila, chromium, size):  # noqa: F811
    """Issue 65: as the app opens, unscrolled, at 1280 x 800 and 1366 x 768, the four views, the *selected* list, the
    X/Y/Z sliders and the readout (the selected joint's table) lie wholly in the window (the old header, 185 px
    tall, pushed the sliders and the readout below it)."""
    m = _arrival(voila, chromium, size)
    width, height = size
    print(size, m)
    assert m["scrolled"] == 0 and len(m["views"]) == 4
    parts = [(f"view {k + 1}", b) for k, b in enumerate(m["views"])] + list(m["parts"].items())
    out = [f"{name}: {b}" for name, b in parts
           if b is None or b["x"] < -0.5 or b["y"] < -0.5 or b["right"] > width + 0.5 or b["bottom"] > height + 0.5]
    assert out == [], f"not on the first screen at {width} x {height}: {out}"


def test_the_views_grow_with_a_1920_by_1080_window(voila, chromium):  # noqa: F811
    """Issue 65: at 1920 x 1080 the four views share the window's width (the old views stayed 312 px wide, their
    canvas's own width, half the width empty), and the *selected* list, the sliders and the readout still lie on
    the first screen."""
    m = _arrival(voila, chromium, (1920, 1080))
    views = m["views"]
    print([round(v["width"]) for v in views], m["parts"])
    assert len(views) == 4 and len({round(v["y"]) for v in views}) == 1
    assert min(v["width"] for v in views) >= 400, [v["width"] for v in views]
    assert max(v["right"] for v in views) - min(v["x"] for v in views) >= 0.8 * 1920
    assert all(b is not None and b["bottom"] <= 1080 for b in m["parts"].values()), m["parts"]
