"""The posing studio on its own page: what ``make studio`` serves (``notebooks/studio.ipynb``, one cell).

Introduced in ``notebooks/06_posing_studio.ipynb``, which builds the same :class:`~posekit.viz.studio.PosingStudio`
on the same held-out case step by step (:func:`studio_case` is its first cell's set-up). The app adds only the
choice of data and solvers from the environment, so ``make studio STUDIO_DATA=my_clips/ STUDIO_WEIGHTS=my_weights/``
poses a user's own skeleton with the models they trained (README, "Your own mocap, end to end"):

* ``POSEKIT_STUDIO_DATA`` — a data set name or a BVH folder (:func:`posekit.data.open_dataset`; default the Bandai
  mini set);
* ``POSEKIT_STUDIO_SOLVERS`` — 2-4 registered solver names shown first (default :data:`SOLVERS`);
* ``POSEKIT_WEIGHTS_DIR`` — a folder of the user's checkpoints (:func:`posekit.paths.weights_path`);
* ``POSEKIT_STUDIO_LICENCE`` — the licence of the user's data, shown as given in the page's data line
  (:func:`data_line`).

:func:`app_page` is the page's one cell: the data line, then the studio, or a sentence saying what is wrong with
the data, weights or solver choice (never a traceback on the server's console only).

A learned solver whose weights were made for another skeleton is left out of the choice, with its reason. Each
page keeps its files (setups, uploads, exports) in a folder of its own (:func:`session_folder`; its *setup file* box
takes a file name there and nothing outside), so the students of a class served by one ``make studio`` never read
or overwrite each other's files, nor any other file of the server. The
data set is let go once the app's case is built and its memory handed back, so a kernel of the app holds the
studio, not the data; the page Voila serves is :data:`VOILA_TEMPLATE`, which asks nothing of the internet.
"""

from __future__ import annotations

import os
import secrets
import time
from pathlib import Path

from ..paths import EXPORTS as _EXPORTS, exports_dir

__all__ = ["SOLVERS", "STUDIO_POOL", "VOILA_PATH", "VOILA_TEMPLATE", "EXPORTS", "studio_case", "usable_solvers",
           "session_folder", "app_studio", "refused_note", "app_page", "data_line", "kept_label"]

STUDIO_POOL = 3
"""Kernels ``make studio`` keeps preheated (Voila's pool: each has already run the page, so a visitor's first view
waits for no kernel to start): sized for a class arriving at once, a small group at a time. Each costs its memory
while it waits, about 0.25 GB (``posekit bench studio --sessions``: a kernel's RSS, docs/studio.md), so the default
holds about 0.75 GB; ``make studio STUDIO_POOL=N`` sizes it for N (e.g. the class's size). ``posekit bench studio
--visitors 3`` measures every visitor's first view with three at once."""

COMPACT_HEADER = (
    ".jp-MarkdownCell h1 { font-size: 18px; line-height: 22px; margin: 0 0 2px 0 !important; padding: 0; }"
    ".jp-MarkdownCell .jp-RenderedMarkdown p { font-size: 11px; line-height: 14px; margin: 0; }"
    ".jp-MarkdownCell .jp-RenderedMarkdown p code { line-height: 14px; vertical-align: top; }"
    ".posekit-data-line { font-size: 11px; line-height: 14px; margin: 0 0 6px 0 !important; }"
    ".jp-MarkdownCell .jp-RenderedMarkdown { padding-top: 0; padding-bottom: 0; }"
    ".jp-Cell { padding-top: 2px; padding-bottom: 2px; }")
"""The app page's rules for its header (the notebook's title and paragraph, about 185 px at full size): small, so the
views, the *selected* list, the X/Y/Z sliders and the readout lie on the first screen of a 1280 x 800 or a
1366 x 768 display when the page opens. Sizes and line heights in whole pixels: the views below then lie on whole
pixels (a fractional offset blurs a screenshot of a canvas by half a pixel)."""

