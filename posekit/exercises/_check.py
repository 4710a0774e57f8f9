"""Shared machinery of the checkers."""

from __future__ import annotations

import numpy as np


def report(name: str, fn, cases, atol: float = 1e-6) -> bool:
    """Run ``fn(*args)`` for each ``(args, expected, describe)`` case and print one verdict line.

    ``describe(got, expected)`` returns a short text naming where they differ. An ``expected`` of None
    (no answer, e.g. a ray that misses) passes only when ``fn`` returns None too.
    """
    for k, (args, expected, describe) in enumerate(cases):
        try:
            got = fn(*args)
        except NotImplementedError:
            print(f"… {name}: not attempted yet (the function still raises NotImplementedError)")
            return False
        except Exception as e:  # a student's bug must not stop the notebook
            print(f"✗ {name}: case {k + 1} raised {type(e).__name__}: {e}")
            return False
        if expected is None or got is None:  # "no answer" cases (a ray that misses): both must say None
            if (expected is None) != (got is None):
                print(f"✗ {name}: case {k + 1} differs: {describe(got, expected)}")
                return False
            continue
        got = np.asarray(got, dtype=float) if not isinstance(got, tuple) else np.asarray(got[0], dtype=float)
        if got.shape != np.shape(expected):
            print(f"✗ {name}: case {k + 1} returned shape {got.shape}, expected {np.shape(expected)}")
            return False
        if not np.allclose(got, expected, atol=atol):
            print(f"✗ {name}: case {k + 1} differs: {describe(got, expected)}")
            return False
    print(f"✓ {name}: all {len(cases)} cases match posekit")
    return True
