"""The X/Y/Z target sliders of a :class:`~posekit.viz.SkeletonViewer`: each press moves the selected joint's handle
by its own steps, and nothing else, whatever the timing.

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``; a part of :class:`~posekit.viz.SkeletonViewer` (it
inherits :class:`TargetSliders`). The sliders show the selected joint's *handle* (:meth:`TargetSliders._handle`):
its target, or its look-at target when it has only that or when the *sliders move* choice says so, or the
joint itself when it has neither (a move then creates a target). They step 1 mm within
:attr:`TargetSliders.SLIDER_SPAN` of the handle; a slider pushed to an end re-centres on its new value, so any
point can be reached.

**Race-free by construction.** The kernel never changes a slider the browser shows: whenever the sliders must show
something new (a new selection, a handle moved by a drag, by code or by undo, a re-centring) it makes three *new*
slider models and puts them in place of the old ones. So every value a slider model sends comes from the browser's
own history of that one model, which starts at the value the kernel created it with; the kernel reads each value
as a number of steps from the model's previous value (a press: one step), on the axis of that slider, and applies
it to the handle of the joint selected *now* — the selection the kernel has already processed, the browser's
messages arriving in order. A press on a slider the browser had not yet replaced after a new selection thus moves
the new joint by one step, never to the old joint's value; a value the browser sends back unchanged (its snap to
the step grid) is zero steps and moves nothing. The last :attr:`TargetSliders.KEEP_OLD` replaced sets stay open
for presses still on their way; older ones are closed. The page keeps the keyboard across the swap: when the
handle that had the focus is replaced, its view's :class:`~posekit.viz.page_watch.PageWatch` gives the focus to the
new handle of the same axis, and keys pressed in between to it (before, the focus fell to the page's body and those
presses went nowhere). Each slider carries the joint it belongs to (the CSS class ``posekit-for-<joint>``), so the
page also holds back a press on a handle of the joint chosen before and gives it to the newly chosen joint's handle
once the kernel has made it: such a press leaves on the selected joint's own slider. Units: metres, world frame
(:mod:`posekit.conventions`).
"""

from __future__ import annotations

from urllib.parse import quote

import numpy as np

from .shared import widget

__all__ = ["TargetSliders"]


