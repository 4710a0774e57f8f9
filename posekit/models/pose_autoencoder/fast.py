"""Compiled single-pose path of the neural solver (:mod:`posekit.models.pose_autoencoder.solver`).

Introduced in ``notebooks/03_autoencoder_solvers.ipynb``. For one pose the networks are a dozen
small matrix-vector products; numpy's and torch's per-call overhead would cost several times the
arithmetic, so one solve runs in these numba kernels instead. They compute exactly what the batched
numpy path computes (:func:`posekit.data.pose_vectors.pose_vectors`, the networks of
:class:`posekit.models.pose_autoencoder.networks.NumpyAESolvers`, :func:`posekit.data.pose_vectors.poses_from_vectors`);
``tests/models/test_pose_autoencoder.py`` checks that they agree.
"""

from __future__ import annotations

import math

import numpy as np

from ..._jit import njit

__all__ = ["root_frame", "features", "mlp", "pose_from_features"]


@njit
def root_frame(pos, pel, lh, rh, ls, rs):
    """Root frame of one pose (J, 3): origin (pelvis on the floor) x, z and cos, sin of the facing angle
    (:func:`posekit.transforms.facing_angle`: ``across = (l_hip - r_hip) + (l_shoulder - r_shoulder)``,
    forward = ``across x up``). ``ls``/``rs`` -1: no shoulders."""
    ax = pos[lh, 0] - pos[rh, 0]
    az = pos[lh, 2] - pos[rh, 2]
    if ls >= 0:
        ax += pos[ls, 0] - pos[rs, 0]
        az += pos[ls, 2] - pos[rs, 2]
    angle = math.atan2(-az, ax)
    return pos[pel, 0], pos[pel, 2], math.cos(angle), math.sin(angle)


@njit
def features(pos, body, ox, oz, c, s, mean, std, out):
    """z-scored root-frame features of body joints ``body`` into ``out`` (3B,) float32."""
    for i in range(len(body)):
        j = body[i]
        x, y, z = pos[j, 0] - ox, pos[j, 1], pos[j, 2] - oz
        out[3 * i] = (c * x - s * z - mean[3 * i]) / std[3 * i]
        out[3 * i + 1] = (y - mean[3 * i + 1]) / std[3 * i + 1]
        out[3 * i + 2] = (s * x + c * z - mean[3 * i + 2]) / std[3 * i + 2]


@njit
def targets(points, ox, oz, c, s, mean, std, lo, hi, out, clamped):
    """Target points (K, 3) world -> z-scored root-frame values ``out`` (3K,) (``mean``/``std``/``lo``/
    ``hi``: the features of those joints), clamped to [lo, hi]; ``clamped`` (K,) flags the clamped ones."""
    for k in range(points.shape[0]):
        x, y, z = points[k, 0] - ox, points[k, 1], points[k, 2] - oz
        v = (c * x - s * z, y, s * x + c * z)
        clamped[k] = False
        for a in range(3):
            i = 3 * k + a
            w = (v[a] - mean[i]) / std[i]
            if w < lo[i]:
                w, clamped[k] = lo[i], True
            elif w > hi[i]:
                w, clamped[k] = hi[i], True
            out[i] = w


@njit
def mlp(h, weights, biases, relu_last):
    """``h`` (n,) through layers ``h <- h @ W + b`` with ReLU between (and after the last when
    ``relu_last``); empty biases mean none (the tied decoder)."""
    n = len(weights)
    for i in range(n):
        h = np.dot(h, weights[i])
        if biases[i].shape[0] > 0:
            h += biases[i]
        if i < n - 1 or relu_last:
            h = np.maximum(h, np.float32(0.0))
    return h


@njit
def pose_from_features(x, body, chain, chain_offsets, n_joints, ox, oz, c, s, mean, std):
    """Global positions (J, 3) from z-scored features ``x`` (3B,); the placement joints ``chain`` (from the
    pelvis up to the root) are put at their offsets below it (``chain_offsets`` (P, 3): each joint's
    offset from its parent)."""
    local = np.zeros((n_joints, 3))
    for i in range(len(body)):
        for a in range(3):
            local[body[i], a] = x[3 * i + a] * std[3 * i + a] + mean[3 * i + a]
    for k in range(len(chain) - 1):
        for a in range(3):
            local[chain[k + 1], a] = local[chain[k], a] - chain_offsets[k, a]
    out = np.empty((n_joints, 3))
    for j in range(n_joints):
        x_, z_ = local[j, 0], local[j, 2]
        out[j, 0] = c * x_ + s * z_ + ox
        out[j, 1] = local[j, 1]
        out[j, 2] = -s * x_ + c * z_ + oz
    return out
