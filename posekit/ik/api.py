"""The one interface every posing solver implements: ``Effector``, ``Pose``, ``IKResult``, ``Solver``.

Introduced in ``notebooks/01_fabrik.ipynb``. FABRIK, CCD and damped least squares implement it now;
the neural solvers, AE-GAN latent optimisation and ProtoRes implement it in later lessons, and the
benchmark (:mod:`posekit.bench.ik`), the CLI and the viewer only ever talk to this interface and to
the registry (:mod:`posekit.ik.registry`).

The contract (version 2)
------------------------
* ``solver.kinds`` — the effector kinds it honours (``"position"``, ``"rotation"``, ``"look_at"``;
  :mod:`posekit.ik.effectors`). Any other kind is a ``ValueError`` naming the solver, the kind and
  what it supports — never silently ignored.
* ``solver.needs_start`` — whether ``solve`` needs a start pose. The classical solvers change a start
  pose (True); a solver that predicts a whole pose from the effectors accepts ``start=None``.
* ``solver.solve(start, effectors) -> IKResult`` — one problem.
* ``solver.solve_batch(starts, effectors) -> list[IKResult]`` — B problems: ``starts`` a sequence of
  B poses (or None), ``effectors`` one effector list shared by every problem or B lists; result ``b``
  equals ``solve(starts[b], effectors[b])`` (FABRIK solves a batch vectorised, to rounding).
* ``IKResult.effector_error`` and ``IKResult.converged`` always come from
  :func:`~posekit.ik.effector_errors.effector_errors`, the one definition of every kind's error.

:class:`SolverBase` holds the shared checks and the default batch loop; a solver subclasses it and
writes ``_solve(start, resolved) -> IKResult``.

Units and axes: :mod:`posekit.conventions` (metres, radians, Y up, facing +Z, quaternions xyzw).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, Sequence, runtime_checkable

import numpy as np

from ..records import Pose
from ..skeleton import Skeleton
from .effector_errors import effector_errors, effector_errors_batch, errors_of
from .effectors import DEFAULT_TOLERANCE, KINDS, Effector, ResolvedEffectors, check_look_at, resolve_effectors

__all__ = ["Effector", "Pose", "IKResult", "Solver", "SolverBase", "EFFECTOR_SETS", "effector_set",
           "resolve_effectors", "effector_errors", "effector_errors_batch", "KINDS", "DEFAULT_TOLERANCE",
           "ResolvedEffectors", "base_index", "base_on_target"]

EFFECTOR_SETS = {
    "2": ("left_hand", "right_hand"),
    "5": ("left_hand", "right_hand", "left_foot", "right_foot", "head"),  # Victor et al. 2021
    "5point": ("chest", "left_hand", "right_hand", "left_foot", "right_foot"),  # Oreshkin et al. 2022
}
"""Named effector sets, as joint roles."""


@dataclass
class IKResult:
    """What a solver returns.

    Attributes
    ----------
    pose : Pose
    converged : bool
        Every effector within its tolerance.
    iterations : int
    effector_error : ndarray, shape (K,)
        Each effector's error (:func:`~posekit.ik.effector_errors.effector_errors`): metres for position
        effectors, radians for rotation and look-at effectors.
    info : dict
        Solver-specific extras.
    kinds : tuple of str, length K
        The kind of each effector (so its error's unit is known); empty means all positions.
    """

    pose: Pose
    converged: bool
    iterations: int
    effector_error: np.ndarray
    info: dict = field(default_factory=dict)
    kinds: tuple = ()


@runtime_checkable
class Solver(Protocol):
    """Anything that poses a skeleton to meet effectors (the contract in the module docstring).
    ``isinstance(x, Solver)`` only checks attribute names; ``tests/ik/test_ik.py`` checks behaviour."""

    name: str
    skeleton: Skeleton
    kinds: tuple
    needs_start: bool

    def solve(self, start: Pose | None, effectors: Sequence[Effector]) -> IKResult:
        ...

    def solve_batch(self, starts, effectors) -> list:
        ...


class SolverBase:
    """The shared part of every solver: effector and start-pose checks, the batch loop, the result.

    A subclass sets ``name``, ``kinds``, ``needs_start`` and ``self.skeleton`` and implements
    ``_solve(start, resolved) -> IKResult`` (``start`` a checked :class:`Pose`, or None when
    ``needs_start`` is False and none was given; ``resolved`` the
    :class:`~posekit.ik.effectors.ResolvedEffectors`). It may override ``_solve_many(starts,
    resolved_list)`` to solve a batch at once (FABRIK does). :meth:`result` builds the
    :class:`IKResult` with the shared error function.
    """

    name: str = "solver"
    kinds: tuple = ("position",)
    needs_start: bool = True
    keeps_bone_lengths: bool = True
    """Every bone of a result keeps the skeleton's length (False: a learned solver's raw prediction)."""
    batch_atol: float = 1e-9
    """How closely ``solve_batch`` reproduces ``solve``, metres (float32 networks: about 1e-5)."""
    skeleton: Skeleton

    def resolve(self, effectors) -> ResolvedEffectors:
        """Check ``effectors`` against this solver's skeleton and kinds."""
        if isinstance(effectors, ResolvedEffectors):
            bad = [k for k in effectors.kinds if k not in self.kinds]
            if bad:
                raise ValueError(f"solver {self.name!r} does not support effector kind {bad[0]!r}; "
                                 f"it supports: {', '.join(self.kinds)}")
            return effectors
        return resolve_effectors(self.skeleton, effectors, self.kinds, self.name)

    def _prepare(self, start, effectors):
        if start is None:
            if self.needs_start:
                raise ValueError(f"solver {self.name!r} needs a start pose (it changes one); got start=None")
            return None, self.resolve(effectors)
        pos = check_pose(self.skeleton, start)
        res = self.resolve(effectors)
        check_look_at(res, pos)
        return self._onto_base(start, res), res

    def _onto_base(self, start: Pose, res: ResolvedEffectors) -> Pose:
        """A solver that keeps a base joint in place (``self.base``: FABRIK, CCD, DLS) starts from ``start`` moved
        as a whole onto a position effector on that joint, when there is one; else from ``start`` itself."""
        base = getattr(self, "base", None)
        return start if base is None else base_on_target(start, res, int(base))

    def solve(self, start: Pose | None, effectors: Sequence[Effector]) -> IKResult:
        """Pose the skeleton so the effectors reach their targets (one problem)."""
        start, res = self._prepare(start, effectors)
        return self._solve(start, res)

    def solve_batch(self, starts, effectors) -> list[IKResult]:
        """B problems at once; ``result[b]`` equals ``solve(starts[b], effectors[b])``.

        Parameters
        ----------
        starts : sequence of B Pose, or None
            None only for solvers with ``needs_start = False`` (then B comes from ``effectors``).
        effectors : sequence of Effector, or sequence of B sequences of Effector
            One list shared by every problem, or one list per problem.

        Returns
        -------
        list of B IKResult
        """
        starts, effs = batch_arguments(starts, effectors)
        shared = {}
        prepared_s, prepared_r = [], []
        for s, e in zip(starts, effs):
            key = id(e)
            if s is None or key not in shared:
                s, r = self._prepare(s, e)
                shared[key] = r
            else:
                s, r = self._prepare_start(s, shared[key])
            prepared_s.append(s)
            prepared_r.append(r)
        return self._solve_many(prepared_s, prepared_r)

    def _prepare_start(self, start, res):
        check_look_at(res, check_pose(self.skeleton, start))
        return self._onto_base(start, res), res

    def _solve(self, start, resolved) -> IKResult:
        raise NotImplementedError

    def _solve_many(self, starts, resolved) -> list[IKResult]:
        return [self._solve(s, r) for s, r in zip(starts, resolved)]

    def result(self, pose: Pose, resolved: ResolvedEffectors, iterations: int, info=None,
               global_rot=None) -> IKResult:
        """The :class:`IKResult` of ``pose``, errors and convergence by the shared error function;
        ``global_rot`` (J, 3, 3), when the solver has it, saves recomputing FK."""
        if global_rot is not None or not resolved.angular:
            err, conv = errors_of(pose.global_pos, global_rot, resolved)
        else:
            err, conv = effector_errors(self.skeleton, pose, resolved)
        return IKResult(pose, conv, int(iterations), err, {} if info is None else info, resolved.kinds)


