"""What only the page can see, told to the kernel: the mouse button let go anywhere, and the slider handle that had
the keyboard when the kernel replaced it.

Introduced with :class:`~posekit.viz.SkeletonViewer` (``notebooks/00_skeletons_and_poses.ipynb``; dragging in
``notebooks/06_posing_studio.ipynb``); a part of its controls. pythreejs' pickers report mouse events on the canvas
only, and the kernel never sees the keyboard's focus; :class:`PageWatch` is a small `anywidget
<https://anywidget.dev>`_ whose script listens on the page's ``window`` (in JupyterLab and in Voila alike) for one
view — the elements that carry the CSS class :attr:`PageWatch.scope` (its canvas and its controls):

1. **A drag always ends.** Once a press on the canvas has started a drag in 3D (*drag in 3D* on, :attr:`armed`), or
   the kernel says it holds one (:attr:`holding`), the first ``pointerup`` or ``pointercancel`` anywhere — over
   another part of the page, outside the window —, the window losing focus, or a ``pointermove`` with no button down
   (the button let go where the page could not see it) sends the kernel ``{"event": "release"}``: the view's
   :meth:`~posekit.viz.drag.DragTargets._let_go` runs (:meth:`PageWatch.on_release`).
2. **Key presses survive the slider swap.** The kernel puts new X/Y/Z slider models in place of the old ones
   whenever what they show changes (:mod:`posekit.viz.sliders`), and a focused handle that leaves the page drops the
   keyboard's focus to the page's body. The script remembers which axis's handle (``.posekit-target-x`` ...
   ``.noUi-handle``) had focus; when that handle has left the page and nothing else took focus, it focuses the
   newest handle of the same axis as soon as it is shown, and keys pressed in between (arrows, Page Up/Down,
   Home, End) are held back and then given to that handle, in order. A handle with no successor within 5 s (its
   view was closed, not swapped) is forgotten, and the page's keys are the page's again.
   **The page knows which joint a slider belongs to**: each slider carries the CSS class ``posekit-for-<joint>``
   (:mod:`posekit.viz.sliders`, the joint's name URI-encoded). A key pressed on a handle whose joint is not the one
   the view's *selected* list shows now (a joint just chosen: the kernel has not yet made its sliders) is held back
   the same way and given to that joint's handle of the same axis once it is shown, which then has the focus: the
   press leaves for the kernel on the selected joint's own slider, whatever the order in which the list's and the
   sliders' messages reach it (none lost, none on the joint chosen before).

3. **Keys of the view.** Escape while a drag is held sends ``{"event": "cancel"}`` (the drag goes back to where it
   started); Ctrl+Z and Ctrl+Shift+Z (or Ctrl+Y) with the focus inside :attr:`PageWatch.keys_scope` (the studio),
   outside a text box, send ``undo`` and ``redo``; arrow keys in the view's joint list stay in the list (in
   JupyterLab they would also move to the next cell).

A page without the script (a front end without anywidget) still ends a drag with the canvas' ``mouseup`` picker.
"""

from __future__ import annotations

import anywidget
import traitlets

__all__ = ["PageWatch"]

