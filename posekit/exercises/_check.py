"""Shared machinery of the checkers.

:func:`report` runs a student's function on a checker's cases and prints one verdict line. Besides comparing the
answers it refuses three things a grader would: an answer that *changes its inputs* in place (the caller's array is
not the function's to move), an answer that *calls the very posekit function it is compared against* (the exercise
is to build it), and cases whose several correct conventions the text allows (``Either``: one of them must match).
"""

from __future__ import annotations

import sys
import types
from dataclasses import dataclass

import numpy as np

# captured once: an answer that rebinds numpy's functions while it runs cannot change how it is judged
_allclose, _asarray, _array_equal, _shape = np.allclose, np.asarray, np.array_equal, np.shape


@dataclass(frozen=True)
class Either:
    """Several answers a case accepts (the conventions the lesson's text allows), e.g. two clamping margins."""

    answers: tuple

    def __init__(self, *answers):
        object.__setattr__(self, "answers", tuple(_asarray(a, dtype=float) for a in answers))


class _Watch:
    """Notes every call of a forbidden function while the student's answer runs.

    Python functions are recognised by their code object through :func:`sys.setprofile` (so a reference captured
    under another name, or called through a wrapper, is seen too); other callables (compiled kernels) are replaced,
    for the duration, in every loaded module that holds them by a recorder that calls through.
    """

    def __init__(self, forbid):
        self.names = {}
        self.codes = {}
        self.others = []
        for f in forbid:
            name = f"{getattr(f, '__module__', '?')}.{getattr(f, '__qualname__', getattr(f, '__name__', repr(f)))}"
            code = getattr(f, "__code__", None)
            if isinstance(code, types.CodeType):
                self.codes[code] = name
            else:
                self.others.append((f, name))
        self.called = []
        self._swapped = []
        self.turned_off = False
        self._hook = self._profile  # one bound method, so that the one set can be recognised afterwards

    def _profile(self, frame, event, arg):
        if event == "call" and frame.f_code in self.codes:
            self.called.append(self.codes[frame.f_code])

    def __enter__(self):
        for f, name in self.others:
            def recorder(*a, __f=f, __name=name, **k):
                self.called.append(__name)
                return __f(*a, **k)
            for mod in list(sys.modules.values()):
                d = getattr(mod, "__dict__", None)
                if not isinstance(d, dict):
                    continue
                for key, value in list(d.items()):
                    if value is f:
                        d[key] = recorder
                        self._swapped.append((d, key, f))
        self._previous = sys.getprofile()
        if self.codes:
            sys.setprofile(self._hook)
        return self

    def __exit__(self, *exc):
        self.turned_off = bool(self.codes) and sys.getprofile() is not self._hook
        sys.setprofile(self._previous)
        for d, key, f in self._swapped:
            d[key] = f
        return False


def _snapshot(args):
    return [a.copy() if isinstance(a, np.ndarray) else None for a in args]


def _changed_input(args, before) -> int | None:
    for k, (a, b) in enumerate(zip(args, before)):
        if b is not None and (a.shape != b.shape or not _array_equal(a, b, equal_nan=True)):
            return k
    return None


def report(name: str, fn, cases, atol: float = 1e-6, forbid=(), arg_names=None) -> bool:
    """Run ``fn(*args)`` for each ``(args, expected, describe)`` case and print one verdict line.

    Parameters
    ----------
    name : str
        The checker's name, printed.
    fn : callable
        The student's function (or a wrapper that calls it).
    cases : list of (tuple, ndarray or Either or None, callable)
        ``describe(got, expected)`` returns a short text naming where they differ. An ``expected`` of None (no
        answer, e.g. a ray that misses) passes only when ``fn`` returns None too; an :class:`Either` passes when
        any of its answers matches.
    atol : float
        Absolute tolerance of the comparison.
    forbid : sequence of callables
        The posekit functions the expected answers come from: an answer that calls one of them fails (the exercise
        is to build it, not to call it).
    arg_names : sequence of str, optional
        The parameters' names, to name an input the answer changed in place.

    Returns
    -------
    bool
        True when every case matches.
    """
    allclose, asarray, shape_of, watch_class = _allclose, _asarray, _shape, _Watch  # bound before any answer runs
    for k, (args, expected, describe) in enumerate(cases):
        before = _snapshot(args)
        watch = watch_class(forbid)
        try:
            with watch:
                got = fn(*args)
        except NotImplementedError:
            print(f"… {name}: not attempted yet (the function still raises NotImplementedError)")
            return False
        except Exception as e:  # a student's bug must not stop the notebook
            print(f"✗ {name}: case {k + 1} raised {type(e).__name__}: {e}")
            return False
        if watch.turned_off:
            print(f"✗ {name}: your function switched the checker's watch off (sys.setprofile): not accepted")
            return False
        if watch.called:
            print(f"✗ {name}: your function calls {watch.called[0]}, the function it is compared against — "
                  "build it yourself from the lesson's steps")
            return False
        changed = _changed_input(args, before)
        if changed is not None:
            what = f"`{arg_names[changed]}`" if arg_names and changed < len(arg_names) else f"argument {changed + 1}"
            print(f"✗ {name}: case {k + 1} changed its input {what} in place — work on a copy "
                  "(the caller's array is not yours to move)")
            return False
        if expected is None or got is None:  # "no answer" cases (a ray that misses): both must say None
            if (expected is None) != (got is None):
                print(f"✗ {name}: case {k + 1} differs: {describe(got, expected)}")
                return False
            continue
        got = asarray(got, dtype=float) if not isinstance(got, tuple) else asarray(got[0], dtype=float)
        answers = expected.answers if isinstance(expected, Either) else (expected,)
        if got.shape != shape_of(answers[0]):
            print(f"✗ {name}: case {k + 1} returned shape {got.shape}, expected {shape_of(answers[0])}")
            return False
        if not any(allclose(got, a, atol=atol) for a in answers):
            nearest = min(answers, key=lambda a: float(np.abs(got - a).max()))
            print(f"✗ {name}: case {k + 1} differs: {describe(got, nearest)}")
            return False
    print(f"✓ {name}: all {len(cases)} cases match posekit")
    return True
