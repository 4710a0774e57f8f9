"""The posing studio's messages and busy sign: each message on the line of the controls that caused it, one at a
time, and a busy sign drawn by CSS (:class:`~posekit.viz.studio.PosingStudio`, lesson 06)."""

from __future__ import annotations

__all__ = ["BUSY_SIGN", "WRAP", "StudioMessages"]

BUSY_SIGN = ("<style>@keyframes posekit-spin {to {transform: rotate(360deg)}}</style>"
             "<span style='display:inline-block;width:10px;height:10px;margin-right:6px;vertical-align:-1px;"
             "border:2px solid #b9770e;border-top-color:transparent;border-radius:50%;"
             "animation:posekit-spin 0.9s linear infinite'></span>")
"""A spinning ring drawn by CSS alone: it shows in any browser, whatever fonts it has (an emoji sign showed as an
empty box where no emoji font is installed)."""

WRAP = {"flex_flow": "row wrap", "align_items": "center"}
"""A row of controls that wraps onto the next line when the page is narrow (JupyterLab with its sidebar open)."""


class StudioMessages:
    """The studio's messages, each on the line of the controls that caused it (``row``: ``"solvers"``,
    ``"setup"``, ``"export"``, ``"timeline"``). Setting :attr:`value` writes the current row's line and clears the
    others: one message at a time, next to its control, gone at the next action that succeeds."""

    ROWS = ("solvers", "setup", "export", "timeline")

    def __init__(self):
        import ipywidgets as w

        from .shared import widget

        self.lines = {r: widget(w.HTML, layout={"margin": "0 0 0 8px"}) for r in self.ROWS}
        for r, line in self.lines.items():
            line.add_class("posekit-message")
            line.add_class(f"posekit-message-{r}")
        self.row = "setup"

    @property
    def value(self) -> str:
        """The current row's message (HTML)."""
        return self.lines[self.row].value

    @value.setter
    def value(self, text: str):
        for r, line in self.lines.items():
            if r != self.row and line.value:
                line.value = ""
        self.lines[self.row].value = text
