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
    """Switch *drag in 3D* on and press the mouse at pixel ``at`` (x, y) of ``canvas``; returns that point in the
    page's coordinates (the mouse stays down).

    Between the switch and the press it pauses as a person does: the kernel turns orbiting off in the page in
    reply to the switch, and a press before that reply orbits the camera instead (a full CI run, the other core
    busy with notebooks, lost that race twice in one run)."""
    toggle = page.locator(views).get_by_role("button", name="drag in 3D")
    toggle.click()
    wait_for(lambda: "mod-active" in (toggle.get_attribute("class") or ""), 10, "the drag-in-3D switch to show on")
    page.wait_for_timeout(2000)
    box = canvas.bounding_box()
    x, y = box["x"] + at[0], box["y"] + at[1]
    page.mouse.move(x, y)
    page.mouse.down()
    return x, y


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
  const sent = window.__posekit_sent = [];
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
        if (msg.header.msg_type === 'comm_msg' && body.method === 'update') sent.push(Object.keys(body.state));
      } catch (err) { sent.push(['unreadable', String(err)]); }
      return send(data);
    };
    return socket;
  };
  window.WebSocket.prototype = Socket.prototype;
  Object.assign(window.WebSocket, Socket);
})();"""
"""An init script for a page (``page.add_init_script``): ``window.__posekit_sent`` lists every state update the
page sends its kernel (the trait names; ``["open", model]`` for a model the page creates)."""
