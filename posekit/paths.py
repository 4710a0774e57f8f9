"""The one place that knows where data lives (no walking up parent folders).

* :func:`samples_dir` — the embedded default data and shipped weights, ``data_samples/`` at the top
  of the posekit checkout (override with ``$POSEKIT_SAMPLES_DIR``).
* :func:`weights_path` — where a weight file lives: ``data_samples/weights/`` unless a folder is given, or a
  weights folder of the user's own is in use (:func:`use_weights`, ``$POSEKIT_WEIGHTS_DIR``, ``--weights DIR``
  of ``posekit bench ik`` and ``bench all``, ``make studio STUDIO_WEIGHTS=DIR``) and holds that file.
* :func:`shared_data_dir` — larger real mocap read by path, never copied: ``$POSEKIT_DATA_DIR``
  (the Makefile points it at ``../shared/data`` when that folder exists).
* :func:`notebooks_dir` — the lessons, ``notebooks/`` of the checkout.
* :func:`course_assets_dir` — reveal.js and MathJax for the slides and the course page, installed by
  ``make course-assets`` (npm) into ``tools/course/node_modules`` (override with ``$POSEKIT_COURSE_ASSETS``).
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

__all__ = ["samples_dir", "weights_path", "user_weights_dir", "use_weights", "shared_data_dir", "require_shared_data",
           "notebooks_dir", "course_assets_dir"]

_USER_WEIGHTS: list[Path] = []

_CHECKOUT = Path(__file__).resolve().parent.parent


def samples_dir() -> Path:
    """Folder holding the shipped samples and weights."""
    env = os.environ.get("POSEKIT_SAMPLES_DIR")
    return Path(env) if env else _CHECKOUT / "data_samples"


def weights_path(file: str, folder=None) -> Path:
    """Where the weight file ``file`` lives: in ``folder`` if given; else in the user's weights folder
    (:func:`user_weights_dir`) when one is in use and holds ``file``; else in ``weights/`` of :func:`samples_dir`.

    Every learned model's weights are found through this one function (each model names its file:
    ``WEIGHTS`` beside its networks), so a folder of models a user trained on their own data (``posekit train
    ... --data FOLDER --out DIR/FILE``) replaces the shipped ones file by file; a file the folder lacks is the
    shipped one."""
    if folder:
        return Path(folder) / file
    mine = user_weights_dir()
    if mine is not None and (mine / file).is_file():
        return mine / file
    return samples_dir() / "weights" / file


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
    """
    path = Path(folder).expanduser()
    if not path.is_dir():
        raise FileNotFoundError(f"--weights {folder}: not a folder (expected a folder of .pt files from "
                                "`posekit train ... --out DIR/FILE.pt`)")
    if not any(path.glob("*.pt")):
        raise FileNotFoundError(f"--weights {folder}: the folder holds no .pt file (expected the checkpoints of "
                                "`posekit train ... --out DIR/FILE.pt`)")
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
