"""Analytic two-bone IK: the law of cosines for a shoulder-elbow-wrist or hip-knee-ankle chain.

Introduced at the start of ``notebooks/01_fabrik.ipynb``; the procedural rig of lesson 02 uses it
for its limb controls. Conventions: :mod:`posekit.conventions`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["two_bone_ik"]


def two_bone_ik(root, mid, end, target, pole, eps: float = 1e-6):
    """Place the middle and end joints of a two-bone chain so the end reaches ``target``.

    With bone lengths ``l1 = |mid - root|``, ``l2 = |end - mid|`` and ``d = |target - root|`` clamped
    to the reachable range ``[|l1 - l2|, l1 + l2]``, the angle at the root between the root-target
    line and the first bone is (law of cosines)

        cos(alpha) = (l1^2 + d^2 - l2^2) / (2 l1 d),

    and the middle joint bends towards ``pole`` (e.g. in front of the knee).

    Parameters
    ----------
    root, mid, end : ndarray, shape (..., 3), metres
        Current joint positions (they give the bone lengths).
    target : ndarray, shape (..., 3)
    pole : ndarray, shape (..., 3)
        A point the middle joint should bend towards.

    Returns
    -------
    mid, end : ndarray, shape (..., 3)
        New positions; ``end`` equals ``target`` whenever it is reachable.
    reached : ndarray of bool, shape (...)
    """
    root, mid, end, target, pole = (np.asarray(x, dtype=float) for x in (root, mid, end, target, pole))
    for name, x in (("root", root), ("mid", mid), ("end", end), ("target", target), ("pole", pole)):
        if x.shape[-1:] != (3,) or not np.all(np.isfinite(x)):
            raise ValueError(f"{name}: expected finite values of shape (..., 3), got {x.shape}")
    l1 = np.linalg.norm(mid - root, axis=-1)
    l2 = np.linalg.norm(end - mid, axis=-1)
    if np.any(l1 < eps) or np.any(l2 < eps):
        raise ValueError("two_bone_ik: a bone has zero length")
    to_t = target - root
    dist = np.linalg.norm(to_t, axis=-1)
    lo, hi = np.abs(l1 - l2) + eps, l1 + l2 - eps
    d = np.clip(dist, lo, hi)
    reached = (dist >= lo) & (dist <= hi)
    u = to_t / np.maximum(dist, eps)[..., None]
    # bend direction: the pole made perpendicular to the root-target line
    v = pole - root
    v = v - np.sum(v * u, axis=-1, keepdims=True) * u
    nv = np.linalg.norm(v, axis=-1, keepdims=True)
    fallback = mid - root  # pole on the line: keep the current bend plane
    fallback = fallback - np.sum(fallback * u, axis=-1, keepdims=True) * u
    v = np.where(nv > eps, v / np.maximum(nv, eps),
                 fallback / np.maximum(np.linalg.norm(fallback, axis=-1, keepdims=True), eps))
    cos_a = np.clip((l1**2 + d**2 - l2**2) / (2 * l1 * d), -1.0, 1.0)
    sin_a = np.sqrt(1.0 - cos_a**2)
    new_mid = root + l1[..., None] * (cos_a[..., None] * u + sin_a[..., None] * v)
    new_end = root + d[..., None] * u
    return new_mid, new_end, reached
