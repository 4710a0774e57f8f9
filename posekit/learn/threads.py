"""One-thread sections: the same numbers and fair timings whatever the machine's core count.

Introduced with :mod:`posekit.learn` in ``notebooks/02_inverse_rig_mapping.ipynb``; the benchmarks
(``posekit bench fk``, ``posekit bench invrig``, ``posekit bench ik``) time solvers on one thread so
that no method wins by using more cores, and lessons 03-05 reuse it.
"""

from __future__ import annotations

from contextlib import contextmanager

__all__ = ["single_thread"]


@contextmanager
def single_thread():
    """Run the ``with`` block on one thread: BLAS/OpenMP pools (``threadpoolctl``) and torch's
    intra-op pool (``torch.set_num_threads(1)``); both are restored afterwards, also on error.

    Examples
    --------
    >>> with single_thread():
    ...     y = net.predict(X)            # doctest: +SKIP
    """
    import torch
    from threadpoolctl import threadpool_limits

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        with threadpool_limits(1):
            yield
    finally:
        torch.set_num_threads(threads)
