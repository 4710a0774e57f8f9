"""One-thread sections: the same numbers and fair timings whatever the machine's core count.

Introduced with :mod:`posekit.learn` in ``notebooks/02_inverse_rig_mapping.ipynb``; the benchmarks
(``posekit bench fk``, ``posekit bench invrig``, ``posekit bench ik``) time solvers on one thread so
that no method wins by using more cores, and lessons 03-05 reuse it.
"""

from __future__ import annotations

from contextlib import contextmanager

__all__ = ["single_thread", "limit_threads"]


@contextmanager
def limit_threads(n: int | None):
    """Run the ``with`` block on at most ``n`` threads: BLAS/OpenMP pools (``threadpoolctl``) and torch's
    intra-op pool (``torch.set_num_threads``); both are restored afterwards, also on error. ``None``
    changes nothing."""
    if n is None:
        yield
        return
    import torch
    from threadpoolctl import threadpool_limits

    threads = torch.get_num_threads()
    torch.set_num_threads(int(n))
    try:
        with threadpool_limits(int(n)):
            yield
    finally:
        torch.set_num_threads(threads)


def single_thread():
    """Run the ``with`` block on one thread (:func:`limit_threads` with 1).

    Examples
    --------
    >>> with single_thread():
    ...     y = net.predict(X)            # doctest: +SKIP
    """
    return limit_threads(1)
