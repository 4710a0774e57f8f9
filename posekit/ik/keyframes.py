"""Key poses and in-betweens by IK: interpolate the effectors between keys, let a solver pose every frame.

Introduced in ``notebooks/06_posing_studio.ipynb`` (the studio's timeline). An animator sets a few *key*
effector setups; every frame between two keys gets effectors interpolated between theirs, and a solver
turns each frame's effectors into a pose, starting from the previous frame's pose so that the motion
stays continuous (a solver that needs no start, such as ProtoRes, predicts each frame on its own).

Interpolation of one effector from key ``a`` to key ``b`` at ``s`` in [0, 1] (``s = t`` for
``ease="linear"``, ``s = 3t^2 - 2t^3`` for ``ease="smooth"``, which starts and stops at rest):

* position and look-at targets, tolerances and weights: ``(1 - s) a + s b``;
* rotation targets: spherical linear interpolation (slerp) of the world orientations, the shorter way
  round; the look-at axis (the joint's own direction) is slerped the same way as a unit vector.

Both keys must hold the same effectors (joint and kind, in any order): a frame cannot half-have one.
Units: metres, radians; conventions: :mod:`posekit.conventions`.
"""

from __future__ import annotations

import numpy as np

from ..rotations import matrix_to_quat, quat_to_matrix
from .api import Effector, Pose
from .bone_rotations import pose_with_rotations
from .effectors import resolve_effectors

__all__ = ["interpolate_effectors", "inbetween_effectors", "solve_sequence", "write_poses_bvh", "slerp", "EASES"]

EASES = ("linear", "smooth")
"""Timing curves between keys."""


def slerp(q0, q1, s: float) -> np.ndarray:
    """Spherical linear interpolation of unit quaternions ``(x, y, z, w)``, shape (4,), the shorter way."""
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    d = float(q0 @ q1)
    if d < 0:  # q and -q are the same rotation: take the nearer one
        q1, d = -q1, -d
    if d > 0.9995:  # nearly equal: linear, renormalised
        q = q0 + s * (q1 - q0)
        return q / np.linalg.norm(q)
    theta = np.arccos(np.clip(d, -1.0, 1.0))
    return (np.sin((1 - s) * theta) * q0 + np.sin(s * theta) * q1) / np.sin(theta)


def _unit_slerp(a, b, s):
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    theta = np.arccos(np.clip(a @ b, -1.0, 1.0))
    if theta < 1e-6:
        return a.copy()
    return (np.sin((1 - s) * theta) * a + np.sin(s * theta) * b) / np.sin(theta)


def _key(skeleton, effectors, which):
    res = resolve_effectors(skeleton, effectors)  # checks joints, kinds and values, with its messages
    out = {}
    for k, e in enumerate(effectors):
        key = (int(res.joints[k]), e.kind)
        out[key] = (e, res.rotation[k] if e.kind == "rotation" else None)
    if len(out) != len(effectors):
        raise ValueError(f"{which} has two effectors of one kind on one joint")
    return out


def interpolate_effectors(skeleton, a, b, t: float, ease: str = "linear") -> list[Effector]:
    """The effectors a fraction ``t`` in [0, 1] of the way from key ``a`` to key ``b`` (see the module
    docstring); in ``a``'s order. Raises ValueError when the keys do not hold the same effectors."""
    if ease not in EASES:
        raise ValueError(f"unknown ease {ease!r}; valid: {', '.join(EASES)}")
    t = float(t)
    if not 0.0 <= t <= 1.0:
        raise ValueError(f"t must lie in [0, 1], got {t}")
    s = t if ease == "linear" else t * t * (3 - 2 * t)
    ka, kb = _key(skeleton, list(a), "the first key"), _key(skeleton, list(b), "the second key")
    if set(ka) != set(kb):
        name = lambda k: f"{skeleton.names[k[0]]} {k[1].replace('_', '-')}"  # noqa: E731
        only_a = ", ".join(name(k) for k in ka if k not in kb) or "nothing"
        only_b = ", ".join(name(k) for k in kb if k not in ka) or "nothing"
        raise ValueError(f"the two keys hold different effectors (only in the first: {only_a}; only in the "
                         f"second: {only_b}); every key of a timeline needs the same joints and kinds")
    out = []
    for key, (ea, ra) in ka.items():
        eb, rb = kb[key]
        tol = (1 - s) * ea.tolerance + s * eb.tolerance
        weight = (1 - s) * ea.weight + s * eb.weight
        if ea.kind == "rotation":
            q = slerp(matrix_to_quat(ra), matrix_to_quat(rb), s)
            out.append(Effector(ea.joint, quat_to_matrix(q), "rotation", tolerance=tol, weight=weight))
        else:
            target = (1 - s) * ea.target + s * eb.target
            axis = None if ea.kind != "look_at" else _unit_slerp(ea.axis, eb.axis, s)
            out.append(Effector(ea.joint, target, ea.kind, tolerance=tol, weight=weight, axis=axis))
    return out


