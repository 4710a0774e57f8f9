"""The posing studio as a browser app: notebook 06 served by Voila, driven in a real headless Chromium.

It loads and every view draws a skeleton; as it opens the page sends its kernel next to nothing and asks nothing of
any other server; the kernel's websocket sends without Nagle's delay; dragging a target in 3D re-solves every view;
a rotation and a look-at effector change the pose; the BVH export downloads a file posekit's reader parses; 1,000
rapid target updates all arrive, the page posts itself no message (Voila's log forwarding), the kernel survives and
its memory does not grow (the latency is printed, not asserted: ``posekit bench studio`` measures it); and Voila's
kernel is gone when the test ends.

Needs Debian's ``chromium`` (``make test`` installs it) and Playwright's Python package.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from tests.viz.browser_helpers import (BACKGROUND, SENT_LOG, drag_in_3d, kernel_round_trip, pixels as _pixels,
                                      press_five, press_in_3d, presses_right_after_selections, selected_joint, wait_for,
                                      wait_still)
from posekit.bench.browser import blank_tab, chromium_missing, serve_voila
from posekit.bench.studio import choose_solvers, open_studio, rapid_updates, update_number

pytestmark = pytest.mark.browser

VIEWS = ".posekit-views"
ASKED_OUTSIDE = []
"""What the studio's page asked of any server but its own (the page fixture's tab)."""


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    missing = chromium_missing()
    if missing:
        pytest.fail(missing)
    with serve_voila(folder=tmp_path_factory.mktemp("voila"), cull_idle_s=600) as s:
        yield s


@pytest.fixture(scope="module")
def page(server, chromium):
    """The studio app in a tab of ``tests/conftest.py``'s browser."""
    tab = blank_tab(chromium)
    tab.add_init_script(SENT_LOG)
    own = (server.base, "data:", "blob:")
    tab.on("request", lambda r: r.url.startswith(own) or ASKED_OUTSIDE.append(r.url))
    pg = open_studio(chromium, server.url, page=tab)
    server.note_kernels()
    try:
        yield pg
    finally:
        if not pg.is_closed():
            pg.close()


def _labels(page):
    return page.locator(f"{VIEWS} .widget-html-content", has_text="time")


def _texts(page):
    return [t for t in _labels(page).all_inner_texts()]


def _canvases(page):
    return page.locator(f"{VIEWS} canvas").all()


def _images(page):
    return [_pixels(c) for c in _canvases(page)]


def _all_changed(before, after, frac=0.0005):
    return all((np.abs(a - b).sum(-1) > 60).mean() > frac for a, b in zip(before, after))


def _wait_update(page, n0, what, timeout=60):
    wait_for(lambda: update_number(page) > n0, timeout, what, every=0.2)


def test_studio_loads_and_every_view_shows_a_skeleton(page):
    canvases = _canvases(page)
    assert len(canvases) == 4  # the notebook compares FABRIK, DLS and two learned solvers with an exact finish
    for c in canvases:
        img = wait_for(lambda c=c: (lambda im: im if (np.abs(im - BACKGROUND).sum(-1) > 60).mean() > 0.002
                                     else None)(_pixels(c)), 60, "a skeleton on every canvas")
        assert (np.abs(img - BACKGROUND).sum(-1) > 60).mean() > 0.002
    texts = _texts(page)
    assert len(texts) == 4 and all("worst effector" in t and "ms" in t for t in texts), texts
    # issue 44: the left hand, selected as the app opens, is yellow from the first display (it was blue)
    def yellow():
        im = _pixels(canvases[0])
        r, g, b = im[..., 0], im[..., 1], im[..., 2]
        return ((r > 180) & (g > 120) & (g < 215) & (b < 90)).sum() > 3

    wait_for(yellow, 30, "the selected joint's yellow marker in the first view")
    summary = page.locator(".posekit-summary").inner_text()
    assert all(n in summary for n in ("fabrik", "dls", "protores+dls", "latent-opt+dls")), summary


def test_an_opening_page_reports_almost_nothing_back_and_asks_nothing_outside(page):
    # the views' models hold what the browser computes (buffer versions, matrices, projections, lights' parts), so
    # the page does not send them back: about 200 updates and 12 new models, each handled by the kernel, before
    wait_for(lambda: update_number(page) >= 0, 60, "the summary")
    # what the page sends once the views are drawn: anything sent before the round trip's switch on and off
    kernel_round_trip(page, VIEWS)
    sent = page.evaluate("() => window.__posekit_sent")
    assert page.evaluate("() => window.__posekit_switches") == [True, False]  # the round trip's own
    assert not [s for s in sent if s[0] == "open"], sent
    three = {"version", "matrix", "projectionMatrix", "matrixWorldNeedsUpdate", "morphTargetInfluences", "type"}
    assert not [s for s in sent if three & set(s)], sent
    assert len(sent) <= 6, sent  # the three target sliders' values, snapped to their steps by the browser
    # and it asks nothing of the internet (Voila's own page fetched two stylesheets from a CDN)
    assert ASKED_OUTSIDE == []


