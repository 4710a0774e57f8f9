"""One picture of several views: each view's own pixels side by side, its title above and its status text below, as
the page shows them.

Introduced with the posing studio's *views as PNG* export (:mod:`posekit.viz.studio_export`,
``notebooks/06_posing_studio.ipynb``); the pictures come from the page (:mod:`posekit.viz.canvas_capture`).
"""

from __future__ import annotations

import io

import numpy as np

__all__ = ["compose_views", "PAD", "TITLE_SIZE", "LABEL_SIZE"]

PAD = 8
"""Pixels around and between the views."""
TITLE_SIZE, LABEL_SIZE = 15, 13
"""Font sizes (pixels) of a view's title and of its status lines."""


def _font(size: int, bold: bool = False):
    """DejaVu Sans (shipped with matplotlib: it has the ✓ ✗ ◐ of the status lines) at ``size`` pixels."""
    from matplotlib import font_manager
    from PIL import ImageFont

    path = font_manager.findfont(font_manager.FontProperties(family="DejaVu Sans",
                                                             weight="bold" if bold else "normal"))
    return ImageFont.truetype(path, size)


def _picture(png):
    from PIL import Image

    if png is None:
        return None
    if isinstance(png, (bytes, bytearray)):
        return Image.open(io.BytesIO(png)).convert("RGB")
    if isinstance(png, np.ndarray):
        return Image.fromarray(np.asarray(png, dtype=np.uint8)).convert("RGB")
    return png.convert("RGB")


def compose_views(pictures, titles, labels, background=(255, 255, 255)):
    """Lay the views' pictures out in one row, each with its title above and its status lines below.

    Parameters
    ----------
    pictures : list of bytes, ndarray (H, W, 3) uint8 or PIL.Image
        Each view's pixels (PNG bytes as ``canvas.toDataURL()`` gives them); None for a view with no picture (its
        place stays blank, its title and label still drawn).
    titles : list of str
        Each view's title (the solver's name).
    labels : list of str
        Each view's status text as its view shows it (lines separated by newlines; a table row's cells by tabs).

    Returns
    -------
    image : PIL.Image.Image
        RGB.
    boxes : list of tuple
        Where each view's picture lies in ``image``: ``(x, y, width, height)``, pixels.
    """
    from PIL import Image, ImageDraw

    if not len(pictures) == len(titles) == len(labels):
        raise ValueError(f"{len(pictures)} pictures, {len(titles)} titles and {len(labels)} labels: one of each per view")
    pics = [_picture(p) for p in pictures]
    title_font, label_font = _font(TITLE_SIZE, bold=True), _font(LABEL_SIZE)
    lines = [[" ".join(c for c in line.split("\t") if c.strip()) for line in str(t).splitlines() if line.strip()]
             for t in labels]
    widths = []
    for p, title, ls in zip(pics, titles, lines):
        texts = [title_font.getlength(str(title))] + [label_font.getlength(s) for s in ls]
        widths.append(int(max([p.width if p is not None else 200, *texts])) + 1)
    title_h, line_h = TITLE_SIZE + 8, LABEL_SIZE + 5
    pic_h = max([p.height for p in pics if p is not None] or [200])
    height = PAD + title_h + pic_h + PAD + line_h * max([len(ls) for ls in lines] or [0]) + PAD
    width = PAD + sum(w + PAD for w in widths)
    image = Image.new("RGB", (width, height), background)
    draw = ImageDraw.Draw(image)
    x, boxes = PAD, []
    for p, title, ls, w in zip(pics, titles, lines, widths):
        draw.text((x, PAD), str(title), fill=(20, 20, 20), font=title_font)
        y = PAD + title_h
        if p is not None:
            image.paste(p, (x, y))
            boxes.append((x, y, p.width, p.height))
        else:
            boxes.append((x, y, 0, 0))
        for k, s in enumerate(ls):
            draw.text((x, y + pic_h + PAD + k * line_h), s, fill=(40, 40, 40), font=label_font)
        x += w + PAD
    return image, boxes
