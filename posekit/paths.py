"""The one place that knows where data lives (no walking up parent folders).

* :func:`samples_dir` — the embedded default data and shipped weights, ``data_samples/`` at the top
  of the posekit checkout (override with ``$POSEKIT_SAMPLES_DIR``).
* :func:`weights_path` — where a weight file lives (``data_samples/weights/`` unless a folder is given).
* :func:`shared_data_dir` — larger real mocap read by path, never copied: ``$POSEKIT_DATA_DIR``
  (the Makefile points it at ``../shared/data`` when that folder exists).
* :func:`notebooks_dir` — the lessons, ``notebooks/`` of the checkout.
* :func:`course_assets_dir` — reveal.js and MathJax for the slides and the course page, installed by
  ``make course-assets`` (npm) into ``tools/course/node_modules`` (override with ``$POSEKIT_COURSE_ASSETS``).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["samples_dir", "weights_path", "shared_data_dir", "require_shared_data", "notebooks_dir", "course_assets_dir"]

_CHECKOUT = Path(__file__).resolve().parent.parent


def samples_dir() -> Path:
    """Folder holding the shipped samples and weights."""
    env = os.environ.get("POSEKIT_SAMPLES_DIR")
    return Path(env) if env else _CHECKOUT / "data_samples"


def weights_path(file: str, folder=None) -> Path:
    """Where the weight file ``file`` lives: in ``folder`` if given, else in ``weights/`` of :func:`samples_dir`.

    Every learned model's shipped weights are found through this one function (each model names its
    file: ``WEIGHTS`` beside its networks)."""
    return Path(folder or samples_dir() / "weights") / file


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