_ESM = r"""
const AXES = ["x", "y", "z"];
// how long keys wait for a replaced handle's successor before the page has them back (a view closed, not swapped)
const GIVE_UP_MS = 5000;
const SLIDER_KEYS = new Set(["ArrowLeft", "ArrowRight", "ArrowUp", "ArrowDown", "PageUp", "PageDown", "Home", "End"]);

// the set a slider belongs to: its box carries posekit-sliders-<n>, n counting up with every set the kernel makes
function generation(handle) {
  const box = handle.closest("[class*='posekit-sliders-']");
  const found = box && box.className.match(/posekit-sliders-(\d+)/);
  return found ? Number(found[1]) : -1;
}

function initialize({ model }) {
  const scope = () => "." + model.get("scope");
  const inScope = (node) => node instanceof Element && node.closest(scope()) !== null;
  const axisOf = (node) => (node instanceof Element && node.classList.contains("noUi-handle") && inScope(node)
    ? AXES.find((a) => node.closest(".posekit-target-" + a)) ?? null : null);

  // 1. a drag always ends: the first release, wherever it happens, once a drag may be held
  let held = false;
  const down = (e) => { if (model.get("armed") && inScope(e.target)) held = true; };
  const end = (e) => {
    if (!held || (e.type === "pointermove" && e.buttons !== 0) || (e.type === "blur" && e.target !== window)) return;
    held = false;
    model.send({ event: "release", why: e.type });
  };
  const holding = () => { if (model.get("holding")) held = true; };  // a drag the press above did not see
  model.on("change:holding", holding);

  // 2. the handle that had the keyboard: its axis, and keys pressed while its successor is not yet shown
  let last = null, lastAxis = null, queued = [];
  // the joint a slider belongs to (its class posekit-for-<joint>), and the joint the view's list shows now
  const jointOf = (handle) => {
    const box = handle instanceof Element ? handle.closest("[class*='posekit-for-']") : null;
    const found = box && [...box.classList].find((c) => c.startsWith("posekit-for-"));
    return found ? decodeURIComponent(found.slice("posekit-for-".length)) : null;
  };
  const listed = () => {
    for (const root of document.querySelectorAll(scope())) {
      for (const d of root.querySelectorAll(".widget-dropdown")) {
        const label = d.querySelector("label"), list = d.querySelector("select");
        if (label && list && label.textContent.trim() === "selected") return list.value;
      }
    }
    return null;
  };
  // a handle of another joint than the list's (a new choice whose sliders the kernel has not made yet)
  const stale = (handle) => {
    if (handle === null || !handle.isConnected) return false;
    const joint = jointOf(handle), chosen = listed();
    return joint !== null && chosen !== null && chosen !== "(none)" && joint !== chosen;
  };
  let staleSince = null;
  let goneAt = null;  // when the remembered handle was first seen gone
  const focusIn = (e) => {
    lastAxis = axisOf(e.target);
    last = lastAxis ? e.target : null;
    queued = [];
    goneAt = staleSince = null;  // a new handle remembered: no wait of an earlier one counts against it
  };
  const lost = () => {
    if (last !== null && stale(last) && document.activeElement === last) {  // its joint is no longer the list's
      staleSince = staleSince ?? performance.now();
      if (performance.now() - staleSince <= GIVE_UP_MS) return true;
      last = null;  // the chosen joint's sliders never came: let the keys be
      queued = [];
      return false;
    }
    staleSince = null;
    if (last === null || last.isConnected) { goneAt = null; return false; }
    goneAt = goneAt ?? performance.now();
    if (performance.now() - goneAt > GIVE_UP_MS) {  // no successor came (the view was closed): let the keys be
      last = null;
      queued = [];
      return false;
    }
    const now = document.activeElement, here = document.querySelector(scope());
    // the focus fell to the body, or to a box around the view (JupyterLab's output area): nothing else took it
    return !now || now === document.body || now === document.documentElement || (here !== null && now.contains(here));
  };
  const newest = () => {  // the newest handle of the axis, of the joint the list shows
    let best = null;
    const chosen = listed();
    for (const h of document.querySelectorAll(`${scope()} .posekit-target-${lastAxis} .noUi-handle`)) {
      const joint = jointOf(h);
      if (joint !== null && chosen !== null && chosen !== "(none)" && joint !== chosen) continue;
      if (best === null || generation(h) > generation(best)) best = h;
    }
    return best;
  };
  const restore = () => {
    if (!lost()) return;
    const handle = newest();
    if (handle === null || handle === last) return;
    const keys = queued;
    handle.focus({ preventScroll: true });  // focusin: the new handle is the one remembered
    last = handle;
    for (const k of keys) {
      handle.dispatchEvent(new KeyboardEvent("keydown", { key: k.key, code: k.code, shiftKey: k.shiftKey,
                                                          bubbles: true, cancelable: true }));
    }
  };
  // 3. keys of the view: Escape cancels a held drag; Ctrl+Z / Ctrl+Shift+Z (Ctrl+Y) undo and redo with the focus
  // anywhere in the keys' scope (the studio), but not in a text box; the joint list's keys stay in the list
  const typing = (node) => node instanceof Element && node.closest("input[type=text], input:not([type]), textarea");
  const inKeysScope = (node) => model.get("keys_scope") !== "" && node instanceof Element
    && node.closest("." + model.get("keys_scope")) !== null;
  const viewKey = (e) => {
    if (e.key === "Escape" && held) {
      e.preventDefault();
      e.stopPropagation();
      held = false;
      model.send({ event: "cancel" });
      return true;
    }
    const z = e.key === "z" || e.key === "Z", y = e.key === "y" || e.key === "Y";
    // a slider that had the focus and is being drawn again (an undo's new sliders not there yet) left it on the
    // page: the key is still the studio's (it was dropped, and a redo right after an undo did nothing)
    if ((e.ctrlKey || e.metaKey) && !e.altKey && (z || y) && (inKeysScope(e.target) || lost()) && !typing(e.target)) {
      e.preventDefault();
      e.stopPropagation();
      model.send({ event: (e.shiftKey || y) ? "redo" : "undo" });
      return true;
    }
    if (SLIDER_KEYS.has(e.key) && e.target instanceof Element && e.target.tagName === "SELECT" && inScope(e.target)) {
      e.stopPropagation();  // the list's arrows are the list's: never the notebook's (JupyterLab's next cell)
      return true;
    }
    return false;
  };
  const key = (e) => {
    if (viewKey(e)) return;
    if (!SLIDER_KEYS.has(e.key) || e.altKey || e.ctrlKey || e.metaKey) return;
    if (axisOf(e.target) !== null && e.target !== last) {  // (a handle focused without a focusin seen)
      last = e.target;
      lastAxis = axisOf(e.target);
    }
    if (!lost()) return;
    e.preventDefault();
    e.stopPropagation();
    queued.push({ key: e.key, code: e.code, shiftKey: e.shiftKey });
    restore();
  };
  const watcher = new MutationObserver(() => { if (last !== null && (!last.isConnected || stale(last))) restore(); });
  watcher.observe(document.body, { childList: true, subtree: true });

  const listeners = [["pointerdown", down, true], ["pointerup", end, true], ["pointercancel", end, true],
                     ["pointermove", end, true], ["blur", end, false], ["focusin", focusIn, true],
                     ["keydown", key, true]];
  for (const [type, fn, capture] of listeners) window.addEventListener(type, fn, capture);
  return () => {
    for (const [type, fn, capture] of listeners) window.removeEventListener(type, fn, capture);
    watcher.disconnect();
    model.off("change:holding", holding);
  };
}

// 4. shown after a change the page asked for (the studio's *compare*): once the page shows the view (this widget is
// rendered with its controls), the view's row is scrolled into sight if it is off the screen
const revealed = new WeakSet();  // the models whose view was scrolled into sight already (once per view)
function render({ model }) {
  if (!model.get("reveal") || revealed.has(model)) return;
  revealed.add(model);
  const started = performance.now();
  const reveal = () => {
    const here = document.querySelector("." + model.get("scope"));
    if (here === null || here.getBoundingClientRect().height === 0) {
      if (performance.now() - started < GIVE_UP_MS) requestAnimationFrame(reveal);
      return;
    }
    const row = here.closest(".posekit-views") ?? here;
    const box = row.getBoundingClientRect();
    if (box.top < 0 || box.top > window.innerHeight - 100) row.scrollIntoView({ block: "start" });
  };
  reveal();
}

export default { initialize, render };
"""