def test_the_kernel_sends_to_the_page_without_nagles_delay(server, page):
    # make studio's setting (posekit.viz.websocket): the page's websocket socket has TCP_NODELAY, as the server read
    # it back while the page connected (each message of an update used to wait ~30 ms for the previous one's ack); the
    # page fixture has already seen the studio drawn, so the connection is made
    assert "websocket TCP_NODELAY=1" in server.log_tail(10 ** 6), server.log_tail()


def _joint_list(page):
    """The first view's *selected* joint list (a select element)."""
    return page.locator(VIEWS).locator(".widget-dropdown", has_text="selected").first.locator("select")


def _status_rows(page):
    """The first view's status table under its sliders: row label -> (x, y, z) in metres."""
    table = page.locator(VIEWS).locator(".widget-html-content", has=page.locator("th", has_text="x m")).first
    rows = {}
    for tr in table.locator("tr").all()[1:]:
        label = tr.locator("th").inner_text().strip()
        rows[label] = tuple(float(t) for t in tr.locator("td").all_inner_texts()[:3])
    return rows


def _buttons_disabled(page):
    return [page.locator(".widget-button", has_text=n).first.is_disabled() for n in ("undo", "redo")]


def test_a_fresh_studio_has_no_history_and_selecting_moves_nothing(page):
    """Issue 27: choosing joints one after another (the sliders re-range each time) never moves a target,
    adds an effector or re-solves; the helper root is not offered; a fresh studio has nothing to undo or redo."""
    assert _buttons_disabled(page) == [True, True]
    joints = _joint_list(page)
    assert "joint_Root" not in joints.locator("option").all_inner_texts()
    n0, texts = update_number(page), _texts(page)
    for j in ("Head", "Hand_R", "Foot_L", "Hand_R", "Chest", "Hand_L"):
        joints.select_option(j)
        kernel_round_trip(page, VIEWS)  # the kernel has handled the choice and any echo of the re-ranged sliders
    assert update_number(page) == n0, "selecting joints re-solved: a target moved or an effector was added"
    assert _texts(page) == texts
    assert _buttons_disabled(page) == [True, True]
    assert "target" in _status_rows(page)  # the left hand (selected last) has its target, where it was


RACE_JOINTS = ("Hand_R", "Head", "Foot_L", "Hand_L")
"""Joints with a position target in the studio's set-up (hands, feet, head): a press moves their target only."""

def test_a_press_right_after_a_selection_moves_the_new_joint_by_one_step(page):
    """Issue 44: choose a joint and press the Y slider's arrow key within 50 ms (the press handled right behind the
    selection, in the same turn of the page's event loop), while the slider on the page is still the previous
    joint's, 20 times over four joints, with a second process keeping a core busy: every press moves the joint
    chosen last by exactly one step (1 mm up), and no other target moves (the old code applied the previous joint's
    value plus a step to the new joint, or took the press for an echo and dropped it)."""
    gaps, on_old = presses_right_after_selections(page, page.locator(VIEWS), RACE_JOINTS)
    print(f"\npresses {max(gaps):.0f} ms or less after the selection; {on_old} of 20 on the previous joint's slider")
    assert max(gaps) < 50, gaps
    assert on_old >= 1, "no press reached the previous joint's slider: the test did not race"


def test_reset_view_brings_an_orbited_view_back(page, server):
    """Issue 44: orbit the first view with the mouse, press *reset view*: the view shows what it showed after an
    earlier reset (the pose framed from the front), not the orbited picture."""
    first = _canvases(page)[0]
    reset = page.locator(VIEWS).get_by_role("button", name="reset view")
    reset.click()
    framed = wait_for(lambda: (lambda a: a if (np.abs(a - _pixels(first)).sum(-1) > 60).mean() < 0.001 else None)(
        _pixels(first)), 30, "the view to stand still after a reset")
    first.scroll_into_view_if_needed()
    box = first.bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] * 0.8
    page.mouse.move(cx, cy)
    page.mouse.down()
    page.mouse.move(cx + 120, cy - 30, steps=10)
    page.mouse.up()
    wait_for(lambda: (np.abs(_pixels(first) - framed).sum(-1) > 60).mean() > 0.01, 30, "the view to orbit")
    page.screenshot(path=str(server.folder / "studio_orbited.png"))
    reset.click()
    wait_for(lambda: (np.abs(_pixels(first) - framed).sum(-1) > 60).mean() < 0.002, 30,
             "the view to show the framed picture again")
    page.screenshot(path=str(server.folder / "studio_reset.png"))


def _drag_in_3d(page, canvas, at, by):
    """Switch *drag in 3D* on, press at pixel ``at`` (x, y) of ``canvas`` (:func:`press_in_3d`) and move the mouse
    ``by`` (dx, dy) pixels."""
    x, y = press_in_3d(page, canvas, at, VIEWS)
    page.mouse.move(x + by[0], y + by[1], steps=8)
    page.mouse.up()


