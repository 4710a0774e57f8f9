"""``njit``: numba's compiler when numba is installed, else a no-op decorator (same results, slower).

Compiled kernels are cached on disk and reused by every later process (a notebook kernel, a test worker, the
studio's kernel): compiling one costs about a second, loading it a few milliseconds. numba's own cache keys a
kernel on its own file only, so a kernel calling a helper from another file would keep running the old helper
after an update. The cache here lives in a folder named by a hash of **every** posekit source file, numba's
version and Python's (:func:`cache_dir`): any change to the package starts a fresh folder, so a stale kernel is
never run; numba's index adds the CPU (a kernel built for one CPU is not loaded on another).

Where: ``$POSEKIT_NUMBA_CACHE`` if set (``0`` or ``off`` turns caching off), else ``$NUMBA_CACHE_DIR`` if set,
else ``$XDG_CACHE_HOME/posekit`` (default ``~/.cache/posekit``), then ``numba-<hash>``; each process touches its
folder, and folders of other source versions unused for a week are removed when a new one is made. A folder that
cannot be written falls back to compiling in every process.
"""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

__all__ = ["njit", "HAVE_NUMBA", "cache_dir", "source_hash"]

_PACKAGE = Path(__file__).resolve().parent


def source_hash() -> str:
    """A hash of every ``.py`` file of the posekit package (path and bytes), numba's, numpy's and Python's
    versions: what any compiled kernel can depend on."""
    import numpy

    h = hashlib.sha256()
    try:
        import numba

        h.update(numba.__version__.encode())
    except ImportError:  # pragma: no cover
        pass
    h.update(numpy.__version__.encode())
    h.update(sys.version.encode())
    for f in sorted(_PACKAGE.rglob("*.py")):
        h.update(str(f.relative_to(_PACKAGE)).encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


def cache_dir() -> Path | None:
    """The folder compiled kernels are cached in (see the module docstring), or None when caching is off or the
    folder cannot be created."""
    setting = os.environ.get("POSEKIT_NUMBA_CACHE", "").strip()
    if setting.lower() in ("0", "off", "false", "no"):
        return None
    base = setting or os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "posekit")
    path = Path(base) / f"numba-{source_hash()}"
    try:
        new = not path.is_dir()
        path.mkdir(parents=True, exist_ok=True)
        (path / ".writable").touch()
    except OSError:
        return None
    if new:
        _prune(path)
    return path


def _prune(current: Path, days: float = 7.0) -> None:
    """Remove the caches of older source versions not used for ``days`` (each is a few MB; a checkout that
    still uses one just compiles again)."""
    import shutil
    import time

    for old in current.parent.glob("numba-*"):
        try:
            if old != current and time.time() - (old / ".writable").stat().st_mtime > days * 86400:
                shutil.rmtree(old, ignore_errors=True)
        except OSError:
            continue


try:
    import numba
    from numba import njit as _njit

    _CACHE = cache_dir()
    if _CACHE is not None:
        numba.config.CACHE_DIR = str(_CACHE)  # read when a cached kernel is defined, below

    def njit(fn=None, **kw):
        kw.setdefault("cache", _CACHE is not None)
        kw.setdefault("fastmath", False)
        return _njit(**kw)(fn) if fn is not None else _njit(**kw)

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - numba is a dependency; this keeps a broken install usable
    _CACHE = None

    def njit(fn=None, **kw):
        return fn if fn is not None else (lambda f: f)

    HAVE_NUMBA = False