def batch_arguments(starts, effectors):
    """Normalise ``solve_batch`` arguments to two lists of length B (see :meth:`SolverBase.solve_batch`)."""
    shared = isinstance(effectors, ResolvedEffectors) or (
        len(effectors) > 0 and all(isinstance(e, Effector) for e in effectors))
    if starts is None:
        B = 1 if shared else len(effectors)
        starts = [None] * B
    else:
        if isinstance(starts, Pose):
            raise ValueError("starts: expected a sequence of Pose (one per problem), got one Pose; "
                             "use solve() for a single problem")
        starts = list(starts)
    effs = [effectors] * len(starts) if shared else list(effectors)
    if len(effs) != len(starts):
        raise ValueError(f"{len(starts)} start poses but {len(effs)} effector lists; give one list per "
                         "problem, or one list of Effector objects for all")
    return starts, effs


def effector_set(skeleton: Skeleton, name: str, pose_pos, tolerance: float = 1e-3) -> list[Effector]:
    """Effectors of a named set (:data:`EFFECTOR_SETS`) placed at the joints of ``pose_pos`` (J, 3)."""
    if name not in EFFECTOR_SETS:
        raise ValueError(f"unknown effector set {name!r}; valid: {', '.join(EFFECTOR_SETS)}")
    skeleton.require_roles(EFFECTOR_SETS[name], f"effector set {name!r}")
    pose_pos = np.asarray(pose_pos, dtype=float)
    return [Effector(role, pose_pos[skeleton.index(role)], tolerance=tolerance) for role in EFFECTOR_SETS[name]]


