"""Shared machinery of the checkers.

:func:`report` runs a student's function on a checker's cases and prints one verdict line. Besides comparing the
answers it refuses three things a grader would: an answer that *changes its inputs* in place (the caller's array is
not the function's to move), an answer that *calls the very posekit function it is compared against* (the exercise
is to build it), and cases whose several correct conventions the text allows (``Either``: one of them must match).
"""

from __future__ import annotations

import copy
import sys
import types
from dataclasses import dataclass

import numpy as np

# captured once: an answer that rebinds numpy's functions while it runs cannot change how it is judged
_allclose, _asarray, _array_equal, _shape = np.allclose, np.asarray, np.array_equal, np.shape


class Forbidden(Exception):
    """The answer called the posekit function it is compared against (raised in a judge, :mod:`._judge`)."""


class WatchOff(Exception):
    """The answer switched the checker's watch off while it ran (raised in a judge, :mod:`._judge`)."""


class _Current:
    """What :func:`report` tells a judge's ``Remote`` about the case in hand: the functions to forbid, and (set by
    the ``Remote``) which input the answer changed in place, by the executor's account."""

    forbid: tuple = ()
    own: tuple = ()  # "module:name" of every helper of the checker's own module (set by the judge): forbidden too
    changed: int | None = None
    in_judge: bool = False  # in a judge the answer runs elsewhere: its executor watches, not this process


CURRENT = _Current()


@dataclass(frozen=True)
class Either:
    """Several answers a case accepts (the conventions the lesson's text allows), e.g. two clamping margins."""

    answers: tuple

    def __init__(self, *answers):
        object.__setattr__(self, "answers", tuple(_asarray(a, dtype=float) for a in answers))


_TRIPS: dict = {}
"""Tripwire code object -> (the forbidden function's own copy, its name, the watch to tell): see :class:`_Watch`."""
_AUDIT = {"watch": None}
"""The watch an audit hook reports to while an answer runs (one hook per process, added on first use)."""


def _trip(*args, **kwargs):
    import sys as here  # this code runs with the forbidden function's module globals: every name imported here

    import posekit.exercises._check as check

    return check._tripped(here._getframe(0).f_code, args, kwargs)


def _tripped(code, args, kwargs):
    original, name, watch = _TRIPS[code]
    watch.called.append(name)
    return original(*args, **kwargs)


def _audit(event, _args):
    watch = _AUDIT["watch"]
    if watch is not None and event in ("sys.setprofile", "sys.settrace", "code.__new__",
                                       "threading.setprofile", "threading.settrace"):
        watch.tampered.append(event)


class _Watch:
    """Notes every call of a forbidden function while the student's answer runs, in any thread.

    * A forbidden Python function's code is swapped, for the duration, for a tripwire that notes the call and runs
      the function's own code: every reference to it (captured under another name, held by a thread started
      earlier, called through a wrapper) trips it.
    * A profile hook, in this thread and in every thread the answer starts, recognises the function's code by its
      bytecode, constants, file and line, so a copy made beforehand (``types.FunctionType(f.__code__.replace(co_name=...))``)
      is seen too.
    * An audit hook notes, at any point of the answer's run, a call that switches a profile or trace hook or makes
      a code object: the watch was being turned off (``turned_off``), whatever the answer restores before it returns.
    * Other callables (compiled kernels) are replaced, for the duration, in every loaded module that holds them by a
      recorder that calls through.
    """

    def __init__(self, forbid):
        self.codes = {}
        self.bytecode = {}
        self.functions = []
        self.others = []
        for f in forbid:
            name = f"{getattr(f, '__module__', '?')}.{getattr(f, '__qualname__', getattr(f, '__name__', repr(f)))}"
            code = getattr(f, "__code__", None)
            if isinstance(code, types.CodeType) and isinstance(f, types.FunctionType):
                self.codes[code] = name
                self.bytecode[self._key(code)] = name
                self.functions.append((f, name))
            else:
                self.others.append((f, name))
        self.called = []
        self.tampered = []
        self._swapped = []
        self._tripped = []
        self.turned_off = False
        self._hook = self._profile  # one bound method, so that the one set can be recognised afterwards

    @staticmethod
    def _key(code):
        """A code object as a copy of it keeps it (``replace(co_name=...)`` changes the name only)."""
        return code.co_code, code.co_consts, code.co_filename, code.co_firstlineno

    def _profile(self, frame, event, arg):
        if event == "call":
            code = frame.f_code
            name = self.codes.get(code)
            if name is None and code not in _TRIPS:
                name = self.bytecode.get(self._key(code))
            if name is not None:
                self.called.append(name)

    def __enter__(self):
        import threading

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
        for f, name in self.functions:
            if f.__closure__:  # a closure's code cannot be swapped: the profile hook sees it
                continue
            own = types.FunctionType(f.__code__, f.__globals__, f.__name__, f.__defaults__, f.__closure__)
            own.__kwdefaults__ = f.__kwdefaults__
            trip = _trip.__code__.replace(co_name=f"_trip_{len(_TRIPS)}_{f.__name__}")
            _TRIPS[trip] = (own, name, self)
            self._tripped.append((f, f.__code__, trip))
            f.__code__ = trip
        if not getattr(sys, "_posekit_audit", False):
            sys.addaudithook(_audit)
            sys._posekit_audit = True
        self._previous = sys.getprofile()
        self._previous_threads = threading.getprofile()
        if self.codes:
            threading.setprofile(self._hook)
            sys.setprofile(self._hook)
        _AUDIT["watch"] = self
        return self

    def __exit__(self, *exc):
        import threading

        _AUDIT["watch"] = None
        self.turned_off = bool(self.tampered) or (bool(self.codes) and sys.getprofile() is not self._hook)
        sys.setprofile(self._previous)
        threading.setprofile(self._previous_threads)
        for f, code, trip in self._tripped:
            f.__code__ = code
            _TRIPS.pop(trip, None)
        for d, key, f in self._swapped:
            d[key] = f
        return False


