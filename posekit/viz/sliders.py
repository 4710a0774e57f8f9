"""The X/Y/Z target sliders of a :class:`~posekit.viz.SkeletonViewer`: what they move, and never moving on a selection.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``; a part of :class:`~posekit.viz.SkeletonViewer` (it
inherits :class:`TargetSliders`). The sliders show the selected joint's *handle* (:meth:`TargetSliders._handle`):
its target, or its look-at target when it has only that or when the *sliders move* choice says so, or the
joint itself when it has neither (a move then creates a target). They step 1 mm within
:attr:`TargetSliders.SLIDER_SPAN` of the handle; a slider pushed to an end re-centres on its new value, so any
point can be reached.

Selecting never moves anything. A new selection gives every slider a new range; the kernel sends each slider's
range and value in one message, and for :attr:`TargetSliders.ECHO_S` seconds after a new range a value the
browser sends back that the slider held in the last seconds before that range (clamped into the new range, so
possibly an end of it) is an echo, not a move; values the user moved it to since are moves: under load the browser can send back a value from two selections ago. A real move changes its
own axis of the handle only. Units: metres, world frame (:mod:`posekit.conventions`).
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["TargetSliders"]


class TargetSliders:
    """The slider half of :class:`~posekit.viz.SkeletonViewer` (see the module docstring).

    Expects of the viewer: ``selected``, ``targets``, ``look_targets``, ``pose``, ``skeleton``, ``move_target``,
    ``move_look_target``.

    Attributes
    ----------
    sliders : list of ipywidgets.FloatSlider
        X, Y and Z (CSS classes ``posekit-target-x`` ...).
    handle_choice : ipywidgets.ToggleButtons
        *sliders move*: ``"target"`` or ``"look_at"``, shown for a joint that has both.
    """

    SLIDER_STEP = 0.001
    """Target slider resolution, metres."""
    SLIDER_SPAN = 0.5
    """The X/Y/Z sliders reach this far (metres) either side of the selected joint's target (a slider
    pushed to an end re-centres on its new value)."""
    ECHO_S = 2.0
    """For this many seconds after the kernel gives a slider a new range, the browser sending back a value the
    slider held in the last ``ECHO_S`` seconds (set by the kernel or sent by the browser; clamped into the new
    range, so possibly an end of it) is an echo, not a move (the browser re-sends a slider's value when its
    range changes, sometimes after the next selection has already begun)."""

    def _init_sliders(self):
        import ipywidgets as w

        self._syncing = False
        self._held_values = [[], [], []]  # per slider: (time, value) it held lately, what the browser may send back
        self._ranges = [[], [], []]  # per slider: (time, min, max) of its ranges lately, the last one newest
        step = self.SLIDER_STEP
        self.sliders = [w.FloatSlider(value=0.0, min=-step, max=step, step=step, description=f"target {a}",
                                      continuous_update=True, readout_format=".3f", disabled=True, readout=False,
                                      layout=w.Layout(width="480px"))
                        for a in "xyz"]
        self._synced = None
        for a, s in zip("xyz", self.sliders):
            s.add_class(f"posekit-target-{a}")
            s.observe(self._on_slider, names="value")
        self.handle_choice = w.ToggleButtons(options=[("target", "target"), ("look-at", "look_at")], value="target",
                                             description="sliders move", style={"button_width": "70px"},
                                             layout=w.Layout(display="none"))
        self.handle_choice.observe(lambda ch: self._sync_sliders(recentre=True), names="value")

    def _show_handle_choice(self):
        both = self.selected is not None and self.selected in self.targets and self.selected in self.look_targets
        self.handle_choice.layout.display = None if both else "none"

    def _handle(self):
        """What the sliders move for the selected joint: ``("look_at", point)`` for its look-at target (when it
        has only that, or when it has both and the choice says so), else ``("target", point)`` — its target,
        or the joint itself when it has none yet."""
        name = self.selected
        has_look, has_target = name in self.look_targets, name in self.targets
        if has_look and (not has_target or self.handle_choice.value == "look_at"):
            return "look_at", self.look_targets[name]
        return "target", self.targets.get(name, self.pose[self.skeleton.index(name)])

    def _sync_sliders(self, recentre: bool = False):
        """Show the selected joint's handle (:meth:`_handle`) on the sliders, within ``SLIDER_SPAN`` of it (the
        range moves with a new selection, or when the point leaves it); with no selection the sliders are
        disabled and show no number. Each slider's range and value go to the browser in one message; after a
        new range, values the browser sends back that the slider held lately are echoes for ``ECHO_S`` seconds."""
        active = self.selected is not None
        for s in self.sliders:
            s.disabled, s.readout = not active, active
        self._show_handle_choice()
        if not active:
            self._synced = None
            return
        _, p = self._handle()
        step = self.SLIDER_STEP
        now = time.monotonic()
        self._syncing = True
        try:
            for axis, (s, v) in enumerate(zip(self.sliders, p)):
                before = (s.min, s.max, s.value)
                with s.hold_sync():
                    if recentre or not (s.min <= v <= s.max):
                        # limits on the step grid, so that the browser's snapping to it does not move a value
                        lo = float(np.floor((v - self.SLIDER_SPAN) / step) * step)
                        hi = float(np.ceil((v + self.SLIDER_SPAN) / step) * step)
                        if lo > s.max:
                            s.max, s.min = hi, lo
                        else:
                            s.min, s.max = lo, hi
                    s.value = float(np.clip(v, s.min, s.max))
                self._remember(axis, before[2], now)
                if (s.min, s.max) != before[:2]:  # a new range: the browser may send back a stale value
                    self._ranges[axis] = [r for r in self._ranges[axis] if now - r[0] < self.ECHO_S]
                    self._ranges[axis] += [(now, *before[:2]), (now, s.min, s.max)]
        finally:
            self._syncing = False
        self._synced = np.array([s.value for s in self.sliders])

    def _remember(self, axis, value, now):
        """Note that slider ``axis`` held ``value`` at ``now`` (only the last ``ECHO_S`` seconds are kept)."""
        self._held_values[axis] = [(t, x) for t, x in self._held_values[axis] if now - t < self.ECHO_S]
        self._held_values[axis].append((now, float(value)))

    def _is_echo(self, axis, v, tol, now) -> bool:
        """Whether ``v``, sent by the browser for slider ``axis``, is a stale value and not a move: within
        ``ECHO_S`` of a new range, a value the slider held lately (up to that range: not a value the user moved
        it to since), or an end of a recent range, as the browser may have clamped it into any recent range (the
        browser can lag a selection behind)."""
        recent = [(t, lo, hi) for t, lo, hi in self._ranges[axis] if now - t < self.ECHO_S]
        if not recent:
            return False
        ranges, newest = [(lo, hi) for _, lo, hi in recent], max(t for t, _, _ in recent)
        # only values held up to the newest range: the user's own moves since then are never echoes
        held = [x for t, x in self._held_values[axis] if now - t < self.ECHO_S and t <= newest]
        held += [end for r in ranges for end in r]
        s = self.sliders[axis]
        stale = {float(np.clip(np.clip(x, lo, hi), s.min, s.max)) for x in held for lo, hi in ranges}
        return any(abs(v - x) <= tol for x in stale)

    def _on_slider(self, change):
        """A slider moved in the browser: move the handle along that axis only (the other coordinates stay the
        handle's), unless the value is one the kernel set (an echo, or the browser's snap to the step grid)."""
        if self._syncing or self.selected is None:
            return
        axis = self.sliders.index(change["owner"])
        v, tol = float(change["new"]), 0.5 * self.SLIDER_STEP + 1e-9
        kind, p = self._handle()
        if abs(v - p[axis]) <= tol or (self._synced is not None and abs(v - self._synced[axis]) <= tol):
            return
        now = time.monotonic()
        if self._is_echo(axis, v, tol, now):  # a stale value sent back: put the slider back where the handle is
            self._sync_sliders()
            return
        p = np.array(p, dtype=float)
        p[axis] = v
        if kind == "look_at":
            self.move_look_target(self.selected, p)
        else:
            self.move_target(self.selected, p)
        s = change["owner"]
        if v <= s.min + tol or v >= s.max - tol:  # at an end: re-centre, so the next push goes further
            self._sync_sliders(recentre=True)
