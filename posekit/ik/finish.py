"""A learned pose with an exact finish: a learned solver's pose, then damped least squares until every effector
of every kind is met.

Introduced in ``notebooks/06_posing_studio.ipynb``; registered as ``"<learned>+dls"`` for each learned solver
(``"neural+dls"``, ``"latent-opt+dls"``, ``"protores+dls"``), so a user sees both parts in the name.

Why two stages. A learned solver (lessons 03-05) proposes a *plausible* whole pose from a few effectors — its
prior fills in the joints no effector constrains — but misses its effectors by millimetres to centimetres. DLS
(:mod:`posekit.ik.dls`) meets effectors of all three kinds exactly, but from a poor start it bends whatever joints
reach the targets fastest. Started from the learned pose, DLS only has to close the learned solver's small
misses, so the pose keeps most of what the prior chose (DLS's damping keeps each step small: it changes the
learned pose as little as it must).

The stages
----------
1. the learned solver is given the effectors of the kinds it honours (``"protores"``: all three; the lesson 03
   and 04 solvers: positions), from the start pose when it needs one;
2. a positions-only learned pose gets rotations that turn the start's bones onto its positions
   (:func:`posekit.ik.bone_rotations.rotations_from_positions`; bone lengths are the skeleton's); DLS moves
   it as a whole onto a position effector on its base joint (the pelvis) first, as every solver that keeps a
   base in place does (:func:`posekit.ik.api.base_on_target`);
3. :class:`~posekit.ik.dls.DLSSolver` from that pose with every effector, and DLS from the start pose as well:
   two answers, each meeting the effectors (or not);
4. ``choose="natural"`` (default): when both meet every effector, the more natural is kept — the one nearer a
   training pose (:class:`posekit.data.metrics.NaturalnessIndex` over :data:`JUDGE_POSES` training frames: a
   nearest-neighbour prior on the data the learned prior was made from); when one meets them, that one; when
   neither, the one nearer its effectors. The training poses are those of the data being posed when a caller
   names it (:func:`judged_on`: ``posekit bench ik`` and ``bench all`` name ``--data``'s training split, the one
   ``posekit train --data`` trains on), else those the learned solver was registered with (the Bandai mini set's
   for the shipped models); with neither on the skeleton there is no judge and the rule is ``"learned"``
   (:attr:`FinishedSolver.choose` says which ran). ``choose="learned"``: the answer from the learned pose unless
   DLS got stuck there (a limb stretched to its end, a local minimum) and the start's answer is no worse.
   ``info["kept"] = "start"`` when the start's answer is kept.

Why judge two answers. From a start that already resembles the target (the rest pose, five effectors on the
body's ends), DLS from the start alone is often a better pose than the learned one finished; elsewhere the
learned pose is. Neither is better everywhere; keeping the one nearer the training poses lands nearer the true
pose, in the median over held-out poses, for every finish under both starts of lesson 06's comparison of the two
rules (five effectors).

``info`` says what each stage did: ``learned_ms`` and ``finish_ms`` (wall clock; the finish counts both DLS
runs and the judge), ``learned_converged``, ``finish_iterations`` and, when the judge chose, ``natural_mm``
(the two answers' distances to the nearest training pose: from the learned pose, from the start). Targets DLS
cannot meet (out of reach, conflicting) give the best pose it found; when that pose is further from the
effectors than the learned one (its worst effector, each kind in its own unit: position errors in metres, angles
in radians, compared kind by kind), the learned pose is returned instead and ``info["kept"] = "learned"`` says
so. Never NaN, never a hang: both stages have iteration limits.
"""

from __future__ import annotations

import contextlib
import time
from dataclasses import replace

import numpy as np

from .api import IKResult, SolverBase
from .bone_rotations import rotations_from_positions
from .dls import DLSSolver
from .effectors import KINDS, ResolvedEffectors
from .registry import make_solver, register, solver_info
from ..records import Pose
from ..rotations import matrix_to_quat, quat_to_matrix

__all__ = ["FinishedSolver", "finished_name", "FINISHED", "CHOICES", "JUDGE_POSES", "judge_for", "judged_on"]

FINISHED = ("neural", "latent-opt", "protores")
"""The learned solvers (lessons 03, 04, 05) registered with an exact finish, ``NAME+dls``."""

CHOICES = ("natural", "learned")
"""How the finish picks between its two answers (the module docstring, step 4)."""

JUDGE_POSES = 2000
"""Training poses the judge compares an answer with (a seeded subset: a query costs about 0.1 ms)."""