def test_dragging_a_target_in_3d_resolves_every_view(page, server):
    first = _canvases(page)[0]
    first.scroll_into_view_if_needed()
    before, texts, n0 = _images(page), _texts(page), update_number(page)
    # the selected joint (the left hand, on its target) is drawn larger and yellow
    _drag_in_3d(page, first, selected_joint(_pixels(first)), (15, -45))
    _wait_update(page, n0, "a solve after the drag")
    # every view re-solved (the summary's update) and re-posed, each still on the moved target; a status line may
    # read as before (FABRIK: 0.0 mm, 2 iterations, the same time to the hundredth of a ms)
    wait_for(lambda: _all_changed(before, _images(page)), 60, "every view to re-pose")
    assert len(_texts(page)) == len(texts) and all("reached" in t for t in _texts(page)), _texts(page)
    # the target moved up (the sliders show it) and the studio counted the drag as one undo step
    # (the sliders wait for the mouse to be released, which the kernel may reach after the moves queued before it)
    readout = page.locator(".posekit-target-y .widget-readout").first
    wait_for(lambda: float(readout.inner_text()) > 0.949 + 0.02, 60, "the Y slider to show the target moved up")
    drag_in_3d(page, VIEWS, False)  # orbit again
    page.screenshot(path=str(server.folder / "studio_after_drag.png"))


def test_undo_after_a_drag_that_widened_the_view_brings_back_the_view_as_it_was(page, server):
    """Issue 44: a drag in 3D out past the view's edge widens the camera once the mouse is up; *undo* brings
    back the pose and the camera together, so every pixel of the view is as before the drag (before the fix the
    camera came back turned away from the pose: about a tenth of the view's pixels differed)."""
    first = _canvases(page)[0]
    first.scroll_into_view_if_needed()
    before, n0 = _pixels(first), update_number(page)
    readout = page.locator(".posekit-target-y .widget-readout").first
    ty0 = float(readout.inner_text())
    x, y = press_in_3d(page, first, selected_joint(before), VIEWS)
    box = first.bounding_box()
    page.mouse.move(box["x"] + box["width"] - 3, box["y"] + 5, steps=20)  # up and out past the corner
    page.mouse.up()
    _wait_update(page, n0, "a solve after the drag")
    wait_for(lambda: _changed_fraction(before, _pixels(first)) > 0.02, 60, "the view to show the dragged pose")
    # the drag kept the camera's scale while the mouse was down: the corner is a few hand-spans up, not metres
    # (the issue: a view that widened mid-drag turned a 120 px drag into a 1.94 m lift). The sliders wait for the
    # mouse to be released: on a busy machine the kernel is still solving the moves queued before it
    ty = wait_for(lambda: (lambda v: v if v != ty0 else None)(float(readout.inner_text())), 60,
                  "the sliders to show where the target went once the mouse was released")
    assert 0.1 < ty - ty0 < 1.0, f"the hand's target went from y = {ty0} to {ty} m"
    drag_in_3d(page, VIEWS, False)  # orbit again
    n1 = update_number(page)
    page.locator(".widget-button", has_text="undo").first.click()
    _wait_update(page, n1, "a solve after undo")
    # the view settles on the picture it showed before the drag (a state of the page, not a pause)
    wait_for(lambda: _changed_fraction(before, _pixels(first)) < 0.002, 60,
             "the view after undo to be the view before the drag")


def _held(page):
    """Whether the kernel holds a drag: it marks the *drag in 3D* switch with DRAG_HELD_CLASS meanwhile."""
    from posekit.viz.drag import DRAG_HELD_CLASS

    toggle = page.locator(VIEWS).get_by_role("button", name="drag in 3D").first
    return DRAG_HELD_CLASS in (toggle.get_attribute("class") or "").split()


def _hand_target(page):
    return wait_for(lambda: _status_rows(page).get("target"), 30, "the left hand's target in the status table")


RELEASES = ("over the page", "outside the window", "the window losing focus")
"""Where issue 57's drags end: the button let go over another part of the page (the view's heading), let go beyond
the window's left edge, or the window losing focus while the button is down outside it."""


def _magenta(img):
    """Pixels of a lit magenta target marker."""
    r, g, b = (img[..., k].astype(int) for k in range(3))
    return (r > 150) & (g < 100) & (b > 90) & (b < r)


