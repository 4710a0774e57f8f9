"""``njit``: numba's compiler when numba is installed, else a no-op decorator (same results, slower).

Kernels are compiled on first use in each process (about a second each). numba's on-disk cache is
off on purpose: it keys on the kernel's own file only, so a kernel calling a helper from another
file would keep running the old helper after an update.
"""

try:
    from numba import njit as _njit

    def njit(fn=None, **kw):
        kw.setdefault("cache", False)
        kw.setdefault("fastmath", False)
        return _njit(**kw)(fn) if fn is not None else _njit(**kw)

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - numba is a dependency; this keeps a broken install usable
    def njit(fn=None, **kw):
        return fn if fn is not None else (lambda f: f)

    HAVE_NUMBA = False
