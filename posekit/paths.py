"""The one place that knows where data lives (no walking up parent folders).

* :func:`samples_dir` — the embedded default data and shipped weights, ``data_samples/`` at the top
  of the posekit checkout (override with ``$POSEKIT_SAMPLES_DIR``).
* :func:`shared_data_dir` — larger real mocap read by path, never copied: ``$POSEKIT_DATA_DIR``
  (the Makefile points it at ``../shared/data`` when that folder exists).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["samples_dir", "shared_data_dir", "require_shared_data"]


def samples_dir() -> Path:
    """Folder holding the shipped samples and weights."""
    env = os.environ.get("POSEKIT_SAMPLES_DIR")
    return Path(env) if env else Path(__file__).resolve().parent.parent / "data_samples"


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