@pytest.mark.parametrize("release", RELEASES)
def test_a_drag_ends_wherever_the_button_is_let_go(page, server, release):
    """Issue 57, item 1: press on the selected hand with *drag in 3D* on, drag its target to the view's top corner,
    out of the framed region, then on out of the view (above it, never back across it) and let go there. The kernel
    lets go (before, only a release on the canvas did: hovering with no button then kept moving the target, once
    below the floor), the view widens to take the target in (its marker leaves the canvas' top rows), and hovering
    over the view with no button down moves nothing."""
    _joint_list(page).select_option("Hand_L")
    page.locator(VIEWS).get_by_role("button", name="reset view").click()  # the pose framed: a corner is out of frame
    kernel_round_trip(page, VIEWS)  # orbiting, nothing held
    first = _canvases(page)[0]
    first.scroll_into_view_if_needed()
    img = wait_still(first, 30, "the view to stand still")
    box = first.bounding_box()
    press_in_3d(page, first, selected_joint(img), VIEWS)
    wait_for(lambda: _held(page), 30, "the kernel to hold the drag")
    page.mouse.move(box["x"] + box["width"] - 3, box["y"] + 3, steps=12)  # the target to the top-right corner
    # a state, not a pause: on a loaded machine each move waits for a solve of every view, and two screenshots half a
    # second apart can look alike while the target is still on its way (a marker that moved a few pixels)
    t0 = time.time()
    while _magenta(_pixels(first)[:12]).sum() <= 3:
        if time.time() - t0 > 90:
            where = np.argwhere(_magenta(_pixels(first)))
            pytest.fail("the dragged target did not reach the view's top edge in 90 s (the kernel "
                        f"{'still holds' if _held(page) else 'has let go of'} the drag; magenta pixels from row, col "
                        f"{where.min(0).tolist() if len(where) else None} to {where.max(0).tolist() if len(where) else None})")
        time.sleep(0.5)
    page.mouse.move(box["x"] + box["width"] - 3, box["y"] - 14, steps=3)  # up, out of the view, over its heading
    if release == "over the page":
        page.mouse.move(box["x"] + 30, box["y"] - 14, steps=4)
        page.mouse.up()
    else:
        page.mouse.move(-40, box["y"] - 14, steps=6)  # left, along the heading and beyond the window's edge
        if release == "outside the window":
            page.mouse.up()
        else:  # the person switched to another window, the button still down
            page.evaluate("() => window.dispatchEvent(new FocusEvent('blur'))")
    wait_for(lambda: not _held(page), 60, f"the kernel to let go of the drag released {release}")
    if release == "the window losing focus":
        page.mouse.up()  # (Playwright's mouse), once the kernel has let go
    # the view widened once let go: the camera stepped back and re-centred, the target is in view, off the top rows
    after = wait_for(lambda: (lambda im: im if _magenta(im[:12]).sum() == 0 else None)(_pixels(first)), 60,
                     "the view to take the target in")
    assert _magenta(after).sum() > 3
    page.screenshot(path=str(server.folder / f"studio_released_{release.replace(' ', '_')}.png"))
    where = _hand_target(page)
    # hover over the view with no button down: nothing moves (a barrier: the kernel handles the page's messages in
    # order, so every hover has been handled once the round trip's switch comes back)
    for fx, fy in ((0.5, 0.5), (0.3, 0.9), (0.8, 0.2), (0.5, 0.99)):
        page.mouse.move(box["x"] + fx * box["width"], box["y"] + fy * box["height"], steps=6)
    assert not _held(page)
    kernel_round_trip(page, VIEWS)
    assert _hand_target(page) == where, "hovering with no button down moved the target"


