"""What the one-screen tests measure in a page (issue 57, item 3): where a widget's views and controls lie on the
screen, and which of its texts are cut off."""

from __future__ import annotations

SCREEN = {"width": 1280, "height": 800}
"""The screen the studio, the lessons' views and lesson 02's rig view must fit: 1280 x 800 pixels."""

MEASURE = """(root) => {
  // the widget's top scrolled to the top of the area that scrolls it (the page in Voila, the notebook in JupyterLab)
  root.scrollIntoView({block: 'start'});
  const box = (el) => { const r = el.getBoundingClientRect();
    return {x: r.x, y: r.y, right: r.right, bottom: r.bottom, width: r.width, height: r.height}; };
  // what of the page is visible there: the screen cut by every ancestor that hides or scrolls its overflow
  const seen = {x: 0, y: 0, right: innerWidth, bottom: innerHeight};
  for (let a = root.parentElement; a && a !== document.body; a = a.parentElement) {
    const style = getComputedStyle(a);
    if (!/(auto|scroll|hidden)/.test(style.overflowX + style.overflowY)) continue;
    const r = a.getBoundingClientRect();
    seen.x = Math.max(seen.x, r.x); seen.y = Math.max(seen.y, r.y);
    seen.right = Math.min(seen.right, r.right); seen.bottom = Math.min(seen.bottom, r.bottom);
  }
  const visible = (el) => el.offsetParent !== null;
  const views = [...root.querySelectorAll('canvas')].filter(visible).map(box);
  const selected = [...root.querySelectorAll('.widget-dropdown')].filter(d => d.textContent.includes('selected'))
    .filter(visible).map(box);
  const sliders = ['x', 'y', 'z'].map(a => [...root.querySelectorAll(`.posekit-target-${a}`)].filter(visible).map(box));
  // text cut off: a label, a readout, a button or a HTML text wider than its box (ellipsis or hidden overflow)
  const texts = [...root.querySelectorAll('.widget-label, .widget-readout, button, .widget-html-content, '
                                          + '.widget-dropdown select')].filter(visible);
  const clipped = texts.filter(el => el.scrollWidth > el.clientWidth + 1)
    .map(el => `${(el.textContent || el.value || '').trim().slice(0, 40)}: ${el.scrollWidth} px in ${el.clientWidth} px`);
  // a box that scrolls sideways hides part of what it holds
  const scrolled = [...root.querySelectorAll('.widget-box')].filter(visible)
    .filter(el => el.scrollWidth > el.clientWidth + 2)
    .map(el => `${el.className.split(' ').slice(0, 3).join('.')}: ${el.scrollWidth} px in ${el.clientWidth} px (` +
      [...el.children].filter(c => c.getBoundingClientRect().right > el.getBoundingClientRect().right + 1)
        .map(c => `${c.className.split(' ').slice(-2).join('.')} ${c.getBoundingClientRect().width.toFixed(0)} px`)
        .join(', ') + ')');
  return {root: box(root), seen, viewport: {width: innerWidth, height: innerHeight}, views, selected, sliders,
          clipped, scrolled, texts: texts.length};
}"""
"""JavaScript for ``locator.evaluate``: scroll the widget's top to the top of its scrolling area, then return the
bounding boxes (page pixels, the screen's top left at 0, 0) of its canvases, its *selected* list and its X/Y/Z
sliders, the visible area of its scroller, and the texts cut off inside it."""


def off_screen(m: dict, screen=SCREEN) -> list:
    """Which of the measured parts (:data:`MEASURE`) lie not wholly on the screen, nor wholly in the area that
    scrolls the widget: a list of sentences, empty when all do."""
    left, top = max(0, m["seen"]["x"]), max(0, m["seen"]["y"])
    right, bottom = min(screen["width"], m["seen"]["right"]), min(screen["height"], m["seen"]["bottom"])
    parts = [(f"view {k + 1}", b) for k, b in enumerate(m["views"])] + [("selected", b) for b in m["selected"][:1]]
    parts += [(f"slider {a}", s[0]) for a, s in zip("xyz", m["sliders"]) if s]
    out = [f"{name} at x {b['x']:.0f}-{b['right']:.0f}, y {b['y']:.0f}-{b['bottom']:.0f} (visible: x {left:.0f}-"
           f"{right:.0f}, y {top:.0f}-{bottom:.0f})" for name, b in parts
           if b["x"] < left - 0.5 or b["y"] < top - 0.5 or b["right"] > right + 0.5 or b["bottom"] > bottom + 0.5]
    missing = [name for name, found in (("selected", m["selected"]), *zip(("slider x", "slider y", "slider z"),
                                                                           m["sliders"])) if not found]
    return out + [f"{name}: not found" for name in missing]
