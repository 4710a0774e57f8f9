"""What the headless-Chromium tests share: canvas pixels, the viewer's background, waiting for a condition, the
selected joint's marker and a press in a view with *drag in 3D* on."""

from __future__ import annotations

import io
import time

import numpy as np
import pytest

BACKGROUND = np.array([0xF7, 0xF7, 0xF2])
"""The viewer's background colour (``SkeletonViewer(background="#f7f7f2")``)."""


def pixels(locator):
    """A screenshot of one element as an (H, W, 3) int array."""
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(locator.screenshot())).convert("RGB")).astype(int)


def foreground(img):
    """Pixels that are not the viewer's background."""
    return np.abs(img - BACKGROUND).sum(-1) > 60


def selected_joint(img):
    """Pixel (x, y) in the middle of the selected joint's yellow marker (drawn larger) in a canvas image; the test
    fails when the marker is not there."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    ys, xs = np.nonzero((r > 180) & (g > 120) & (g < 215) & (b < 90))
    assert len(xs) > 3, "the selected joint's yellow marker is not on the canvas"
    return float(np.median(xs)), float(np.median(ys))


def press_in_3d(page, canvas, at, views=".posekit-views"):
    """Switch *drag in 3D* on (:func:`drag_in_3d`) and press the mouse at pixel ``at`` (x, y) of ``canvas``;
    returns that point in the page's coordinates (the mouse stays down)."""
    drag_in_3d(page, views, True)
    box = canvas.bounding_box()
    x, y = box["x"] + at[0], box["y"] + at[1]
    page.mouse.move(x, y)
    page.mouse.down()
    return x, y


def drag_in_3d(page, views=".posekit-views", on=True):
    """Set the first *drag in 3D* switch in ``views`` (a selector or a locator) to ``on``, clicking it only when it
    is not, and wait until the kernel reports the switch done: it marks the switch with
    ``posekit.viz.drag.DRAG_ON_CLASS`` after it has turned orbiting off, and takes the mark off after turning it on.
    A press before that reply orbits the camera instead of grabbing a joint (a full CI run, the other core busy with
    notebooks, lost that race twice in one run); waiting for the reply, not a pause, holds however slow the kernel
    is."""
    from posekit.viz.drag import DRAG_ON_CLASS

    scope = page.locator(views) if isinstance(views, str) else views
    toggle = scope.get_by_role("button", name="drag in 3D").first

    def state():
        classes = (toggle.get_attribute("class") or "").split()
        return "mod-active" in classes, DRAG_ON_CLASS in classes

    if state()[0] != on:
        toggle.click()
    wait_for(lambda: state() == (on, on), 30, f"the kernel to switch drag in 3D {'on' if on else 'off'}")


def kernel_round_trip(page, views=".posekit-views"):
    """Wait until the kernel has handled everything the page sent it before, and the page has drawn every reply:
    switch the first view's *drag in 3D* on and off again, each time waiting for the kernel's mark
    (:func:`drag_in_3d`). A page sends its kernel messages in order and the kernel answers in order, so once the
    second mark is gone, an echo the page sent earlier (a slider snapping to a new range) has been handled and any
    solve it caused has reached the page. Tests that check that something did *not* happen wait for this, not for
    a pause."""
    drag_in_3d(page, views, True)
    drag_in_3d(page, views, False)


def wait_still(locator, timeout, what):
    """Wait until an element's picture stands still (two screenshots in a row alike) and return it."""
    last = [pixels(locator)]

    def still():
        now = pixels(locator)
        same = (np.abs(now - last[0]).sum(-1) > 60).mean() < 0.0005
        last[0] = now
        return now if same else None

    return wait_for(still, timeout, what)


def wait_for(pred, timeout, what, every: float = 0.5):
    """Poll ``pred()`` until it returns something other than None or False; fail the test after ``timeout`` s."""
    t0 = time.time()
    while time.time() - t0 < timeout:
        value = pred()
        if value is not None and value is not False:
            return value
        time.sleep(every)
    pytest.fail(f"timed out after {timeout} s waiting for {what}")


SENT_LOG = r"""(() => {
  // every state update the page sends its kernel, in order: the names of the traits it reports
  const sent = window.__posekit_sent = [], switches = window.__posekit_switches = [];
  const decode = (data) => {
    if (typeof data === 'string') return JSON.parse(data);
    // the kernel websocket protocol v1: a count, offsets, then channel, header, parent, metadata, content
    const view = new DataView(data), n = Number(view.getBigUint64(0, true)), offsets = [];
    for (let i = 1; i <= n; i++) offsets.push(Number(view.getBigUint64(8 * i, true)));
    const part = (i) => new TextDecoder().decode(
      new Uint8Array(data, offsets[i], (offsets[i + 1] || data.byteLength) - offsets[i]));
    return {header: JSON.parse(part(1)), content: JSON.parse(part(4))};
  };
  const Socket = window.WebSocket;
  window.WebSocket = function (...args) {
    const socket = new Socket(...args), send = socket.send.bind(socket);
    socket.send = (data) => {
      try {
        const msg = decode(data), body = msg.content.data || {};
        // (the widget manager's own control channel opens without a model)
        if (msg.header.msg_type === 'comm_open' && body.state) sent.push(['open', body.state._model_name]);
        if (msg.header.msg_type === 'comm_msg' && body.method === 'update') {
          const keys = Object.keys(body.state);
          // a switch's value (a toggle button: true or false) is kept apart: kernel_round_trip sends two
          if (keys.length === 1 && typeof body.state.value === 'boolean') switches.push(body.state.value);
          else sent.push(keys);
        }
      } catch (err) { sent.push(['unreadable', String(err)]); }
      return send(data);
    };
    return socket;
  };
  window.WebSocket.prototype = Socket.prototype;
  Object.assign(window.WebSocket, Socket);
})();"""
"""An init script for a page (``page.add_init_script``): ``window.__posekit_sent`` lists every state update the
page sends its kernel (the trait names; ``["open", model]`` for a model the page creates), but a switch's new value
(true or false), which goes to ``window.__posekit_switches``."""