_JUDGES: dict = {}


def judge_for(data: str | None, skeleton):
    """The naturalness judge of a learned solver trained on ``data`` (a data set's name): a
    :class:`~posekit.data.metrics.NaturalnessIndex` over :data:`JUDGE_POSES` of its training frames
    (:func:`posekit.data.cases.case_split`, the split the learned solvers were trained on; never a held-out
    frame), built once per data set. None when there is no such set or its skeleton is not ``skeleton``."""
    if not data:
        return None
    if data not in _JUDGES:
        from ..data.cases import case_split
        from ..data.metrics import NaturalnessIndex
        from ..data.sources import open_dataset

        motions = open_dataset(data)
        train = case_split(motions)[0]
        _JUDGES[data] = (motions.skeleton, NaturalnessIndex(motions.skeleton, motions.global_pos[train],
                                                            max_poses=JUDGE_POSES, seed=0))
    trained_on, index = _JUDGES[data]
    return index if trained_on.same_as(skeleton) else None


_JUDGED_ON: list = []
"""The data :func:`judged_on` names, innermost last: ``[skeleton, source, frames, index or None]``."""


@contextlib.contextmanager
def judged_on(motions, train_frames=None):
    """Within the block, an exact finish made for ``motions``' skeleton judges its two answers against training
    poses of ``motions``: a :class:`~posekit.data.metrics.NaturalnessIndex` over :data:`JUDGE_POSES` of
    ``motions.global_pos[train_frames]`` (built when a finish first needs it).

    Parameters
    ----------
    motions : MotionSet
        The data being posed (``posekit bench ik --data``).
    train_frames : ndarray of int, optional
        Its training frames; default the split the learned models train on
        (:func:`posekit.data.cases.case_split`, as ``posekit train --data`` splits it). Never held-out frames.
    """
    if train_frames is None:
        from ..data.cases import case_split

        train_frames = case_split(motions)[0]
    _JUDGED_ON.append([motions.skeleton, motions.source, motions.global_pos[np.asarray(train_frames)], None])
    try:
        yield
    finally:
        _JUDGED_ON.pop()


def _judge(data: str | None, skeleton) -> tuple:
    """``(index, source)``: the judge of a finish on ``skeleton`` whose learned solver was registered with
    ``data`` (the innermost :func:`judged_on` on this skeleton, else :func:`judge_for`), or ``(None, None)``."""
    for entry in reversed(_JUDGED_ON):
        if entry[0].same_as(skeleton):
            if entry[3] is None:
                from ..data.metrics import NaturalnessIndex

                entry[3] = NaturalnessIndex(entry[0], entry[2], max_poses=JUDGE_POSES, seed=0)
            return entry[3], entry[1]
    index = judge_for(data, skeleton)
    return (index, data) if index is not None else (None, None)


def finished_name(learned: str) -> str:
    """The registered name of ``learned`` with the exact finish: ``"protores"`` -> ``"protores+dls"``."""
    return f"{learned}+dls"


def _subset(res: ResolvedEffectors, keep) -> ResolvedEffectors:
    """The effectors of ``res`` where ``keep`` (K,) is True."""
    keep = np.asarray(keep, bool)
    idx = np.nonzero(keep)[0]
    return replace(res, joints=res.joints[idx], kinds=tuple(res.kinds[i] for i in idx), codes=res.codes[idx],
                   position=res.position[idx], rotation=res.rotation[idx], axis=res.axis[idx],
                   tolerance=res.tolerance[idx], weight=res.weight[idx],
                   names=tuple(res.names[i] for i in idx) if res.names else ())


def _worse(finished: np.ndarray, learned: np.ndarray, codes: np.ndarray) -> bool:
    """Whether the finished errors are worse than the learned ones: a larger worst error of some kind."""
    for c in np.unique(codes):
        sel = codes == c
        if finished[sel].max() > learned[sel].max() + 1e-12:
            return True
    return False


