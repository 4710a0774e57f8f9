"""Reading the views' own pixels from the page: a tiny page-side widget (``anywidget``, an inline ES module) that,
when the kernel asks, reads every view's WebGL canvas of the widget it sits in and sends the pictures back.

Introduced with the posing studio's *views as PNG* export (:mod:`posekit.viz.studio_export`,
``notebooks/06_posing_studio.ipynb``). pythreejs makes its renderers with ``preserveDrawingBuffer``, so a view's
canvas still holds the frame it shows and ``canvas.toDataURL()`` reads exactly that (a frozen view shows a picture
of its last frame instead: its ``src`` is read). With each picture go the view's title and its status text as the
page shows them (``innerText``) and the size the canvas is shown at.

The kernel cannot wait for the answer inside a cell or a button's handler (the answer is a message the kernel reads
after the handler returns): :meth:`CanvasCapture.capture` takes a callback, called with the pictures when they come.
"""

from __future__ import annotations

import base64
import itertools

import anywidget
import traitlets

__all__ = ["CanvasCapture", "decode_data_url"]

_ESM = r"""
function read(box, msg) {
  const canvas = box.querySelector('canvas'), frozen = box.querySelector(msg.canvas + ' img');
  const text = (sel) => { const e = box.querySelector(sel); return e ? e.innerText.trim() : ''; };
  const shown = (canvas || frozen || box).getBoundingClientRect();
  return {image: canvas ? canvas.toDataURL('image/png') : (frozen ? frozen.src : null),
          title: text(msg.title), label: text(msg.label), shown: [shown.width, shown.height]};
}
function render({model, el}) {
  el.style.display = 'none';
  model.set('shown', model.get('shown') + 1);
  model.save_changes();
  model.on('msg:custom', (msg) => {
    if (msg.type !== 'capture') return;
    const root = el.closest(msg.scope);
    if (!root || !root.isConnected) return;  // another view of this model, not on the page any more
    const views = [...root.querySelectorAll(msg.views)].filter(b => b.offsetParent !== null);
    model.send({type: 'captured', id: msg.id, views: views.map(b => read(b, msg))});
  });
}
export default { render };
"""


def decode_data_url(url: str) -> bytes:
    """The bytes of a ``data:...;base64,`` URL (what ``canvas.toDataURL()`` gives)."""
    head, _, data = url.partition(",")
    if not head.startswith("data:") or ";base64" not in head:
        raise ValueError(f"not a base64 data URL: {url[:40]!r}")
    return base64.b64decode(data)


class CanvasCapture(anywidget.AnyWidget):
    """Put it inside the widget whose views it reads (it shows nothing); :meth:`capture` asks the page.

    Parameters
    ----------
    scope : str
        CSS selector of the ancestor to search (default ``.posekit-studio``).
    views : str
        CSS selector of each view's box inside it (its canvas, title and status), in order.

    Attributes
    ----------
    shown : int
        How many times a page has drawn this widget (0: no page shows it, nothing can be read).
    """

    _esm = _ESM
    shown = traitlets.Int(0).tag(sync=True)

    def __init__(self, scope: str = ".posekit-studio", views: str = ".posekit-view", **kwargs):
        super().__init__(**kwargs)
        self.scope, self.views = scope, views
        self._ids = itertools.count(1)
        self._waiting = {}  # request id -> callback
        self.on_msg(self._on_msg)

    def capture(self, callback) -> int:
        """Ask the page for every view's picture; ``callback(views)`` gets a list of dicts — ``png`` (bytes, the
        canvas's own pixels), ``title``, ``label`` (the view's status text as shown), ``shown`` (width, height in
        CSS pixels) — once the page answers (the first answer, when several pages show the widget). Returns the
        request's id."""
        rid = next(self._ids)
        self._waiting[rid] = callback
        self.send({"type": "capture", "id": rid, "scope": self.scope, "views": self.views,
                   "canvas": ".posekit-canvas", "title": ".posekit-view-title .widget-html-content",
                   "label": ".posekit-view-label .widget-html-content"})
        return rid

    def _on_msg(self, _widget, content, buffers):
        if not isinstance(content, dict) or content.get("type") != "captured":
            return
        callback = self._waiting.pop(content.get("id"), None)
        if callback is None:
            return
        views = []
        for v in content.get("views", []):
            png = decode_data_url(v["image"]) if v.get("image") else None
            views.append({"png": png, "title": v.get("title", ""), "label": v.get("label", ""),
                          "shown": tuple(v.get("shown", (0, 0)))})
        callback(views)
