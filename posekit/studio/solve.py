"""Solve with the effectors of the kinds a solver honours: the one place that filters by ``solver.kinds``.

Introduced in ``notebooks/05_protores.ipynb`` (ProtoRes honours rotations and look-ats, FABRIK positions only) and
used by every panel, the posing studio (:class:`~posekit.studio.session.PosingSession`), its timeline and its
warm-up. The :class:`~posekit.ik.api.Solver` protocol declares ``kinds`` and ``needs_start``: they are read, never
defaulted.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

__all__ = ["Solved", "honoured", "solve_honoured", "accepts"]


def honoured(solver, effectors) -> tuple:
    """``(used, ignored)``: the indices of ``effectors`` whose kind ``solver.kinds`` holds, and the effectors
    (:class:`~posekit.ik.api.Effector`) of the other kinds, which the solver is not given."""
    kinds = solver.kinds
    used = [k for k, e in enumerate(effectors) if e.kind in kinds]
    ignored = [e for e in effectors if e.kind not in kinds]
    return used, ignored


@dataclass
class Solved:
    """One solver's answer to one effector list.

    Attributes
    ----------
    result : IKResult, Exception or None
        The result; the exception the solver raised (a ``ValueError`` is a refusal); None when nothing was solved
        (no effectors, or none of a kind it honours).
    used : list of int
        Indices of the effectors it was given.
    ignored : list of Effector
        The effectors of kinds it does not honour.
    ms : float
        Milliseconds the solve took (0 when nothing was solved).
    """

    result: object = None
    used: list = field(default_factory=list)
    ignored: list = field(default_factory=list)
    ms: float = 0.0


def solve_honoured(solver, start, effectors) -> Solved:
    """Solve ``effectors`` with ``solver``, given only those of the kinds it honours (:func:`honoured`), from
    ``start`` when the solver ``needs_start`` (else from None). An exception the solver raises is returned in
    :attr:`Solved.result`, never raised: one solver that fails leaves the others their say."""
    used, ignored = honoured(solver, effectors)
    if not used:
        return Solved(None, used, ignored)
    t = time.perf_counter()
    try:
        res = solver.solve(start if solver.needs_start else None, [effectors[k] for k in used])
    except Exception as err:  # noqa: BLE001 - a solver that fails says why; the others go on
        return Solved(err, used, ignored)
    return Solved(res, used, ignored, (time.perf_counter() - t) * 1e3)


def accepts(solver, start, effectors) -> bool:
    """Whether ``solver`` solves ``effectors`` (those of the kinds it honours) without raising: nothing to solve
    counts as accepted."""
    return not isinstance(solve_honoured(solver, start, effectors).result, Exception)
