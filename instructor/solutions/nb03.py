"""Reference solutions of lesson 03's exercises (instructor version; ``posekit exercises solutions 03`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_pose_vector", "exercise_tied_decoder", "exercise_solver_loss"]


def exercise_pose_vector(skeleton, global_pos):
    """One pose as the feature vector of the networks: its body joints in the root frame (Victor et al. 2021,
    Sec. 3.2).

    The root frame has its origin at the pelvis projected on the floor and faces +Z: subtract the
    origin, then turn by minus the facing angle about the vertical. A helper root that is not part of the
    body (Bandai's ``joint_Root``) is left out.

    Parameters
    ----------
    skeleton : Skeleton
        Needs the ``pelvis`` role and the hip (and shoulder) roles of the facing direction.
    global_pos : ndarray, shape (J, 3), metres

    Returns
    -------
    ndarray, shape (3 B,), metres
        The B body joints in the root frame, joint by joint (``x[3 i : 3 i + 3]`` is body joint ``i``).
    """
    import numpy as np

    from posekit.transforms import facing_angle

    P = np.asarray(global_pos, dtype=float)
    pelvis = skeleton.index("pelvis")
    origin = P[pelvis] * np.array([1.0, 0.0, 1.0])  # the pelvis on the floor: y = 0, height is kept
    angle = float(facing_angle(skeleton, P))         # radians about +Y, from +Z to the facing direction

    # rotation by -angle about +Y, so that the facing direction (sin a, 0, cos a) becomes +Z
    c, s = np.cos(angle), np.sin(angle)
    turn = np.array([[c, 0.0, -s],
                     [0.0, 1.0, 0.0],
                     [s, 0.0, c]])
    local = (P - origin) @ turn.T  # each row p -> turn @ p

    # body joints: all of them, except the root when the root is a helper above the pelvis
    body = np.arange(1, skeleton.n_joints) if pelvis != 0 else np.arange(skeleton.n_joints)
    return local[body].ravel()


def exercise_tied_decoder(z, W1, W2, W3):
    """The tied decoder of the authors' code (Victor et al. 2021, Sec. 3.3.1): ``D(z) = W1^T relu(W2^T relu(W3^T z))``.

    The decoder reuses the encoder's weight matrices transposed and has no biases. With codes as rows,
    ``W^T z`` for every code is ``z @ W``.

    Parameters
    ----------
    z : ndarray, shape (N, d)
        Latent codes.
    W1 : ndarray, shape (H, F)
        First encoder layer's weight, torch's (out, in) layout.
    W2 : ndarray, shape (H, H)
    W3 : ndarray, shape (d, H)

    Returns
    -------
    ndarray, shape (N, F)
        Decoded (z-scored) poses.
    """
    import numpy as np

    h2 = np.maximum(z @ W3, 0.0)   # relu(W3^T z), (N, H)
    h1 = np.maximum(h2 @ W2, 0.0)  # relu(W2^T h2), (N, H)
    return h1 @ W1                 # W1^T h1, linear, (N, F)


def exercise_solver_loss(decoded, target, columns, k):
    """Eq. (1) of Victor et al. 2021: ``MSE_t(D(z'), x_target) + k MSE_not_t(D(z'), x_target)``.

    The mean squared error over the target joints' feature columns, plus ``k`` times the mean squared
    error over all other features (z-scored units).

    Parameters
    ----------
    decoded : ndarray, shape (N, F)
        Decoded poses ``D(z')``.
    target : ndarray, shape (N, F)
        The true target poses.
    columns : sequence of int, length 3 K
        Feature columns of the target joints.
    k : float
        Weight of the other features (0.01 in the lesson).

    Returns
    -------
    float
    """
    import numpy as np

    se = (np.asarray(decoded) - np.asarray(target)) ** 2  # squared error of every feature, (N, F)
    on = np.zeros(se.shape[1], dtype=bool)
    on[list(columns)] = True                                # True on the target joints' columns
    mse_targets = se[:, on].mean()
    mse_others = se[:, ~on].mean() if np.any(~on) else 0.0  # a mean per group, not over all features
    return float(mse_targets + k * mse_others)
