"""An "animator": key poses on the rig's controls with smooth in-betweens, as training and test clips.

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb``. Training clips keep to moderate poses
with a key every ``key_every`` frames; test clips are larger, faster and more extreme (as the
held-out sequences of Holden, Saito & Komura 2017) — hands may even be placed out of reach.
"""

from __future__ import annotations

import numpy as np

from .humanoid import HumanoidRig

__all__ = ["animate", "standard_sets"]


def _key(rig: HumanoidRig, prev, rng, extreme):
    """One key pose: torso controls drawn around the previous key, hands and feet placed around the
    shoulders and hips of that torso."""
    y = rig.default()
    i = rig.index
    e = extreme
    y[i("root_tx")] = np.clip(prev[i("root_tx")] + rng.normal(0, 0.25 * e), -1.5, 1.5)
    y[i("root_tz")] = np.clip(prev[i("root_tz")] + rng.normal(0, 0.25 * e), -1.5, 1.5)
    y[i("root_ty")] = rng.uniform(-0.22 * e, 0.04)
    y[i("root_yaw")] = prev[i("root_yaw")] + rng.normal(0, 0.4 * e)
    for name, sd in (("root_roll", 0.08), ("root_pitch", 0.15), ("spine_lower_bend", 0.15),
                     ("spine_upper_bend", 0.2), ("spine_side", 0.12), ("spine_twist", 0.25),
                     ("neck_nod", 0.2), ("neck_turn", 0.35), ("neck_tilt", 0.12),
                     ("l_elbow_swivel", 0.3), ("r_elbow_swivel", 0.3), ("l_knee_swivel", 0.15),
                     ("r_knee_swivel", 0.15), ("l_foot_pitch", 0.2), ("r_foot_pitch", 0.2)):
        y[i(name)] = rng.normal(0, sd * e)
    y = np.clip(y, rig.low, rig.high)
    pos = rig.evaluate(y)  # shoulders and hips do not depend on the hand and foot handles
    sk = rig.skeleton
    yaw = y[i("root_yaw")]
    fwd = np.array([np.sin(yaw), 0.0, np.cos(yaw)])
    for side, full in (("l", "left"), ("r", "right")):
        S = pos[sk.index(f"{full}_shoulder")]
        arm = sk.bone_lengths()[[sk.index(f"{full}_elbow"), sk.index(f"{full}_hand")]].sum()
        d = 0.6 * fwd + np.array([0.0, -0.6, 0.0]) + rng.normal(0, 0.6 * e, 3)
        reach = arm * min(rng.uniform(0.45, 0.95) * (1 + 0.1 * (e - 1)), 1.05)
        y[[i(f"{side}_hand_{a}") for a in "xyz"]] = S + d / np.linalg.norm(d) * reach
        H = pos[sk.index(f"{full}_hip")]
        leg = sk.bone_lengths()[[sk.index(f"{full}_knee"), sk.index(f"{full}_foot")]].sum()
        side_step = rng.normal(0, 0.08 * e, 3) * np.array([1.0, 0.0, 1.0]) + fwd * rng.normal(0, 0.12 * e)
        foot = H + np.array([0.0, -leg * rng.uniform(0.86, 0.99), 0.0]) + side_step
        foot[1] = max(foot[1], 0.04)
        y[[i(f"{side}_foot_{a}") for a in "xyz"]] = foot
    return np.clip(y, rig.low, rig.high)


def animate(rig: HumanoidRig, n_clips: int, frames: int = 200, key_every: int = 20, extreme: float = 1.0,
            seed: int = 0):
    """Generate clips of rig controls.

    Parameters
    ----------
    n_clips, frames : int
        Number of clips and frames per clip.
    key_every : int
        Frames between key poses (smaller is faster motion).
    extreme : float
        Scales how far keys stray (1 for training; the test clips use more).
    seed : int

    Returns
    -------
    controls : ndarray, shape (n_clips * frames, C)
    clip_id : ndarray of int, shape (n_clips * frames,)
    """
    rng = np.random.default_rng(seed)
    out, ids = [], []
    for c in range(n_clips):
        n_keys = frames // key_every + 2
        keys = [rig.default()]
        for _ in range(n_keys):
            keys.append(_key(rig, keys[-1], rng, extreme))
        keys = np.array(keys[1:])
        # smoothstep in-betweens between consecutive keys
        t = np.arange(frames) / key_every
        k = np.minimum(t.astype(int), len(keys) - 2)
        s = t - k
        s = s * s * (3 - 2 * s)
        clip = keys[k] * (1 - s[:, None]) + keys[k + 1] * s[:, None]
        out.append(np.clip(clip, rig.low, rig.high))
        ids.append(np.full(frames, c))
    return np.concatenate(out), np.concatenate(ids)


def standard_sets(rig: HumanoidRig, seed: int = 0):
    """The animation data of lesson 02 and its benchmark, seeded.

    Returns
    -------
    train : ndarray, shape (4000, C)
        20 clips of 200 frames, a key every 20 frames, ``extreme=1``.
    test : ndarray, shape (1000, C)
        5 clips of 200 frames, a key every 10 frames, ``extreme=1.6`` (larger, faster, more extreme).
    test_clip : ndarray of int, shape (1000,)
    """
    train, _ = animate(rig, 20, 200, key_every=20, extreme=1.0, seed=seed)
    test, test_clip = animate(rig, 5, 200, key_every=10, extreme=1.6, seed=seed + 1)
    return train, test, test_clip
