"""What the headless-Chromium tests share: canvas pixels, the viewer's background, waiting for a condition."""

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