def flat(*parts) -> np.ndarray:
    """The parts of an answer (a loss and a gradient, three arrays) as one flat vector, in float32 when any part is
    float32, so that :func:`report` judges a float32 answer with float32's tolerance (a wrapper that made everything
    float64 would hold it to float64's)."""
    single = any(getattr(p, "dtype", None) == np.float32 for p in parts)
    return np.concatenate([np.ravel(_asarray(p, dtype=np.float32 if single else float)) for p in parts])


def _snapshot(args):
    return [copy.deepcopy(a) if isinstance(a, (np.ndarray, list, dict)) else None for a in args]


def _changed_input(args, before) -> int | None:
    for k, (a, b) in enumerate(zip(args, before)):
        if b is None:
            continue
        if isinstance(b, np.ndarray):
            if a.shape != b.shape or not _array_equal(a, b, equal_nan=True):
                return k
        elif type(a) is not type(b) or len(a) != len(b) or any(
                not _array_equal(_asarray(x), _asarray(y)) for x, y in zip(a, b)):
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
        watch = watch_class(() if CURRENT.in_judge else forbid)
        CURRENT.forbid, CURRENT.changed = tuple(forbid), None
        try:
            with watch:
                got = fn(*args)
        except NotImplementedError:
            print(f"… {name}: not attempted yet (the function still raises NotImplementedError)")
            return False
        except WatchOff:
            watch.turned_off = True
        except Forbidden as e:
            watch.called.append(str(e))
        except Exception as e:  # a student's bug must not stop the notebook
            print(f"✗ {name}: case {k + 1} raised {type(e).__name__}: {e}")
            return False
        if watch.turned_off:
            print(f"✗ {name}: your function switched the checker's watch off (a profile or trace hook, or a code "
                  "object made while it ran): not accepted")
            return False
        if watch.called:
            print(f"✗ {name}: your function calls {watch.called[0]}, the function it is compared against — "
                  "build it yourself from the lesson's steps")
            return False
        changed = _changed_input(args, before)
        if changed is None:
            changed = CURRENT.changed
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
        answers = expected.answers if isinstance(expected, Either) else (expected,)
        if isinstance(got, tuple):  # rows of the answer, or (answer, extra) as posekit's solvers return
            try:
                whole = asarray(got, dtype=float)
            except (TypeError, ValueError):
                whole = None
            got = whole if whole is not None and whole.shape == shape_of(answers[0]) else got[0]
        single = getattr(got, "dtype", None) == np.float32 or (
            isinstance(got, (list, tuple)) and any(getattr(g, "dtype", None) == np.float32 for g in got))
        try:
            got = asarray(got, dtype=float)
        except (TypeError, ValueError):
            print(f"✗ {name}: case {k + 1} returned {type(got).__name__}, expected numbers shaped "
                  f"{shape_of(answers[0])}")
            return False
        if got.shape != shape_of(answers[0]):
            print(f"✗ {name}: case {k + 1} returned shape {got.shape}, expected {shape_of(answers[0])}")
            return False
        tol = atol
        if single:  # float32 arithmetic: about a hundred of its units in the last place
            tol = max(atol, 1e-5 * max(1.0, max(float(np.abs(a).max(initial=0.0)) for a in answers)))
        if not any(allclose(got, a, atol=tol) for a in answers):
            nearest = min(answers, key=lambda a: float(np.abs(got - a).max()))
            print(f"✗ {name}: case {k + 1} differs: {describe(got, nearest)}")
            return False
    print(f"✓ {name}: all {len(cases)} cases match posekit")
    return True
