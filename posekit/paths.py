"""The one place that knows where data lives (no walking up parent folders).

* :func:`samples_dir` — the embedded default data and shipped weights, ``data_samples/`` at the top
  of the posekit checkout (override with ``$POSEKIT_SAMPLES_DIR``).
* :func:`weights_path` — where a weight file lives: ``data_samples/weights/`` unless a folder is given, or a
  weights folder of the user's own is in use (:func:`use_weights`, ``$POSEKIT_WEIGHTS_DIR``, ``--weights DIR``
  of ``posekit bench ik`` and ``bench all``, ``make studio STUDIO_WEIGHTS=DIR``) and holds that file.
* :func:`shared_data_dir` — larger real mocap read by path, never copied: ``$POSEKIT_DATA_DIR``
  (the Makefile points it at ``../shared/data`` when that folder exists).
* :func:`notebooks_dir` — the lessons, ``notebooks/`` of the checkout.
* :func:`exports_dir` — where the posing studio writes its files (setups, BVH, PNG) when no folder is given:
  ``studio_exports/`` in the working folder, beside the notebook (override with ``$POSEKIT_EXPORTS_DIR``; the
  tests point it at a temporary folder, so a test run never writes into a student's ``notebooks/studio_exports/``).
* :func:`course_assets_dir` — reveal.js and MathJax for the slides and the course page, installed by
  ``make course-assets`` (npm) into ``tools/course/node_modules`` (override with ``$POSEKIT_COURSE_ASSETS``).
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

__all__ = ["samples_dir", "weights_path", "find_checkpoint", "checkpoint_identity", "weights_note",
           "held_checkpoints", "use_skeleton", "user_weights_dir",
           "use_weights", "shared_data_dir", "require_shared_data",
           "notebooks_dir", "EXPORTS", "exports_dir", "course_assets_dir"]

_USER_WEIGHTS: list[Path] = []
_USER_SKELETON: list[tuple] = []

_CHECKOUT = Path(__file__).resolve().parent.parent


def samples_dir() -> Path:
    """Folder holding the shipped samples and weights."""
    env = os.environ.get("POSEKIT_SAMPLES_DIR")
    return Path(env) if env else _CHECKOUT / "data_samples"


IDENTITY_FIELDS = ("kind", "config.arch", "config.structured", "extra.method")
"""What a checkpoint says it is: its ``kind`` (the trainer's model: ``ae_solvers``, ``aegan``, ``protores``,
``invrig_nn``) and the fields that tell one trainer's models apart (ProtoRes's ``arch``, the AE-GAN's
``structured`` latent, the inverse-rig network's supersampling ``method``)."""

_HEADERS: dict = {}


def _header(path: Path):
    """``(identity, joint names)`` of a checkpoint (cached per file and modification time); None when the file is
    not a posekit checkpoint."""
    try:
        st = path.stat()
    except OSError:
        return None
    key = (str(path), st.st_mtime_ns, st.st_size)
    if key not in _HEADERS:
        from .io.torch_file import read_torch_file

        try:
            d = read_torch_file(path)
        except Exception:  # noqa: BLE001 - not a checkpoint posekit can read: not a candidate
            d = None
        if not isinstance(d, dict) or d.get("format") != "posekit-checkpoint":
            _HEADERS[key] = None
        else:
            def field(name):
                value = d
                for part in name.split("."):
                    value = value.get(part) if isinstance(value, dict) else None
                return value

            skel = d.get("skeleton") or {}
            _HEADERS[key] = (tuple(field(n) for n in IDENTITY_FIELDS), tuple(skel.get("names") or ()))
    return _HEADERS[key]


def checkpoint_identity(path):
    """What the checkpoint at ``path`` says it is (its :data:`IDENTITY_FIELDS` values), or None when the file is
    missing or not a posekit checkpoint."""
    h = _header(Path(path))
    return None if h is None else h[0]


def _describe(identity) -> str:
    parts = [str(identity[0])] + [f"{n.split('.')[-1]} {v}" for n, v in zip(IDENTITY_FIELDS[1:], identity[1:])
                                  if v is not None]
    return parts[0] + (f" ({', '.join(parts[1:])})" if len(parts) > 1 else "")