def inbetween_effectors(skeleton, keys, inbetweens: int, ease: str = "linear") -> list[list[Effector]]:
    """Every frame's effectors: each key, then ``inbetweens`` interpolated frames, up to the last key.

    Returns ``(len(keys) - 1) * (inbetweens + 1) + 1`` lists (the keys themselves at frames
    ``0, inbetweens + 1, ...``)."""
    keys = [list(k) for k in keys]
    if len(keys) < 2:
        raise ValueError(f"a timeline needs at least two keys, got {len(keys)}")
    if int(inbetweens) != inbetweens or inbetweens < 0:
        raise ValueError(f"inbetweens must be a whole number >= 0, got {inbetweens!r}")
    frames = []
    n = int(inbetweens) + 1
    for k in range(len(keys) - 1):
        for i in range(n):
            frames.append(keys[k] if i == 0 else interpolate_effectors(skeleton, keys[k], keys[k + 1], i / n, ease))
    frames.append(keys[-1])
    return frames


def solve_sequence(solver, start: Pose, frames, progress: bool = False):
    """Pose every frame's effectors with ``solver``, each from the previous frame's pose.

    Parameters
    ----------
    solver : Solver
    start : Pose
        The first frame's start (ignored by a solver with ``needs_start = False``).
    frames : list of list of Effector
    progress : bool
        Show a progress bar (``tqdm.auto``).

    Returns
    -------
    list of IKResult
        One per frame.
    """
    frames = list(frames)
    it = frames
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(frames, desc="in-betweens", unit="frame")
    needs = getattr(solver, "needs_start", True)
    results, current = [], start
    for effs in it:
        res = solver.solve(current if needs else None, effs)
        results.append(res)
        current = res.pose  # every solver returns what its own next solve needs (rotations if it uses them)
    return results


def write_poses_bvh(path, skeleton, poses, reference: Pose, frame_time: float = 1 / 30, order: str = "ZXY"):
    """Write solved poses (one or an animation) as a BVH file that reads back to the same positions.

    Parameters
    ----------
    path : str or Path
    skeleton : Skeleton
    poses : list of Pose
        One per frame. Poses without rotations (FABRIK's) get them from the previous frame's (the first
        from ``reference``) by :func:`posekit.ik.bone_rotations.pose_with_rotations`; joints whose bone a
        rotation cannot place get position channels (every frame writes the same channel layout).
    reference : Pose
        A pose with rotations (the solve's start).
    frame_time : float, seconds

    Returns
    -------
    list of Pose
        What was written, with rotations: FK of its rotations (and translations) is each pose's positions.
    """
    from ..io.bvh import write_bvh

    poses = list(poses)
    if not poses:
        raise ValueError("no poses to write")
    if not np.isfinite(frame_time) or frame_time <= 0:
        raise ValueError(f"frame_time must be a positive number of seconds, got {frame_time!r}")
    written, prev = [], reference
    for p in poses:
        prev = pose_with_rotations(skeleton, p, prev)
        written.append(prev)
    J = skeleton.n_joints
    local_pos = np.stack([np.array(skeleton.offsets, float) if w.local_pos is None else np.asarray(w.local_pos, float)
                          for w in written])
    local_pos[:, 0] = np.stack([w.root_pos for w in written])
    moves = np.linalg.norm(local_pos - np.asarray(skeleton.offsets, float), axis=-1).max(0) > 1e-9
    rot = tuple(f"{a}rotation" for a in order.upper())
    position = ("Xposition", "Yposition", "Zposition")
    channels = [position + rot] + [(position + rot) if moves[j] else rot for j in range(1, J)]
    write_bvh(path, skeleton, np.stack([w.local_rot for w in written]), frame_time, local_pos=local_pos,
              channels=channels, order=order)
    return written