class PageWatch(anywidget.AnyWidget):
    """The page-side watcher of one view (see the module docstring); shows nothing.

    Parameters
    ----------
    scope : str
        The CSS class the view's canvas and controls carry.

    Attributes
    ----------
    armed : bool
        Set by the kernel: *drag in 3D* is on, so a press on the canvas may start a drag.
    holding : bool
        Set by the kernel: it holds a drag (``DragTargets.dragging``).
    keys_scope : str
        A CSS class (the studio's ``posekit-studio``): with the focus inside it, Ctrl+Z and Ctrl+Shift+Z are sent
        as ``undo`` and ``redo`` (:meth:`on_key`); empty: not watched.
    reveal : bool
        Set before the page shows the view: once shown, its row of views (``.posekit-views``, else the view) is
        scrolled into sight if it is off the screen (the studio's new views after *compare*).
    """

    _esm = _ESM
    scope = traitlets.Unicode("").tag(sync=True)
    armed = traitlets.Bool(False).tag(sync=True)
    holding = traitlets.Bool(False).tag(sync=True)
    keys_scope = traitlets.Unicode("").tag(sync=True)
    reveal = traitlets.Bool(False).tag(sync=True)

    def __init__(self, scope: str, **kwargs):
        super().__init__(scope=scope, **kwargs)
        self._release_callbacks = []
        self._key_callbacks = {"cancel": [], "undo": [], "redo": []}
        self.on_msg(self._on_page_message)

    def on_key(self, event: str, callback):
        """Call ``callback()`` when the page says ``event``: ``"cancel"`` (Escape during a held drag), ``"undo"``
        (Ctrl+Z) or ``"redo"`` (Ctrl+Shift+Z, Ctrl+Y) with the focus inside :attr:`keys_scope`."""
        self._key_callbacks[event].append(callback)

    def on_release(self, callback):
        """Call ``callback()`` whenever the page says the mouse button was let go (or the window lost focus) after a
        press that may have started a drag."""
        self._release_callbacks.append(callback)

    def _on_page_message(self, _, content, buffers):
        event = content.get("event") if isinstance(content, dict) else None
        if event == "release":
            for callback in self._release_callbacks:
                callback()
        for callback in self._key_callbacks.get(event, ()):
            callback()