VOILA_PATH = Path(__file__).parent / "voila"
"""A Jupyter data folder (for ``JUPYTER_PATH``) holding the studio's Voila page template, :data:`VOILA_TEMPLATE`."""
VOILA_TEMPLATE = "posekit"
"""Voila's lab page without the two stylesheets it fetches from a CDN (Font Awesome's, which Voila's own scripts
already carry): the page asks nothing of the internet, so a room whose network drops such requests does not wait
for them (a stylesheet in the page's head holds the page back until its request gives up). Nor does it forward
every console call to ``window.top`` (for JupyterLab's Voila preview): on its own page that posted each of
pythreejs's debug lines, about 50 per view per update, to the page itself."""

SOLVERS = ("fabrik", "dls", "protores+dls", "latent-opt+dls")
"""Lesson 06's first four: two classical solvers and the two learned ones with an exact finish."""

EXPORTS = _EXPORTS
"""Where the app's pages write, relative to the notebook's folder: one folder per page, :func:`session_folder`
(``$POSEKIT_EXPORTS_DIR`` moves it: :func:`posekit.paths.exports_dir`)."""


def session_folder(root=None) -> Path:
    """The folder one page of the app writes into: ``root/session-<date>-<time>-<6 hex digits>``, named by the
    moment its kernel built the studio and a random part (two pages built in the same second never share one).
    ``root`` defaults to :func:`posekit.paths.exports_dir` (:data:`EXPORTS` beside the notebook).

    Every page Voila serves runs its own kernel in the same working folder. With one folder for all, a student's
    *save* overwrote another's ``setup.json`` and *load* read whoever saved last, and an upload replaced any file
    of the same name, a broken one included. Nothing is created until the page writes a file."""
    root = exports_dir() if root is None else Path(root)
    return root / f"session-{time.strftime('%Y%m%d-%H%M%S')}-{secrets.token_hex(3)}"


def studio_case(motions, case: int = 3, cases: int = 20, seed: int = 0):
    """Lesson 06's set-up: held-out case ``case`` of :func:`posekit.data.cases.build_cases` (``cases`` of them,
    same-clip start) — the start pose, the target pose's joint positions (the ghost, (J, 3) metres), five
    position effectors where the target pose has the hands, feet and head, and lesson 05's tolerance slider
    mapping (Lambda -> metres or radians)."""
    from ..data.cases import build_cases
    from ..ik import effector_set
    from ..models.protores.tolerance import tolerance_to_sigma  # numpy only: no torch for classical solvers

    built = build_cases(motions, cases, seed=seed, start="same-clip")
    if not 0 <= case < len(built.target_pos):
        raise ValueError(f"case {case}: the data gave {len(built.target_pos)} held-out cases")
    goal = built.target_pos[case]
    effectors = effector_set(motions.skeleton, "5", goal)
    return built.pose(case), goal, effectors, lambda lam, kind: max(tolerance_to_sigma(lam), 1e-4)


def usable_solvers(skeleton, data: str, names=None):
    """The registered solvers that can pose ``skeleton``: classical ones always; a learned one when its
    weights were made for ``data`` (:attr:`SolverInfo.data`), else only if it builds (the user's own weights
    for this skeleton). Returns ``(usable, refused)``: a list of names and {name: reason}."""
    from ..ik import make_solver, solver_info, solver_names

    usable, refused = [], {}
    for name in names or solver_names():
        made_for = solver_info(name).data
        if not made_for or made_for == data:
            usable.append(name)
            continue
        try:
            make_solver(name, skeleton)
            usable.append(name)
        except ValueError as err:
            refused[name] = str(err).split("\n")[0]
    return usable, refused


