"""A posing method's poses on held-out cases, scored with the same code for every method.

Introduced in ``notebooks/01_fabrik.ipynb`` (``posekit bench ik``); the learned solvers of lessons 03-05
are scored by it on the same cases (:mod:`posekit.data.cases`). Units: the pose metrics of
:mod:`posekit.data.metrics` reported in millimetres and degrees.

Metrics (per case)
------------------
* effector error — the worst effector of the case, by the solvers' one definition
  (:func:`posekit.ik.effector_errors.errors_of`): distance for position effectors (mm), angle for rotation
  and look-at effectors (degrees). Measured here on the returned pose, not taken from the solver's report;
* MPJPE, bone-length error, rotation error and naturalness — :mod:`posekit.data.metrics`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..data.metrics import NaturalnessIndex, bone_length_error, mpjpe, rotation_error
from ..ik.effector_errors import errors_of, position_errors
from ..ik.effectors import as_resolved
from ..kinematics import fk

__all__ = ["PoseScores", "score_poses", "case_effector_errors"]


def case_effector_errors(skeleton, effectors, global_pos, local_rot=None) -> tuple[np.ndarray, np.ndarray, bool]:
    """Errors of one returned pose against its effectors.

    Parameters
    ----------
    skeleton : Skeleton
    effectors : sequence of Effector, or ResolvedEffectors
    global_pos : ndarray, shape (J, 3), metres
    local_rot : ndarray, shape (J, 4), optional
        Local quaternions; without them the angular effectors' errors are NaN (a method that returns
        positions only cannot be judged on them) and the case does not count as converged.

    Returns
    -------
    position : ndarray, shape (K_pos,), metres
    angle : ndarray, shape (K_ang,), radians
    converged : bool
        Every effector within its tolerance.
    """
    res = as_resolved(skeleton, effectors)
    angular = res.codes != 0
    P = np.asarray(global_pos, dtype=float)
    if local_rot is None:
        if not angular.any():
            err, conv = errors_of(P, None, res)
            return err, np.empty(0), conv
        pos = position_errors(P[res.joints[~angular]], res.position[~angular])
        return pos, np.full(int(angular.sum()), np.nan), False
    G = fk(skeleton, np.asarray(local_rot, dtype=float))[1] if angular.any() else None  # rotations need no translations
    err, conv = errors_of(P, G, res)
    return err[~angular], err[angular], conv


@dataclass
class PoseScores:
    """Per-case metrics of one method on one set of cases (see the module docstring).

    Attributes
    ----------
    effector_mm : ndarray, shape (N,)
        Worst position effector of each case.
    effector_deg : ndarray, shape (N,) or None
        Worst angular effector (NaN for a case without one; None when no case has one the method can be judged
        on).
    mpjpe_mm, bone_mm : ndarray, shape (N,)
    rotation_deg : ndarray, shape (N,) or None
        None when the method returned no local rotations.
    natural_mm, natural_floor_mm : ndarray, shape (N,) or None
        None without a :class:`NaturalnessIndex`.
    converged : ndarray of bool, shape (N,)
        Every effector of the case within its tolerance (measured here, not as the solver says).
    """

    effector_mm: np.ndarray
    effector_deg: np.ndarray | None
    mpjpe_mm: np.ndarray
    bone_mm: np.ndarray
    rotation_deg: np.ndarray | None
    natural_mm: np.ndarray | None
    natural_floor_mm: np.ndarray | None
    converged: np.ndarray

    def summary(self) -> dict:
        """The benchmark's JSON keys: medians over cases, the worst case for bone lengths. The angular effector
        error's median is over the cases that hold an angular effector."""
        med = lambda a: None if a is None else float(np.median(a))
        deg = None
        if self.effector_deg is not None and np.any(np.isfinite(self.effector_deg)):
            deg = float(np.median(self.effector_deg[np.isfinite(self.effector_deg)]))
        out = {
            "effector_error_mm_median": med(self.effector_mm),
            "effector_error_deg_median": deg,
            "mpjpe_mm_median": med(self.mpjpe_mm),
            "bone_length_error_mm_max": float(np.max(self.bone_mm)),
            "rotation_error_deg_median": med(self.rotation_deg),
            "natural_mm_median": med(self.natural_mm),
            "natural_floor_mm_median": med(self.natural_floor_mm),
            "converged_fraction": float(np.mean(self.converged)),
        }
        return {k: v for k, v in out.items() if v is not None}


def score_poses(cases, result_pos, effectors, result_rot=None, natural: NaturalnessIndex | None = None,
                natural_floor=None) -> PoseScores:
    """Score a method's poses on :class:`posekit.data.cases.Cases`, with the same code for every method.

    Parameters
    ----------
    cases : Cases
    result_pos : ndarray, shape (N, J, 3), metres
    effectors : sequence of sequence of Effector
        The effectors of each case.
    result_rot : ndarray, shape (N, J, 4), optional
        Local quaternions the method returned (rotation error and angular effectors).
    natural : NaturalnessIndex, optional
    natural_floor : ndarray, shape (N,), metres, optional
        ``natural.distance(cases.target_pos)``, passed in when scoring many methods on the same cases.
    """
    s = cases.skeleton
    result_pos = np.asarray(result_pos, dtype=float)
    eff_mm, eff_deg, conv = [], [], []
    for i, effs in enumerate(effectors):
        rot = None if result_rot is None else result_rot[i]
        p, a, c = case_effector_errors(s, effs, result_pos[i], rot)
        eff_mm.append(p.max() * 1e3 if len(p) else 0.0)
        eff_deg.append(np.degrees(a.max()) if len(a) else np.nan)
        conv.append(c)
    eff_deg = np.array(eff_deg)
    rot_deg = None
    if result_rot is not None and cases.target_rot is not None:
        rot_deg = np.degrees(rotation_error(s, result_rot, cases.target_rot))
    nat = floor = None
    if natural is not None:
        nat = natural.distance(result_pos) * 1e3
        floor = (natural.distance(cases.target_pos) if natural_floor is None else np.asarray(natural_floor)) * 1e3
    return PoseScores(np.array(eff_mm), None if np.all(np.isnan(eff_deg)) else eff_deg,
                      mpjpe(s, result_pos, cases.target_pos) * 1e3,
                      bone_length_error(s, result_pos, cases.start_pos) * 1e3, rot_deg, nat, floor, np.array(conv))