class TargetSliders:
    """The slider half of :class:`~posekit.viz.SkeletonViewer` (see the module docstring).

    Expects of the viewer: ``selected``, ``targets``, ``look_targets``, ``pose``, ``skeleton``, ``move_target``,
    ``move_look_target``, ``dragging``.

    Attributes
    ----------
    sliders : list of ipywidgets.FloatSlider
        The current X, Y and Z sliders (CSS classes ``posekit-target-x`` ...); new models after every change the
        kernel makes to what they show.
    slider_box : ipywidgets.VBox
        Holds the current sliders.
    slider_generation : int
        How many slider sets have been made (each carries the CSS class ``posekit-sliders-<n>``).
    handle_choice : ipywidgets.ToggleButtons
        *sliders move*: ``"target"`` or ``"look_at"``, shown for a joint that has both.
    """

    SLIDER_STEP = 0.001
    """Target slider resolution, metres."""
    SLIDER_SPAN = 0.5
    """The X/Y/Z sliders reach this far (metres) either side of the selected joint's target (a slider
    pushed to an end re-centres on its new value)."""
    KEEP_OLD = 8
    """Replaced slider sets kept open: a press on one of them still moves the selected joint by its steps."""

    def _init_sliders(self):
        import ipywidgets as w

        self._browser_value = {}  # slider model id -> (axis, the value the browser last held for it)
        self._old_sliders = []  # replaced sets, oldest first
        self._shown = None  # (joint, handle kind) the current sliders were made for; None: disabled
        self._sliders_due = False  # a change to show once the drag ends
        self.slider_generation = 0
        self.slider_box = widget(w.VBox, [])
        self.sliders = []
        self._make_sliders(None)
        # a layout of its own (shown for a joint with both handles), a shared style
        self.handle_choice = widget(w.ToggleButtons, options=[("target", "target"), ("look-at", "look_at")],
                                    value="target", description="sliders move", style={"button_width": "70px"},
                                    layout=w.Layout(display="none"))
        self.handle_choice.observe(lambda ch: self._sync_sliders(recentre=True), names="value")

    def settle(self):
        """Close the replaced slider sets at once, for a view that no browser has shown yet (an editor or a studio
        just built, :class:`~posekit.viz.EffectorEditor`): no press can be on its way from them."""
        for old in self._old_sliders if self._controls_made else ():
            for s in old:
                self._browser_value.pop(s.model_id, None)
                s.close()
        if self._controls_made:
            self._old_sliders = []

    def _show_handle_choice(self):
        if not self._controls_made:  # a view whose controls are not made yet: they show the handle when they are
            return
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

    def _make_sliders(self, point):
        """Put three new slider models in place of the current ones: centred on ``point`` (3,), or disabled and
        showing no number when it is None. The replaced ones stay open for :attr:`KEEP_OLD` sets."""
        import ipywidgets as w

        step = self.SLIDER_STEP
        self.slider_generation += 1
        new = []
        for axis, a in enumerate("xyz"):
            if point is None:
                lo, hi, value = -step, step, 0.0
            else:  # the value and the limits on the step grid: the browser's snap to it moves nothing
                value = float(np.round(point[axis] / step) * step)
                lo = float(np.floor((point[axis] - self.SLIDER_SPAN) / step) * step)
                hi = float(np.ceil((point[axis] + self.SLIDER_SPAN) / step) * step)
            s = widget(w.FloatSlider, value=value, min=lo, max=hi, step=step, description=f"target {a}",
                       continuous_update=True, readout_format=".3f", disabled=point is None,
                       readout=point is not None, layout={"width": "480px"})
            s.add_class(f"posekit-target-{a}")
            s.add_class(f"posekit-sliders-{self.slider_generation}")
            if point is not None:  # the joint it belongs to, for the page (posekit.viz.page_watch)
                s.add_class(f"posekit-for-{quote(self.selected, safe='')}")
            self._browser_value[s.model_id] = (axis, value)
            s.observe(self._on_slider, names="value")
            new.append(s)
        if self.sliders:
            self._old_sliders.append(self.sliders)
        while len(self._old_sliders) > self.KEEP_OLD:
            for s in self._old_sliders.pop(0):
                self._browser_value.pop(s.model_id, None)
                s.close()
        self.sliders = new
        self.slider_box.children = tuple(new)

    def _sync_sliders(self, recentre: bool = False):
        """Show the selected joint's handle (:meth:`_handle`) on the sliders: new slider models when the joint,
        the handle or its point changed otherwise than by these sliders (or ``recentre``); during a drag in 3D,
        once the mouse is released. With no selection the sliders are disabled and show no number."""
        if not self._controls_made:
            return
        self._show_handle_choice()
        if self.selected is None:
            if self._shown is not None:
                self._shown = None
                self._make_sliders(None)
            return
        kind, p = self._handle()
        if getattr(self, "dragging", None) is not None and not recentre:
            self._sliders_due = True  # a drag moves the handle many times a second: shown when it ends
            return
        self._sliders_due = False
        tol = 0.5 * self.SLIDER_STEP + 1e-9
        held = [self._browser_value.get(s.model_id, (0, np.nan))[1] for s in self.sliders]
        if (recentre or self._shown != (self.selected, kind)
                or not all(abs(h - v) <= tol for h, v in zip(held, p))):
            self._shown = (self.selected, kind)
            self._make_sliders(np.asarray(p, float))

    def _on_slider(self, change):
        """A slider model's value changed in the browser: the steps from its previous value move the selected
        joint's handle along that slider's axis (the other coordinates stay the handle's)."""
        s = change["owner"]
        known = self._browser_value.get(s.model_id)
        if known is None:  # closed: too old
            return
        axis, before = known
        v = float(change["new"])
        self._browser_value[s.model_id] = (axis, v)
        steps = int(np.round((v - before) / self.SLIDER_STEP))
        if steps == 0 or self.selected is None:
            return
        kind, p = self._handle()
        p = np.array(p, dtype=float)
        p[axis] += steps * self.SLIDER_STEP
        if kind == "look_at":
            self.move_look_target(self.selected, p)
        else:
            self.move_target(self.selected, p)
        tol = 0.5 * self.SLIDER_STEP + 1e-9
        if s in self.sliders and (v <= s.min + tol or v >= s.max - tol):  # at an end: re-centre
            self._sync_sliders(recentre=True)