def app_studio(data: str | None = None, solvers=None, export_dir=None):
    """The studio ``make studio`` shows: :func:`studio_case` of ``data`` (default ``$POSEKIT_STUDIO_DATA`` or the
    Bandai mini set), the first 2-4 usable of ``solvers`` (default ``$POSEKIT_STUDIO_SOLVERS`` or
    :data:`SOLVERS`; FABRIK and DLS when fewer than two are usable), the target pose as a ghost, the left hand
    selected; its files go to ``export_dir`` (default a new :func:`session_folder`). Returns the
    :class:`~posekit.viz.studio.PosingStudio` and the solvers left out, {name: reason}."""
    from .studio import PosingStudio

    data = data or os.environ.get("POSEKIT_STUDIO_DATA") or "bandai-mini"
    if solvers is None:
        solvers = os.environ.get("POSEKIT_STUDIO_SOLVERS") or ",".join(SOLVERS)
    if isinstance(solvers, str):
        solvers = [s.strip() for s in solvers.split(",") if s.strip()]
    weights = os.environ.get("POSEKIT_WEIGHTS_DIR")
    if weights:  # a missing folder, or one without checkpoints, is said before any work (not silently the shipped)
        from ..paths import use_weights

        try:
            with use_weights(weights):
                pass
        except (FileNotFoundError, ValueError) as e:
            raise FileNotFoundError(str(e).replace("--weights", "STUDIO_WEIGHTS", 1)) from None
    skeleton, (start, goal, effectors, tolerance_of), (available, refused) = _app_case(data)
    _return_freed_memory()
    unknown = [s for s in solvers if s not in available and s not in refused]
    if unknown:
        raise ValueError(f"POSEKIT_STUDIO_SOLVERS: unknown solver(s) {', '.join(map(repr, unknown))}; "
                         f"registered: {', '.join(available + list(refused))}")
    first = [s for s in solvers if s in available][:4]
    if len(first) < 2:
        first = ["fabrik", "dls"]
    studio = PosingStudio(skeleton, start, first, effectors, available=available,
                          tolerance_of=tolerance_of, own_folder=True,
                          export_dir=session_folder() if export_dir is None else export_dir,
                          selected=skeleton.names[skeleton.index(effectors[0].joint)])
    for v in studio.editor.viewers.values():
        v.set_ghost(goal)
    return studio, refused


def _app_case(data: str):
    """What the app keeps of the data set ``data``: its skeleton, :func:`studio_case` and :func:`usable_solvers`.
    The data set itself (the Bandai mini set: 41,391 frames, about 50 MB of arrays) is let go when this returns,
    and :func:`_return_freed_memory` hands the memory back, so a kernel of the app does not keep it."""
    from ..data.sources import open_dataset

    motions = open_dataset(data)
    return motions.skeleton, studio_case(motions), usable_solvers(motions.skeleton, data)


def _return_freed_memory() -> None:
    """Give the memory Python has freed back to the system (glibc's ``malloc_trim``; a no-op where the C library has
    none). glibc keeps freed heap pages for later allocations, so a kernel that has read a data set and let it go
    still counts it in its resident memory: about 35 MB of the studio's, measured here."""
    import ctypes
    import gc

    gc.collect()
    try:
        ctypes.CDLL(None).malloc_trim(0)  # the process's own symbols: glibc's, where there is glibc
    except (OSError, AttributeError):  # not glibc: its allocator decides
        pass


def refused_note(refused: dict) -> str:
    """One line naming the solvers left out and the first reason (empty when none)."""
    if not refused:
        return ""
    name, why = next(iter(refused.items()))
    other = all("trained for skeleton" in r or "trained for other skeleton" in r for r in refused.values())
    what = "made for another skeleton" if other else "they refused this data or their weights"
    return f"left out ({what}): {', '.join(refused)} — e.g. {name}: {why}"


def data_line(data: str | None = None) -> str:
    """The page's line on whose data it poses: the Bandai mini set and its licence by default, else the user's data
    (``$POSEKIT_STUDIO_DATA``) with the licence they gave (``$POSEKIT_STUDIO_LICENCE``), or just "your data"."""
    data = data or os.environ.get("POSEKIT_STUDIO_DATA") or "bandai-mini"
    weights = os.environ.get("POSEKIT_WEIGHTS_DIR")
    models = f"; models: yours, from {weights}" if weights else ""
    if data == "bandai-mini":
        return "Data: Bandai mini set (Bandai Namco Research Inc.), CC BY-NC 4.0" + models
    if data in ("sample", "deepmimic"):
        return "Data: the DeepMimic humanoid sample shipped with posekit (licence: data_samples/README.md)" + models
    licence = (os.environ.get("POSEKIT_STUDIO_LICENCE") or "").strip()
    return f"Data: your data, {data}" + (f" (licence: {licence})" if licence else "") + models