def find_checkpoint(file: str, folder) -> Path | None:
    """The checkpoint in ``folder`` that is the model the shipped ``file`` is: the same :data:`IDENTITY_FIELDS`
    (trainer and variant), whatever its file name; among several, the one made for the skeleton of
    :func:`use_skeleton` when one is in use, else the one named ``file``. None when the folder holds none.

    Raises
    ------
    ValueError
        Several checkpoints of that model and nothing to choose between them, naming them.
    """
    shipped = _header(samples_dir() / "weights" / file)
    folder = Path(folder)
    if shipped is None:  # not a shipped model: by name, as before
        return folder / file if (folder / file).is_file() else None
    found = [p for p in sorted(folder.glob("*.pt")) if (_header(p) or (None,))[0] == shipped[0]]
    if _USER_SKELETON and len(found) > 1:
        fits = [p for p in found if _header(p)[1] == _USER_SKELETON[-1]]
        found = fits or found
    if len(found) > 1:
        named = [p for p in found if p.name == file]
        if named:
            return named[0]
        raise ValueError(f"{folder}: {len(found)} checkpoints are {_describe(shipped[0])} models "
                         f"({', '.join(p.name for p in found[:4])}{', ...' if len(found) > 4 else ''}) and none is "
                         f"named {file}; keep one of them in the folder, or name the one to use {file}")
    return found[0] if found else None


def weights_note(file: str) -> str:
    """What :func:`weights_path` looked for in the user's weights folder, in words (for an error): empty when no
    folder is in use or it holds the model."""
    mine = user_weights_dir()
    shipped = _header(samples_dir() / "weights" / file)
    if mine is None or shipped is None or not mine.is_dir():
        return ""
    try:
        if find_checkpoint(file, mine) is not None:
            return ""
    except ValueError as e:
        return str(e)
    held = [f"{p.name} ({_describe(_header(p)[0]) if _header(p) else 'not a posekit checkpoint'})"
            for p in sorted(mine.glob("*.pt"))]
    return (f"{mine} holds no {_describe(shipped[0])} checkpoint (it holds {', '.join(held[:5]) or 'no .pt file'}"
            f"{', ...' if len(held) > 5 else ''}), so the shipped {file} was used")


def held_checkpoints() -> str:
    """What the user's weights folder in use holds, in words (``"DIR holds a.pt (ae_solvers), ..."``); empty
    when none is in use."""
    mine = user_weights_dir()
    if mine is None or not mine.is_dir():
        return ""
    held = [f"{p.name} ({_describe(_header(p)[0]) if _header(p) else 'not a posekit checkpoint'})"
            for p in sorted(mine.glob("*.pt"))]
    return f"{mine} holds {', '.join(held[:5]) or 'no .pt file'}{', ...' if len(held) > 5 else ''}"


def weights_path(file: str, folder=None) -> Path:
    """Where the weight file ``file`` lives: in ``folder`` if given; else in the user's weights folder
    (:func:`user_weights_dir`) when one is in use and holds a checkpoint of that model (:func:`find_checkpoint`:
    found by what the checkpoint says it is, not by its file name); else in ``weights/`` of :func:`samples_dir`.

    Every learned model's weights are found through this one function (each model names its shipped file:
    ``WEIGHTS`` beside its networks), so a folder of models a user trained on their own data (``posekit train
    ... --data FOLDER --out DIR/ANY_NAME.pt``) replaces the shipped ones model by model; a model the folder
    lacks is the shipped one."""
    if folder:
        return Path(folder) / file
    mine = user_weights_dir()
    if mine is not None and mine.is_dir():
        found = find_checkpoint(file, mine)
        if found is not None:
            return found
    return samples_dir() / "weights" / file


@contextlib.contextmanager
def use_skeleton(names):
    """Within the block, :func:`find_checkpoint` prefers, among several checkpoints of one model in the user's
    folder, the one trained for these joint names (the data a benchmark opened)."""
    _USER_SKELETON.append(tuple(str(n) for n in names))
    try:
        yield
    finally:
        _USER_SKELETON.pop()


def user_weights_dir() -> Path | None:
    """The user's weights folder in use: the innermost :func:`use_weights`, else ``$POSEKIT_WEIGHTS_DIR``, else
    None (the shipped weights)."""
    if _USER_WEIGHTS:
        return _USER_WEIGHTS[-1]
    env = os.environ.get("POSEKIT_WEIGHTS_DIR")
    return Path(env).expanduser() if env else None