class FinishedSolver(SolverBase):
    """A registered learned solver followed by DLS from its pose (see the module docstring).

    Parameters
    ----------
    skeleton : Skeleton
    learned : str
        A registered learned solver's name (``"neural"``, ``"latent-opt"``, ``"protores"`` ...).
    max_iter : int
        DLS iterations of the finish.
    choose : {"natural", "learned"}
        Which of the two answers is kept (the module docstring, step 4). ``"natural"`` needs training poses of
        this skeleton (:func:`judged_on`, else the learned solver's registered data, :func:`judge_for`); without
        them the rule is ``"learned"``, and :attr:`choose` says so.

    Attributes
    ----------
    choose : str
        The rule that runs: ``"natural"`` only when a judge exists.
    judged_on : str or None
        The data whose training poses judge (a data set's source), None without a judge.
    **learned_options
        Passed to the learned solver (``make_solver(learned, skeleton, **learned_options)``).
    """

    kinds = KINDS

    def __init__(self, skeleton, learned: str, max_iter: int = 100, choose: str = "natural", **learned_options):
        if choose not in CHOICES:
            raise ValueError(f"choose must be one of {', '.join(CHOICES)}, got {choose!r}")
        self.skeleton = skeleton
        self.learned = make_solver(learned, skeleton, **learned_options)
        self.finisher = DLSSolver(skeleton, max_iter=max_iter)
        self.name = finished_name(learned)
        self.judge, self.judged_on = _judge(solver_info(learned).data, skeleton) if choose == "natural" \
            else (None, None)
        self.choose = "natural" if self.judge is not None else "learned"
        self.needs_start = self.learned.needs_start
        self.batch_atol = max(self.learned.batch_atol, 1e-9) * 10

    def _solve(self, start, res) -> IKResult:
        t0 = time.perf_counter()
        mine = np.array([k in self.learned.kinds for k in res.kinds])
        if mine.any():
            try:
                lr = self.learned.solve(start, _subset(res, mine))
            except ValueError as err:  # no learned pose to finish: say whose refusal it is, and what answers
                others = ", ".join(repr(finished_name(n)) for n in FINISHED if n != self.learned.name)
                raise ValueError(f"{self.name}: its learned stage {self.learned.name!r} cannot read these effectors, "
                                 f"so there is no learned pose to finish ({err}); 'dls' alone, or a finish whose "
                                 f"learned stage reads any set ({others}), answers them") from None
            pose, learned_conv = lr.pose, bool(lr.converged) and mine.all()
        else:  # nothing the learned solver reads: the finish starts from the start pose
            pose, learned_conv = start, False
        if pose.local_rot is None:  # a positions-only learned pose: rotations that put the start's bones there
            L, root = rotations_from_positions(self.skeleton, quat_to_matrix(np.asarray(start.local_rot, float))[None],
                                               np.asarray(pose.global_pos, float)[None, 0],
                                               np.asarray(pose.global_pos, float)[None])
            pose = Pose.from_rotations(self.skeleton, matrix_to_quat(L[0]), root[0])
        t1 = time.perf_counter()
        fr = self.finisher.solve(pose, res)
        t2 = time.perf_counter()
        info = {"learned_ms": (t1 - t0) * 1e3, "finish_ms": (t2 - t1) * 1e3, "learned_converged": learned_conv,
                "finish_iterations": fr.iterations}
        has_start = start is not None and start.local_rot is not None
        if has_start and (self.judge is not None or not fr.converged):  # the second answer: DLS from the start
            fs = self.finisher.solve(start, res)
            if fr.converged and fs.converged and self.judge is not None:  # both exact: the more natural
                d = self.judge.distance(np.stack([fr.pose.global_pos, fs.pose.global_pos]))
                info["natural_mm"] = (float(d[0]) * 1e3, float(d[1]) * 1e3)
                take = bool(d[1] < d[0])
            else:  # the one that meets its effectors; when neither, the start's unless it is further off
                take = fs.converged if fr.converged or fs.converged else not _worse(
                    fs.effector_error, fr.effector_error, res.codes)
            info["finish_ms"] = (time.perf_counter() - t1) * 1e3
            if take:
                info["kept"] = "start"
                fr = fs
        if not fr.converged:
            before = self.result(pose, res, 0)
            if _worse(fr.effector_error, before.effector_error, res.codes):
                info["kept"] = "learned"
                return self.result(pose, res, fr.iterations, info)
        return self.result(fr.pose, res, fr.iterations, info)


def _factory(learned):
    def make(skeleton, **options):
        return FinishedSolver(skeleton, learned, **options)

    make.__name__ = f"finished_{learned.replace('-', '_')}"
    return make


def register_finished(learned: str):
    """Register ``learned+dls`` (every effector kind; a start pose when the learned solver needs one)."""
    info = solver_info(learned)
    register(finished_name(learned), _factory(learned), kinds=KINDS, needs_start=info.needs_start,
             description=f"{learned}, then DLS from its pose until every effector is met (an exact finish)",
             lesson="notebooks/06_posing_studio.ipynb", data=info.data)


for _name in FINISHED:
    register_finished(_name)