_SELECT_ON_PRESS = """(scope, joint) => {
  // the next key press first chooses `joint` in the view's *selected* list (a capturing listener runs before the
  // slider's own), so the press leaves for the kernel right behind the selection, on the slider still shown
  window.__press = null;
  const focused = document.activeElement;
  document.addEventListener('keydown', () => {
    const list = [...scope.querySelectorAll('.widget-dropdown')]
      .find(d => d.textContent.includes('selected')).querySelector('select');
    list.value = joint;
    list.dispatchEvent(new Event('change', {bubbles: true}));  // the list's view sends the selection now
    window.__press = {selected_at: performance.now(), on_old: focused.isConnected && focused.classList.contains('noUi-handle')};
  }, {capture: true, once: true});
  // on the slider, after its own handler (listeners of one element run in the order they were added): the press
  // has been applied when this runs
  focused.addEventListener('keydown', () => { window.__press.pressed_at = performance.now(); }, {once: true});
}"""


def status_rows(scope):
    """A view's status table under its sliders (the first in ``scope``): row label -> (x, y, z) in metres; the
    first row is the selected joint."""
    from playwright.sync_api import Page

    page = scope if isinstance(scope, Page) else scope.page
    table = scope.locator(".widget-html-content", has=page.locator("th", has_text="x m")).first
    rows = {}
    for tr in table.locator("tr").all()[1:]:
        label = tr.locator("th").inner_text().strip()
        rows[label] = tuple(float(t) for t in tr.locator("td").all_inner_texts()[:3])
    return rows


def target_mm(scope, joint):
    """``joint``'s target as the status table shows it, in whole millimetres, once it is selected (else None)."""
    rows = status_rows(scope)
    if joint not in rows or "target" not in rows:
        return None
    return tuple(int(round(1000 * c)) for c in rows["target"])


def press_five(page, scope, joint, expected) -> float:
    """Press ArrowRight five times on the focused X handle, wait for ``joint``'s target to settle (+5 mm when every
    press landed) and return how far its x moved, mm; ``expected[joint]`` becomes the new target."""
    for _ in range(5):
        page.keyboard.press("ArrowRight")
        time.sleep(0.03)
    goal = (expected[joint][0] + 5, *expected[joint][1:])
    try:
        wait_for(lambda: target_mm(scope, joint) == goal, 15, f"{joint}'s target +5 mm", every=0.2)
    except pytest.fail.Exception:
        pass
    now = wait_for(lambda: target_mm(scope, joint), 30, f"{joint}'s target")
    moved = now[0] - expected[joint][0]
    expected[joint] = now
    return moved


def presses_right_after_selections(page, scope, joints, presses: int = 20):
    """Issue 44's race, in the view whose *selected* list and Y slider are in ``scope`` (a locator): ``presses``
    times, choose the next of ``joints`` (each with a target) and press ArrowRight on the Y slider in the same turn
    of the page's event loop (the press right behind the selection, on the slider still shown), while a second
    process keeps a core busy. Every press must move the joint chosen last up by exactly one step (1 mm) and no
    other target may move; the test fails at the first that does not. Returns ``(gaps_ms, on_old)``: each press's
    time after its selection, and how many went to the previous joint's slider."""
    import subprocess
    import sys

    joints_list = scope.locator(".widget-dropdown", has_text="selected").first.locator("select")
    where = {}
    for j in joints:  # each joint's target, read from the page
        joints_list.select_option(j)
        where[j] = wait_for(lambda j=j: target_mm(scope, j), 30, f"{j}'s target in the status table")
    expected, gaps, on_old = dict(where), [], 0
    root = scope.element_handle()
    busy = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        for i in range(presses):
            joint = joints[i % len(joints)]
            scope.locator(".posekit-target-y .noUi-handle").first.focus()
            page.evaluate("([scope, joint]) => (" + _SELECT_ON_PRESS + ")(scope, joint)", [root, joint])
            page.keyboard.press("ArrowRight")
            press = wait_for(lambda: page.evaluate("() => window.__press?.pressed_at && window.__press"), 10,
                             "the key press")
            gaps.append(press["pressed_at"] - press["selected_at"])
            on_old += bool(press["on_old"])
            x, y, z = expected[joint]
            expected[joint] = (x, y + 1, z)
            shown = []

            def moved():
                shown[:] = [status_rows(scope)]
                return target_mm(scope, joint) == expected[joint]

            try:
                wait_for(moved, 30, "the target to move", every=0.2)
            except pytest.fail.Exception:
                pytest.fail(f"press {i + 1}: {joint}'s target did not move up one step, to {expected[joint]} mm; the "
                            f"view's table shows {shown}")
    finally:
        busy.kill()
        busy.wait()
    for j in joints:  # every target moved by its own presses only
        joints_list.select_option(j)
        wait_for(lambda j=j: target_mm(scope, j) == expected[j], 30, f"{j}'s target at {expected[j]} mm")
    counts = [sum(1 for i in range(presses) if joints[i % len(joints)] == j) for j in joints]
    assert [expected[j][1] - where[j][1] for j in joints] == counts
    return gaps, on_old