@contextlib.contextmanager
def use_weights(folder):
    """Within the block, learned models load their weights from ``folder`` where it holds their file
    (:func:`weights_path`).

    Raises
    ------
    FileNotFoundError
        ``folder`` is not a folder, or holds no ``.pt`` file (said before any work).
    ValueError
        A ``.pt`` file in ``folder`` is not a posekit checkpoint (named, before any work).
    """
    path = Path(folder).expanduser()
    if not path.is_dir():
        raise FileNotFoundError(f"--weights {folder}: not a folder (expected a folder of .pt files from "
                                "`posekit train ... --out DIR/FILE.pt`)")
    if not any(path.glob("*.pt")):
        raise FileNotFoundError(f"--weights {folder}: the folder holds no .pt file (expected the checkpoints of "
                                "`posekit train ... --out DIR/FILE.pt`)")
    junk = [p.name for p in sorted(path.glob("*.pt")) if _header(p) is None]
    if junk:  # said of the user's file, before a model falls back on the shipped one and is blamed for it
        raise ValueError(f"--weights {folder}: {', '.join(junk[:3])}{', ...' if len(junk) > 3 else ''} "
                         f"{'is' if len(junk) == 1 else 'are'} not a posekit checkpoint (not readable as one); "
                         "expected only the checkpoints of `posekit train ... --out DIR/FILE.pt` in the folder "
                         "(move the file out, or train it again)")
    _USER_WEIGHTS.append(path)
    try:
        yield path
    finally:
        _USER_WEIGHTS.pop()


def shared_data_dir(data_dir=None) -> Path | None:
    """The folder of larger datasets: ``data_dir`` if given, else ``$POSEKIT_DATA_DIR``, else None."""
    d = data_dir if data_dir is not None else os.environ.get("POSEKIT_DATA_DIR")
    if not d:
        return None
    d = Path(d).expanduser()
    return d if d.is_dir() else None


def require_shared_data(data_dir=None) -> Path:
    """Like :func:`shared_data_dir` but raise a clear error when the folder is not there."""
    d = shared_data_dir(data_dir)
    if d is None:
        raise FileNotFoundError(
            "larger datasets not found: set POSEKIT_DATA_DIR to the folder holding bandai-namco-1/ and "
            "bandai-namco-2-every4th/ (in Python you may pass data_dir=... instead)"
            + (f" (given: {data_dir or os.environ.get('POSEKIT_DATA_DIR')!r} is not a folder)"
               if (data_dir or os.environ.get("POSEKIT_DATA_DIR")) else "")
        )
    return d


def notebooks_dir() -> Path:
    """Folder holding the lessons (``notebooks/`` of the posekit checkout)."""
    return _CHECKOUT / "notebooks"


EXPORTS = "studio_exports"
"""The studio's export folder's name, relative to the working folder (the notebook's): :func:`exports_dir`."""


def exports_dir() -> Path:
    """Where the posing studio writes its files when no folder is given (:class:`posekit.viz.studio.PosingStudio`,
    the app's pages: :func:`posekit.viz.studio_app.session_folder`): ``$POSEKIT_EXPORTS_DIR`` when it is set, else
    :data:`EXPORTS` relative to the working folder (beside the notebook that runs the studio).

    ``tests/conftest.py`` sets ``$POSEKIT_EXPORTS_DIR`` to a temporary folder for every test and every notebook the
    tests run (their kernels inherit it), so ``make test`` leaves a student's ``notebooks/studio_exports/`` as it was.
    Nothing is created here: the studio makes the folder when it first writes a file.
    """
    env = os.environ.get("POSEKIT_EXPORTS_DIR")
    return Path(env) if env else Path(EXPORTS)


def course_assets_dir() -> Path:
    """Folder holding the npm packages ``reveal.js`` and ``mathjax`` (``make course-assets``).

    Raises
    ------
    FileNotFoundError
        When they are not installed, saying how to install them.
    """
    env = os.environ.get("POSEKIT_COURSE_ASSETS")
    d = Path(env) if env else _CHECKOUT / "tools" / "course" / "node_modules"
    missing = [p for p in ("reveal.js/dist/reveal.js", "mathjax/es5/tex-svg-full.js") if not (d / p).is_file()]
    if missing:
        raise FileNotFoundError(
            f"reveal.js and MathJax not found in {d} (missing {', '.join(missing)}): run `make course-assets` "
            "(npm ci in tools/course) or point POSEKIT_COURSE_ASSETS at a node_modules folder holding them")
    return d