def base_on_target(pose: Pose, res: ResolvedEffectors, base: int) -> Pose:
    """``pose`` moved as a whole (every joint by the same vector) so that joint ``base`` meets the first position
    effector on it, or ``pose`` itself when no position effector is on ``base``.

    A solver that only turns joints keeps its base where the start put it, so a pinned pelvis (lesson 05's
    random effectors hold one in most cases) could never be met; moved first, it is met exactly and the
    solver turns the rest.

    Parameters
    ----------
    pose : Pose
    res : ResolvedEffectors
    base : int
        The joint the solver keeps in place (:func:`base_index`).
    """
    on_base = np.nonzero((np.asarray(res.joints) == base) & (np.asarray(res.codes) == 0))[0]
    if not len(on_base):
        return pose
    P = np.asarray(pose.global_pos, dtype=float)
    shift = np.asarray(res.position[on_base[0]], dtype=float) - P[base]
    if not np.any(shift):
        return pose
    lp = None if pose.local_pos is None else np.asarray(pose.local_pos, dtype=float).copy()
    if lp is not None:
        lp[0] += shift
    root = None if pose.root_pos is None else np.asarray(pose.root_pos, dtype=float) + shift
    return Pose(P + shift, pose.local_rot, root, lp)


def base_index(skeleton: Skeleton, base=None) -> int:
    """The joint a solver keeps in place: ``base`` if given, else the pelvis role, else joint 0."""
    return skeleton.index(base) if base is not None else skeleton.pelvis()


def check_pose(skeleton: Skeleton, start: Pose) -> np.ndarray:
    """Validate a start pose; returns its global positions (J, 3)."""
    if not isinstance(start, Pose):
        raise ValueError(f"expected a Pose as the start pose, got {type(start).__name__}")
    p = np.asarray(start.global_pos, dtype=float)
    if p.shape != (skeleton.n_joints, 3):
        raise ValueError(f"start pose: expected global_pos of shape ({skeleton.n_joints}, 3), got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError("start pose contains NaN or inf")
    return p