def app_page():
    """What ``notebooks/studio.ipynb`` shows: :func:`data_line`, then :func:`app_studio` with the solvers it left
    out (:func:`refused_note`); when the data, the weights or the solver choice is wrong, that sentence on the page
    instead of the studio (Voila shows only "error when executing cell" for an exception, and the sentence would be
    on the server's console only). Displays them; returns the studio, or None when it could not start."""
    import html

    from IPython.display import HTML, display

    # the page's header (the notebook's title and its paragraph) compact, so that the views, the selected list, the
    # X/Y/Z sliders and the readout are on the first screen on arrival at 1280 x 800 and 1366 x 768
    display(HTML(f"<style>{COMPACT_HEADER}</style><div class='posekit-data-line'>{html.escape(data_line())}</div>"))
    try:
        studio, refused = app_studio()
    except (ValueError, OSError) as e:  # bad input: a missing path, a broken file, an unknown solver name
        display(HTML(
            "<p style='color:#a00'><b>The studio could not start.</b> " + html.escape(str(e)) + "</p>"
            "<p><small>Check STUDIO_DATA (a data set name, a BVH file or folder, or a .npz), STUDIO_WEIGHTS (a folder "
            "of checkpoints from <code>posekit train</code>) and STUDIO_SOLVERS (2-4 registered solver names) of "
            "<code>make studio</code>, then reload this page.</small></p>"))
        return None
    note = refused_note(refused)
    if note:
        display(HTML(f"<small>{html.escape(note)}</small>"))
    display(studio)
    display(kept_label(studio.editor))
    return studio


def kept_label(editor):
    """A line under the studio that counts, per learned solver with an exact finish (``+dls``), how often its finish
    kept the answer from the learned pose since the page opened — in the rest, DLS from the start pose gave the more
    natural answer, or the only exact one, and the learned pose was discarded (a finish without training poses of
    the skeleton, ``choose == "learned"``, is said to have made no naturalness comparison; :mod:`posekit.ik.finish`,
    ``info["kept"] == "start"``). Updated after every solve; an
    ``ipywidgets.HTML`` (``.counts``: {solver: [kept, solves]})."""
    import html

    from ipywidgets import HTML

    from .shared import widget

    label = widget(HTML)
    label.counts = {}

    session = getattr(editor, "session", editor)  # the editor's session (or anything with results and solvers)

    def count():
        if not getattr(session, "effectors", [None]):  # nothing was solved: nothing to count
            return
        for name, res in session.results.items():
            info = getattr(res, "info", None) or {}
            if "learned_ms" not in info:  # not an exact finish (or the solver refused)
                continue
            kept, total = label.counts.setdefault(name, [0, 0])
            label.counts[name] = [kept + (info.get("kept") != "start"), total + 1]
        parts = [f"{n} kept the learned pose in {k} of {t} solves" for n, (k, t) in label.counts.items()]
        unjudged = [n for n in label.counts if getattr(session.solvers.get(n), "choose", "natural") != "natural"]
        why = ("the more natural answer" if not unjudged else "the answer kept (" + ", ".join(unjudged)
               + ": no naturalness comparison, no training poses of this skeleton)")
        label.value = ("<small>Exact finish: " + html.escape("; ".join(parts) + f" (in the others DLS from the "
                       f"start pose gave {why}: the learned pose was discarded)") + "</small>") if parts else ""

    count()
    # the session's changes, which outlive the editor a solver change replaces; a selection solves nothing
    session.on_change(lambda what, _=None: what != "select" and count())
    return label