def _yellow(img) -> int:
    """How many pixels of a canvas image are the selected joint's yellow."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return int(((r > 180) & (g > 120) & (g < 215) & (b < 90)).sum())


def _select_quietly(page, joint):
    """Choose ``joint`` in the first view's *selected* list from a script: the keyboard's focus stays where it is (a
    person's double-click on a joint, or a lesson's code, does not take it either)."""
    page.evaluate("""([scope, joint]) => {
      const list = [...scope.querySelectorAll('.widget-dropdown')].find(d => d.textContent.includes('selected'))
        .querySelector('select');
      list.value = joint;
      list.dispatchEvent(new Event('change', {bubbles: true}));
    }""", [page.locator(VIEWS).element_handle(), joint])


def test_key_presses_right_after_a_selection_all_reach_the_new_joint(page):
    """Issue 57, item 2: focus the X slider's handle of the selected joint, choose another joint and at once press
    ArrowRight 5 times, 30 ms apart, 20 times over four joints, a second process keeping a core busy. The kernel
    replaces the slider models for the new joint while the keys arrive; every trial must move the new joint's target
    +5 mm on X and nothing else (before, the focus fell to the page's body with the old handle and the presses
    after the swap went nowhere: a user measured 5 of 10 trials moving 0-1 mm)."""
    import subprocess
    import sys

    from tests.viz.browser_helpers import target_mm

    scope = page.locator(VIEWS)
    joints = RACE_JOINTS
    where = {}
    for j in joints:
        _joint_list(page).select_option(j)
        where[j] = wait_for(lambda j=j: target_mm(scope, j), 30, f"{j}'s target in the status table")
    kernel_round_trip(page, VIEWS)
    expected, moved = dict(where), []
    handle = scope.locator(".posekit-target-x .noUi-handle").first
    readout = scope.locator(".posekit-target-x .widget-readout").first
    busy = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        for i in range(20):
            old, new = joints[(i - 1) % len(joints)], joints[i % len(joints)]
            # the old joint's sliders are shown (their X readout is its target's x), its X handle has the keyboard
            wait_for(lambda: readout.inner_text().replace("\u2212", "-") == f"{expected[old][0] / 1000:.3f}", 30,
                     f"{old}'s X slider")  # (d3's readout writes a minus sign, not a hyphen)
            handle.focus()
            assert page.evaluate("() => document.activeElement.classList.contains('noUi-handle')")
            _select_quietly(page, new)
            moved.append(press_five(page, scope, new, expected))
    finally:
        busy.kill()
        busy.wait()
    print(f"\nX moved per trial (mm): {moved}")
    assert moved == [5] * 20, f"{sum(m == 5 for m in moved)} of 20 trials moved +5 mm: {moved}"
    for j in joints:  # every target moved by its own presses only
        _joint_list(page).select_option(j)
        wait_for(lambda j=j: target_mm(scope, j) == expected[j], 30, f"{j}'s target at {expected[j]} mm")


_SELECT_THEN_FOCUS = """([scope, joints]) => {
  // a person's choice in the *selected* list (the list has the focus, its value changes; two choices at once when
  // the arrow keys pass over a joint), then at once the X slider's handle focused: the handle on the page now, the
  // outgoing joint's until the kernel's new sliders come
  const list = [...scope.querySelectorAll('.widget-dropdown')].find(d => d.textContent.includes('selected'))
    .querySelector('select');
  list.focus();
  for (const joint of joints) {
    list.value = joint;
    list.dispatchEvent(new Event('input', {bubbles: true}));
    list.dispatchEvent(new Event('change', {bubbles: true}));
  }
  const handle = scope.querySelector('.posekit-target-x .noUi-handle');
  handle.focus();
  window.__focused = handle;
  return document.activeElement === handle;
}"""


def test_presses_right_after_choosing_in_the_list_all_land_on_the_new_joint(page):
    """Issue 65, item 3: choose a joint in the *selected* list, at once focus the X slider's handle (still the
    outgoing joint's: the kernel has not yet made the new joint's sliders) and press ArrowRight 5 times, 30 ms apart,
    10 times over four joints, a second process keeping a core busy; every other trial passes over another joint on
    the way (two choices at once: the list's second message waits in the page for the kernel's answer to the first,
    while the slider's leave at once). Every trial moves the joint chosen last +5 mm on X, and no other target moves:
    not the joint chosen before, not the one passed over (a press on the outgoing handle used to reach the kernel
    before the second choice and move the joint passed over; before issue 57 some trials lost all five presses)."""
    import subprocess
    import sys

    from tests.viz.browser_helpers import target_mm

    scope = page.locator(VIEWS)
    joints = RACE_JOINTS
    where = {}
    for j in joints:
        _joint_list(page).select_option(j)
        where[j] = wait_for(lambda j=j: target_mm(scope, j), 30, f"{j}'s target in the status table")
    kernel_round_trip(page, VIEWS)
    expected, moved, on_old = dict(where), [], 0
    root = scope.element_handle()
    busy = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        for i in range(10):
            old, new = joints[(i - 1) % len(joints)], joints[i % len(joints)]
            chosen = [new] if i % 2 == 0 else [joints[(i + 1) % len(joints)], new]
            wait_for(lambda: target_mm(scope, old) == expected[old], 30, f"{old}'s sliders and target")
            kernel_round_trip(page, VIEWS)  # the old joint's sliders are the ones on the page
            assert page.evaluate(_SELECT_THEN_FOCUS, [root, chosen]), "the X slider's handle did not take the focus"
            moved.append(press_five(page, scope, new, expected))
            on_old += page.evaluate("() => !window.__focused.isConnected")  # the handle focused was replaced
    finally:
        busy.kill()
        busy.wait()
    print(f"\nX moved per trial (mm): {moved}; {on_old} of 10 focused the outgoing joint's handle")
    assert moved == [5] * 10, f"{sum(m == 5 for m in moved)} of 10 trials moved +5 mm: {moved}"
    for j in joints:  # every target moved by its own presses only: none landed on a joint chosen before
        _joint_list(page).select_option(j)
        wait_for(lambda j=j: target_mm(scope, j) == expected[j], 30, f"{j}'s target at {expected[j]} mm")
    assert on_old >= 1, "no trial focused the outgoing joint's handle: the test did not race"


def _changed_fraction(a, b):
    """The share of pixels whose colour differs by more than 30 in a channel."""
    return float((np.abs(a.astype(int) - b.astype(int)).max(axis=-1) > 30).mean())


def _orange(img):
    """Pixels of a lit orange look-at marker (not the yellow selection marker, not the red bones)."""
    r, g, b = (img[..., k].astype(float) for k in range(3))
    ratio = g / np.maximum(r, 1)
    return (r > 150) & (ratio > 0.4) & (ratio < 0.68) & (b < 0.35 * r)


def test_a_look_at_marker_drags_its_own_target(page, server):
    """Issue 27: the head holds a position and a look-at effector. Pressing on the orange marker (drag in 3D)
    moves the point it looks at and leaves its position target; the *sliders move* choice appears and, on
    look-at, the X slider moves the look-at target too."""
    _add(page, "Head", "look-at")
    _joint_list(page).select_option("Head")
    wait_for(lambda: "looks at" in _status_rows(page), 30, "the head's look-at target in the status table")
    rows0 = _status_rows(page)
    choice = page.locator(VIEWS).locator(".widget-toggle-buttons", has_text="sliders move")
    assert choice.is_visible()
    first = _canvases(page)[0]
    first.scroll_into_view_if_needed()
    img = _pixels(first)
    ys, xs = np.nonzero(_orange(img))
    assert len(xs) > 3, "the orange look-at marker is not on the canvas"
    n0 = update_number(page)
    _drag_in_3d(page, first, (float(np.median(xs)), float(np.median(ys))), (40, -20))
    drag_in_3d(page, VIEWS, False)  # orbit again
    _wait_update(page, n0, "a solve after dragging the orange marker")
    rows1 = wait_for(lambda: (lambda r: r if r.get("looks at") != rows0["looks at"] else None)(_status_rows(page)),
                     30, "the look-at target to move")
    assert rows1["target"] == rows0["target"], "dragging the look-at marker moved the head's position target"
    # the sliders: switch them to the look-at target and push X
    choice.get_by_role("button", name="look-at").click()
    kernel_round_trip(page, VIEWS)  # the sliders now hold the look-at target
    n0 = update_number(page)
    _drag_slider(page, page.locator(".posekit-target-x .noUi-handle").first, 60)
    _wait_update(page, n0, "a solve after the look-at slider")
    rows2 = wait_for(lambda: (lambda r: r if r["looks at"][0] != rows1["looks at"][0] else None)(_status_rows(page)),
                     30, "the look-at target to follow the X slider")
    assert rows2["target"] == rows0["target"]
    choice.get_by_role("button", name="target").click()
    page.screenshot(path=str(server.folder / "studio_look_at.png"))


def _add(page, joint, kind):
    n0 = update_number(page)
    row = page.locator(VIEWS).locator(".widget-hbox", has=page.get_by_role("button", name="add effector"))
    row.locator(".widget-dropdown", has_text="joint").locator("select").select_option(joint)
    row.locator(".widget-dropdown", has_text="kind").locator("select").select_option(kind)
    row.get_by_role("button", name="add effector").click()
    _wait_update(page, n0, f"the {kind} effector on {joint}")


def _drag_slider(page, handle, dx):
    handle.scroll_into_view_if_needed()
    box = handle.bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] / 2 + dx, box["y"] + box["height"] / 2, steps=6)
    page.mouse.up()


def test_rotation_and_look_at_effectors_change_the_pose(page):
    # a rotation on the chest, turned with its yaw slider: DLS and ProtoRes (which honour rotations) re-pose
    _add(page, "Chest", "rotation")
    canv = _canvases(page)
    before = [_pixels(c) for c in canv[1:]]
    texts = _texts(page)[1:]
    n0 = update_number(page)
    _drag_slider(page, page.locator(VIEWS).locator(".widget-slider", has_text="yaw").locator(".noUi-handle").first, 90)
    _wait_update(page, n0, "a solve after the yaw slider")
    wait_for(lambda: all(a != b for a, b in zip(_texts(page)[1:], texts)), 60, "DLS and ProtoRes to follow the yaw")
    wait_for(lambda: _all_changed(before, [_pixels(c) for c in _canvases(page)[1:]]), 30, "their views to turn")
    assert all("°" in t for t in _texts(page)[1:])  # an angular error is reported
    # a look-at on the neck, its target moved with the sliders (the first view's joint list selects it)
    _add(page, "Neck", "look-at")
    page.locator(VIEWS).locator(".widget-dropdown", has_text="selected").first.locator("select").select_option("Neck")
    before = [_pixels(c) for c in _canvases(page)[1:]]
    texts = _texts(page)[1:]
    n0 = update_number(page)
    _drag_slider(page, page.locator(".posekit-target-x .noUi-handle").first, 120)
    _wait_update(page, n0, "a solve after moving the look-at target")
    wait_for(lambda: all(a != b for a, b in zip(_texts(page)[1:], texts)), 60, "DLS and ProtoRes to look")
    wait_for(lambda: _all_changed(before, [_pixels(c) for c in _canvases(page)[1:]]), 30, "their views to turn")
    # FABRIK honours positions only: its view names what it ignored and does not call it reached
    fabrik = _texts(page)[0]
    ignored = fabrik.split("reached")[1].split("ignored")[0] if "ignored" in fabrik else ""
    assert "rotation" in ignored and "look-at" in ignored and "✓ reached" not in fabrik, fabrik


def test_bvh_export_downloads_a_file_posekit_reads(page, tmp_path):
    from posekit.io.bvh import read_bvh

    page.locator(".widget-dropdown", has_text="export").locator("select").select_option("dls")
    page.get_by_role("button", name="pose as BVH").click()
    message = page.locator(".posekit-message-export")
    wait_for(lambda: "read back within 0.000 mm" in message.inner_text(), 60, "the export message")
    with page.expect_download(timeout=30_000) as dl:
        message.get_by_text("download pose_dls.bvh").click()
    path = tmp_path / "pose.bvh"
    dl.value.save_as(path)
    motion = read_bvh(path)
    assert motion.n_frames == 1 and len(motion.skeleton.names) == 22 and motion.skeleton.names[1] == "Hips"
    # a malformed setup upload is reported in the app and nothing is lost
    n_rows = page.locator(VIEWS).get_by_role("button", name="remove").count()
    with page.expect_file_chooser(timeout=30_000) as chooser:
        page.get_by_role("button", name="upload setup / BVH").click()
    chooser.value.set_files(files=[{"name": "bad.json", "mimeType": "application/json",
                                    "buffer": b'{"format": "posekit-effector-setup",\n oops}'}])
    setup_line = page.locator(".posekit-message-setup")  # beside the upload box, the export's message gone
    wait_for(lambda: "bad.json, line 2, column 2" in setup_line.inner_text(), 30, "the upload's error message")
    assert message.inner_text() == ""
    assert page.locator(VIEWS).get_by_role("button", name="remove").count() == n_rows


def test_1000_rapid_updates_keep_the_kernel_alive_and_small(page, server):
    choose_solvers(page, ["fabrik", "protores"])
    page.locator(VIEWS).locator(".widget-dropdown", has_text="selected").first.locator("select").select_option("Hand_L")
    kernel = server.note_kernels()[0]
    # the messages the page posts itself: Voila's lab page forwarded every console call to window.top (itself),
    # about 50 per view per update from pythreejs' debug log; the posekit template leaves that out
    page.evaluate("() => { window.__posted = 0; window.addEventListener('message', () => window.__posted++); }")
    result = rapid_updates(page, 1000, kernel)
    lat = result["latency_ms"]
    assert result["updates"] == 1000 and len(lat) >= 990
    assert page.evaluate("() => window.__posted") == 0
    assert result["kernel_alive"] and kernel.is_running()
    growth = result["rss_mb_end"] - result["rss_mb_early"]
    print(f"\nstudio, fabrik + protores: 1,000 updates, latency p50 {np.percentile(lat, 50):.0f} ms, "
          f"p95 {np.percentile(lat, 95):.0f} ms; kernel RSS {result['rss_mb_early']:.0f} -> {result['rss_mb_end']:.0f} MB")
    assert growth < 50, f"the kernel grew by {growth:.0f} MB over 900 updates"
    # still answering
    n0 = update_number(page)
    page.keyboard.press("ArrowRight")
    _wait_update(page, n0, "an update after the 1,000")


def test_keyboard_only_the_list_passes_over_joints_and_ctrl_z_undoes_a_press(page):
    """Issue 65, item 4: with the keyboard alone, arrow keys in the *selected* list pass over joints without adding
    an effector or solving; a press on the selected joint's Y slider moves its target one step, Ctrl+Z (focus in
    the studio) takes it back and Ctrl+Shift+Z does it again; Ctrl+Z pressed while the sliders are drawn again still
    undoes."""
    joints = _joint_list(page)
    joints.select_option("Hand_L")
    kernel_round_trip(page, VIEWS)
    n0, texts = update_number(page), _texts(page)
    joints.focus()
    for key in ("ArrowDown", "ArrowDown", "ArrowDown"):  # over the next joints
        page.keyboard.press(key)
        kernel_round_trip(page, VIEWS)
    assert update_number(page) == n0 and _texts(page) == texts, "passing over joints solved: an effector was added"
    joints.select_option("Hand_L")  # chosen: the sliders are the hand's
    kernel_round_trip(page, VIEWS)
    assert update_number(page) == n0
    y0 = _status_rows(page)["target"][1]
    handle = page.locator(VIEWS).locator(".posekit-target-y .noUi-handle").last
    handle.focus()
    page.keyboard.press("ArrowUp")
    _wait_update(page, n0, "the press's solve")
    wait_for(lambda: abs(_status_rows(page)["target"][1] - (y0 + 0.001)) < 2e-4 or None, 60, "the target one step up")
    n1 = update_number(page)
    page.locator(VIEWS).locator(".posekit-target-y .noUi-handle").last.focus()
    page.keyboard.press("Control+z")
    _wait_update(page, n1, "the undo's solve")
    wait_for(lambda: abs(_status_rows(page)["target"][1] - y0) < 2e-4 or None, 60, "the target back where it was")
    n2 = update_number(page)
    page.locator(VIEWS).locator(".posekit-target-y .noUi-handle").last.focus()
    page.keyboard.press("Control+Shift+z")
    _wait_update(page, n2, "the redo's solve")
    wait_for(lambda: abs(_status_rows(page)["target"][1] - (y0 + 0.001)) < 2e-4 or None, 60, "the step redone")
    # Ctrl+Z while the sliders are drawn again (the focused handle gone from the page, the new one not there yet:
    # on a loaded machine, right after an undo) is still the studio's: the page used to drop it, and the next step's
    # wait above timed out in a CI run
    n3 = update_number(page)
    page.locator(VIEWS).locator(".posekit-target-y .noUi-handle").last.focus()
    page.evaluate(f"""() => {{
        window.__away = [...document.querySelectorAll("{VIEWS} .posekit-target-y .noUi-handle")]
            .map(h => [h, h.parentNode, h.nextSibling]);
        window.__away.forEach(([h]) => h.remove());
    }}""")
    assert page.evaluate("() => document.activeElement === document.body")
    page.keyboard.press("Control+z")
    page.evaluate("() => window.__away.forEach(([h, parent, next]) => parent.insertBefore(h, next))")
    _wait_update(page, n3, "the undo's solve, the key pressed with the sliders away")
    wait_for(lambda: abs(_status_rows(page)["target"][1] - y0) < 2e-4 or None, 60, "the target back again")


@pytest.fixture(scope="module")
def small_page(server, chromium):
    """A fresh studio (a kernel of its own: the set-up the app opens with) in a 1280 x 800 tab."""
    tab = open_studio(chromium, server.url, page=blank_tab(chromium, (1280, 800)))
    try:
        wait_for(lambda: tab.locator(f"{VIEWS} canvas").count() == 4 or None, 120, "four views")
        yield tab
    finally:
        tab.close()


def test_escape_during_a_drag_puts_the_target_back_where_it_started(small_page):
    """Issue 65: press on the selected hand with *drag in 3D* on and drag its target up (the readout follows it);
    Escape with the button still held puts the target back where it was at the press and ends the drag: moving on
    and letting go moves nothing (before, Escape did nothing and the drag went on)."""
    from posekit.viz.drag import DRAG_HELD_CLASS
    from tests.viz.browser_helpers import target_mm

    page = small_page
    scope = page.locator(VIEWS)
    _joint_list(page).select_option("Hand_L")
    start = wait_for(lambda: target_mm(scope, "Hand_L"), 30, "the hand's target in the status table")
    kernel_round_trip(page, VIEWS)
    first = _canvases(page)[0]
    first.scroll_into_view_if_needed()
    toggle = page.locator(VIEWS).get_by_role("button", name="drag in 3D").first
    x, y = press_in_3d(page, first, selected_joint(wait_still(first, 30, "the view to stand still")), VIEWS)
    try:
        wait_for(lambda: DRAG_HELD_CLASS in (toggle.get_attribute("class") or "").split() or None, 30,
                 "the kernel to hold the drag")
        page.mouse.move(x + 10, y - 40, steps=8)
        moved = wait_for(lambda: (lambda t: t if t not in (None, start) else None)(target_mm(scope, "Hand_L")), 30,
                         "the target to follow the drag")
        page.keyboard.press("Escape")
        wait_for(lambda: target_mm(scope, "Hand_L") == start, 30, f"the target back at {start} mm (it was at {moved})")
        wait_for(lambda: DRAG_HELD_CLASS not in (toggle.get_attribute("class") or "").split() or None, 30,
                 "the drag to end")
        page.mouse.move(x + 30, y - 70, steps=6)  # the button still down: the drag has ended, nothing follows
    finally:
        page.mouse.up()
    kernel_round_trip(page, VIEWS)
    assert target_mm(scope, "Hand_L") == start
    drag_in_3d(page, VIEWS, False)


def test_after_compare_the_new_views_are_in_sight(small_page):
    """Issue 65: in a 1280 x 800 window, scroll down to the solver check boxes (the views above, out of sight),
    tick two others and press *compare*: the new views are scrolled into sight, every canvas wholly in the window
    (before, the page stayed where it was, the new views above it)."""
    tab = small_page
    tab.locator(".posekit-compare").scroll_into_view_if_needed()
    tops = [c.bounding_box()["y"] for c in tab.locator(f"{VIEWS} canvas").all()]
    assert max(tops) < 0, f"the views' tops at {tops} px: the test did not scroll them out of sight"
    choose_solvers(tab, ["fabrik", "ccd"])
    canvases = tab.locator(f"{VIEWS} canvas")

    def in_sight():
        boxes = [c.bounding_box() for c in canvases.all()]
        return all(b is not None and b["y"] >= -0.5 and b["y"] + b["height"] <= 800.5 for b in boxes) or None

    try:
        wait_for(in_sight, 10, "the new views in sight")
    except pytest.fail.Exception:
        pytest.fail(f"after compare the views are out of sight: {[c.bounding_box() for c in canvases.all()]}")


def test_voila_shuts_its_kernel_down(page, server):
    """Last in this file: it closes the page and stops the server the tests above share."""
    kernels = server.note_kernels()
    assert kernels and all(k.is_running() for k in kernels)
    page.close()
    alive = server.stop()
    assert alive == [], f"kernels still running after Voila stopped: {alive}"
    assert all(not k.is_running() or k.status() == "zombie" for k in kernels)
