"""``njit``: numba's compiler when numba is installed, else a no-op decorator (same results, slower).

Compiled kernels are cached next to their module (``cache=True``), so only the first run pays the
compile time.
"""

try:
    from numba import njit as _njit

    def njit(fn=None, **kw):
        kw.setdefault("cache", True)
        kw.setdefault("fastmath", False)
        return _njit(**kw)(fn) if fn is not None else _njit(**kw)

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - numba is a dependency; this keeps a broken install usable
    def njit(fn=None, **kw):
        return fn if fn is not None else (lambda f: f)

    HAVE_NUMBA = False
