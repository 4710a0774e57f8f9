"""The studio's *views as PNG* without a browser (issue 57, item 4): the composition of the views' own pictures, and
the export's round trip through the page-side widget with the page's answer played by the test
(``tests/viz/test_one_screen_browser.py`` runs it in a real page)."""

from __future__ import annotations

import base64
import io

import numpy as np
import pytest
from PIL import Image

from posekit.viz.canvas_capture import CanvasCapture, decode_data_url
from posekit.viz.views_picture import PAD, compose_views


def _png(array) -> bytes:
    out = io.BytesIO()
    Image.fromarray(np.asarray(array, dtype=np.uint8)).save(out, format="PNG")
    return out.getvalue()


def _views():
    rng = np.random.default_rng(0)
    return [rng.integers(0, 256, (120, 100, 3)), rng.integers(0, 256, (90, 80, 3)), np.full((120, 100, 3), 200)]


def test_compose_puts_each_views_own_pixels_in_one_row_with_its_title_and_status():
    views = _views()
    image, boxes = compose_views([_png(views[0]), views[1], Image.fromarray(views[2].astype(np.uint8))],
                                 ["fabrik", "dls", "protores+dls"],
                                 ["✓ reached\nworst effector\t0.1 mm (Head)\ntime\t0.92 ms", "✗ not reached", ""])
    a = np.asarray(image).astype(int)
    assert image.mode == "RGB" and len(boxes) == 3
    for (x, y, w, h), v in zip(boxes, views):
        assert (w, h) == v.shape[1::-1]
        np.testing.assert_array_equal(a[y:y + h, x:x + w], v)  # the pixels themselves, unscaled
    xs = [b[0] for b in boxes]
    assert xs[0] == PAD and xs == sorted(xs) and all(b[1] == boxes[0][1] for b in boxes)  # one row
    for x, y, w, h in boxes:  # a title above each picture, dark text on white
        assert (a[PAD:y, x:x + 60] < 100).all(-1).any(), "no title above a view"
    x, y, w, h = boxes[0]
    below = a[y + max(b[3] for b in boxes):, x:x + w]
    assert (below < 100).all(-1).sum() > 50, "the first view's status lines are missing"
    x, y, w, h = boxes[2]
    assert not (a[y + h:, x:x + w] < 100).all(-1).any(), "an empty status drew something"


def test_compose_refuses_mismatched_lists_and_leaves_a_missing_picture_blank():
    with pytest.raises(ValueError, match="one of each per view"):
        compose_views([None], ["a", "b"], ["", ""])
    image, boxes = compose_views([None, _png(_views()[0])], ["a", "b"], ["x", "y"])
    assert boxes[0][2:] == (0, 0) and boxes[1][2:] == (100, 120)


def test_decode_data_url():
    raw = _png(np.zeros((2, 2, 3)))
    assert decode_data_url("data:image/png;base64," + base64.b64encode(raw).decode()) == raw
    with pytest.raises(ValueError, match="not a base64 data URL"):
        decode_data_url("http://example.org/x.png")


def test_the_studio_writes_the_pictures_the_page_sends(tmp_path, skel):
    """The button's route: the studio asks its page-side widget, the page answers (played here), the PNG holds the
    views' pictures; without a page the kernel draws the poses itself, and says so."""
    from posekit.ik.api import Pose
    from posekit.viz import PosingStudio

    start = Pose.from_rotations(skel, np.tile([1.0, 0, 0, 0], (skel.n_joints, 1)), np.zeros(3))
    studio = PosingStudio(skel, start, ["fabrik", "dls"], export_dir=tmp_path)
    sent = []
    studio.views_capture.send = lambda content, buffers=None: sent.append(content)
    path = studio.export_png(from_page=True)  # no page has drawn the widget: the kernel's drawing
    assert not sent and path.exists() and "drawn by the kernel" in studio.message.value
    path.unlink()
    studio.views_capture.shown = 1  # a page shows the studio
    path = studio.export_png(tmp_path / "v.png", from_page=True)
    assert sent and sent[0]["type"] == "capture" and not path.exists()
    assert "reading the 2 views from the page" in studio.message.value
    views = _views()[:2]
    answer = {"type": "captured", "id": sent[0]["id"],
              "views": [{"image": "data:image/png;base64," + base64.b64encode(_png(v)).decode(), "title": n,
                         "label": f"✓ reached\ntime\t0.{k}1 ms", "shown": [v.shape[1], v.shape[0]]}
                        for k, (n, v) in enumerate(zip(["fabrik", "dls"], views))]}
    studio.views_capture._on_msg(studio.views_capture, answer, [])
    assert path.exists() and "the 2 views as the page shows them" in studio.message.value
    with Image.open(path) as im:
        a = np.asarray(im.convert("RGB")).astype(int)
    _, boxes = compose_views([_png(v) for v in views], ["fabrik", "dls"], ["✓ reached\ntime 0.01 ms"] * 2)
    for (x, y, w, h), v in zip(boxes, views):
        np.testing.assert_array_equal(a[y:y + h, x:x + w], v)
    studio.views_capture._on_msg(studio.views_capture, answer, [])  # a second page's answer: ignored
    assert isinstance(studio.views_capture, CanvasCapture)
