"""Progress bars that end finished, also in a stored notebook.

``tqdm.auto`` in Jupyter draws a widget; the notebook file keeps only the text it showed when it was first
displayed (``0%|          | 0/21``), so a stored lesson shows every bar frozen at the start. :func:`tqdm`
here is ``tqdm.auto.tqdm`` everywhere else; in a Jupyter kernel it displays the bar with a display id and,
when the bar closes, updates that display, so the stored output is the finished bar. A loop that stops
early on purpose (a time budget, early stopping) calls :func:`finish` before closing: the total becomes
the count done, so the bar ends full and green rather than red at "460/9000". Used by the library's long
loops (training, benchmarks).

Outside a terminal (a log file, a pipe, CI) a redrawn bar is one endless line of carriage returns, or nothing at
all; there the bar is a line of text every :data:`LOG_SECONDS` seconds (also while one step takes longer), one
when it starts and one when it ends, so a long ``posekit train`` in a log is never silent for minutes.
"""

from __future__ import annotations

import sys
import threading
import time

__all__ = ["tqdm", "finish", "LOG_SECONDS"]

LOG_SECONDS = 5.0
"""Seconds between two progress lines when the output is not a terminal."""


def _log_class():
    from tqdm.std import tqdm as std

    class LogBar(std):
        """A bar written as whole lines: at the start, every :data:`LOG_SECONDS` seconds, and at the end."""

        def __init__(self, *a, **kw):
            kw.setdefault("mininterval", LOG_SECONDS)
            kw.setdefault("file", sys.stderr)
            self._written, self._text, self._write_lock, self._stop = 0.0, None, threading.Lock(), threading.Event()
            super().__init__(*a, **kw)
            if not self.disable:
                threading.Thread(target=self._beat, daemon=True).start()

        def _beat(self):
            while not self._stop.wait(LOG_SECONDS / 5):
                if time.time() - self._written >= LOG_SECONDS and not self.disable:
                    self.display()

        def display(self, msg=None, pos=None):
            if self.disable:
                return True
            with self._write_lock:
                text = str(self) if msg is None else msg
                if text == self._text:  # the same line again (the last step, then the close)
                    return True
                self._written, self._text = time.time(), text
                try:
                    self.fp.write(text + "\n")
                    self.fp.flush()
                except (ValueError, OSError):  # the stream was closed under us
                    self._stop.set()
            return True

        def close(self):
            if self.disable:
                return
            self._stop.set()
            self.display()
            self.sp = None  # the base class then writes nothing more
            super().close()

    return LogBar


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def _notebook_class():
    """The widget bar class when ``tqdm.auto`` would draw widgets here (a Jupyter kernel with ipywidgets)."""
    from tqdm.auto import tqdm as auto

    try:
        from tqdm.notebook import tqdm_notebook
    except ImportError:  # pragma: no cover - tqdm without its notebook module
        return None
    return tqdm_notebook if issubclass(auto, tqdm_notebook) else None


def tqdm(*args, **kwargs):
    """``tqdm.auto.tqdm(*args, **kwargs)``; in Jupyter, a widget bar whose stored output ends finished; when the
    output is not a terminal, a line every :data:`LOG_SECONDS` seconds."""
    base = _notebook_class()
    if base is None or kwargs.get("disable"):
        if not kwargs.get("disable") and not _is_terminal(kwargs.get("file") or sys.stderr):
            return _log_class()(*args, **kwargs)  # a log or a pipe: lines every few seconds
        from tqdm.auto import tqdm as auto

        return auto(*args, **kwargs)

    class FinishingBar(base):
        def __init__(self, *a, **kw):
            kw["display"] = False
            super().__init__(*a, **kw)
            from IPython.display import display

            self._handle = display(self.container, display_id=True)
            self.displayed = True

        def close(self):
            was_open = not self.disable
            super().close()
            if was_open and self._handle is not None:
                self._handle.update(self.container)     # the stored output: the bar as it ends
                self._handle = None

    return FinishingBar(*args, **kwargs)


def finish(bar) -> None:
    """End ``bar`` at what ran, for a loop stopped on purpose before its total (a time budget, early
    stopping): its total becomes its count, so it closes full instead of as a failure. No-op for ``None``."""
    if bar is None or getattr(bar, "disable", False) or not bar.n:
        return
    if bar.total is None or bar.n < bar.total:
        bar.total = bar.n
        container = getattr(bar, "container", None)
        if container is not None:
            container.children[1].max = bar.n
        bar.refresh()
