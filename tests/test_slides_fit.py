"""Every slide of every lesson's deck fits the projector: headless Chromium steps through each deck as built by
``posekit course slides`` and fails on any slide whose content is taller or wider than the configured slide
(1280x720), or whose code or table is cut at its right edge. A clicker (PageDown, Space) goes to the next slide;
content below the bottom of a slide is lost to the room.

Needs Debian's ``chromium`` and Playwright's Python package (see tests/viz/test_browser.py).
"""

from __future__ import annotations

import pytest

from posekit.course.build import build_slides
from posekit.course.lessons import lessons
from posekit.course.slides import SLIDE_HEIGHT, SLIDE_WIDTH

pytestmark = pytest.mark.browser

LESSONS = lessons()

MEASURE = """() => {
  const s = Reveal.getCurrentSlide();
  const clipped = [...s.querySelectorAll('pre, table, .jp-OutputArea-output, img, mjx-container')]
    .filter(e => e.scrollWidth > e.clientWidth + 2 && getComputedStyle(e).overflowX !== 'visible').length;
  const imgs = [...s.querySelectorAll('img')].map(i => [i.complete && i.naturalWidth > 0, i.clientHeight]);
  return {h: s.scrollHeight, w: s.scrollWidth, clipped, imgs,
          title: (s.querySelector('h1, h2, h3, h4, p') || {textContent: ''}).textContent.trim().slice(0, 60)};
}"""
"""What one slide measures: its content's height and width (CSS pixels of the unscaled slide), how many of its
code blocks, tables, outputs or formulas are cut at their own right edge, its images (loaded, drawn height)
and its first line (for the failure message)."""


def open_deck(page, path):
    page.goto(path.as_uri())
    page.wait_for_function("() => window.Reveal && Reveal.isReady()", timeout=30_000)
    # MathJax typesets asynchronously: measure the formulas as drawn, not their TeX source
    page.wait_for_function("() => !window.MathJax || (MathJax.startup && MathJax.startup.promise)", timeout=30_000)
    page.evaluate("() => window.MathJax ? MathJax.startup.promise : null")
    page.evaluate("() => document.fonts.ready")


def slides_of(page):
    """Every slide of the open deck as (h, v) indices, in order."""
    return page.evaluate("""() => Reveal.getHorizontalSlides().flatMap((h, i) => {
      const v = h.querySelectorAll(':scope > section');
      return v.length ? [...v].map((_, j) => [i, j]) : [[i, 0]]; })""")


def measure_deck(page, path, shots=None):
    """Step through the deck at ``path``; returns one dict per slide (see :data:`MEASURE`), with ``at`` (h, v).
    ``shots``: a folder to save each slide's screenshot in."""
    open_deck(page, path)
    out = []
    for h, v in slides_of(page):
        page.evaluate(f"Reveal.slide({h}, {v})")
        m = page.evaluate(MEASURE)
        m["at"] = (h, v)
        out.append(m)
        if shots is not None:
            page.screenshot(path=str(shots / f"{path.stem}-{len(out):02d}.png"))
    return out


def too_big(m) -> list[str]:
    """What is wrong with one measured slide (empty: it fits)."""
    wrong = []
    if m["h"] > SLIDE_HEIGHT + 1:
        wrong.append(f"{m['h']} px tall")
    if m["w"] > SLIDE_WIDTH + 1:
        wrong.append(f"{m['w']} px wide")
    if m["clipped"]:
        wrong.append(f"{m['clipped']} block(s) cut at the right edge")
    if any(not ok for ok, _ in m["imgs"]):
        wrong.append("an image did not load")
    return wrong


@pytest.fixture(scope="module")
def decks(tmp_path_factory):
    out = tmp_path_factory.mktemp("course")
    return {r["lesson"]: r["path"] for r in build_slides(out, progress=False)}


@pytest.fixture(scope="module")
def page(chromium):
    yield chromium.new_page(viewport={"width": SLIDE_WIDTH, "height": SLIDE_HEIGHT})


@pytest.mark.parametrize("number", [le.number for le in LESSONS])
def test_every_slide_fits_the_screen(decks, page, number):
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    measured = measure_deck(page, decks[number])
    assert len(measured) == page.evaluate("Reveal.getTotalSlides()")
    bad = [f"slide {k} {m['at']} ({m['title']!r}): {', '.join(too_big(m))}"
           for k, m in enumerate(measured, 1) if too_big(m)]
    assert not bad, f"lesson {number}: {len(bad)} of {len(measured)} slides do not fit {SLIDE_WIDTH}x{SLIDE_HEIGHT}:\n" \
                    + "\n".join(bad)
    assert errors == []
