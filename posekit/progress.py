"""Progress bars that end finished, also in a stored notebook.

``tqdm.auto`` in Jupyter draws a widget; the notebook file keeps only the text it showed when it was first
displayed (``0%|          | 0/21``), so a stored lesson shows every bar frozen at the start. :func:`tqdm`
here is ``tqdm.auto.tqdm`` everywhere else; in a Jupyter kernel it displays the bar with a display id and,
when the bar closes, updates that display, so the stored output is the finished bar. A loop that stops
early on purpose (a time budget, early stopping) calls :func:`finish` before closing: the total becomes
the count done, so the bar ends full and green rather than red at "460/9000". Used by the library's long
loops (training, benchmarks).
"""

from __future__ import annotations

__all__ = ["tqdm", "finish"]


def _notebook_class():
    """The widget bar class when ``tqdm.auto`` would draw widgets here (a Jupyter kernel with ipywidgets)."""
    from tqdm.auto import tqdm as auto

    try:
        from tqdm.notebook import tqdm_notebook
    except ImportError:  # pragma: no cover - tqdm without its notebook module
        return None
    return tqdm_notebook if issubclass(auto, tqdm_notebook) else None


def tqdm(*args, **kwargs):
    """``tqdm.auto.tqdm(*args, **kwargs)``; in Jupyter, a widget bar whose stored output ends finished."""
    base = _notebook_class()
    if base is None or kwargs.get("disable"):
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
