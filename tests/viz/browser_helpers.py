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
