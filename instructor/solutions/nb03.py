"""Reference solutions of lesson 03's exercises (instructor version; ``posekit exercises solutions 03`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_pose_vector", "exercise_pose_from_vector", "exercise_authors_loss"]


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


def exercise_pose_from_vector(skeleton, x, origin, angle):
    """A pose vector back to a pose in the world: exercise 1 undone (Victor et al. 2021, Sec. 3.2).

    The vector holds the B body joints in the root frame, joint by joint. Put them in their rows, place a helper
    root (a joint above the pelvis, Bandai's ``joint_Root``) at its rest offset from the pelvis — the joints above
    the pelvis do not rotate — then turn everything back by ``+angle`` about +Y and add the root frame's origin.

    Parameters
    ----------
    skeleton : Skeleton
    x : ndarray, shape (3 B,), metres
    origin : ndarray, shape (3,), metres
        The pelvis on the floor, where the root frame was taken.
    angle : float
        The facing angle, radians about +Y, from +Z to the facing direction.

    Returns
    -------
    ndarray, shape (J, 3), metres
    """
    import numpy as np

    pelvis = int(skeleton.pelvis())
    above = []                                   # the joints above the pelvis, nearest first
    j = pelvis
    while j != 0:
        j = int(skeleton.parents[j])
        above.append(j)
    body = [j for j in range(skeleton.n_joints) if j not in above]
    local = np.zeros((skeleton.n_joints, 3))
    local[body] = np.asarray(x, dtype=float).reshape(len(body), 3)
    child = pelvis
    for j in above:                              # each helper at its child's rest offset below the child
        local[j] = local[child] - skeleton.offsets[child]
        child = j
    c, s = np.cos(float(angle)), np.sin(float(angle))
    turn = np.array([[c, 0.0, s],                # rotation by +angle about +Y: +Z goes to (sin a, 0, cos a)
                     [0.0, 1.0, 0.0],
                     [-s, 0.0, c]])
    return local @ turn.T + np.asarray(origin, dtype=float)


def exercise_authors_loss(decoded, target, columns, w):
    """The authors' code's solver loss: one weighted mean over all features, its gradient, and its ``k``.

    ``L = mean_{n,c} m_c (decoded_nc - target_nc)^2`` with ``m_c = w`` on the ``T`` target columns and 1 on the
    ``F - T`` others; ``dL/d decoded = 2 m (decoded - target) / (N F)``. Splitting the mean,
    ``L = (w T / F) MSE_t + ((F - T) / F) MSE_others = (w T / F) (MSE_t + k MSE_others)`` with
    ``k = (F - T) / (w T)``: Eq. (1) times a constant, which moves no minimiser (for the lesson's hands,
    F = 63, T = 6, w = 100: k = 0.095).

    Parameters
    ----------
    decoded, target : ndarray, shape (N, F)
    columns : sequence of int, length T
    w : float

    Returns
    -------
    loss : float
    grad : ndarray, shape (N, F)
    k : float
    """
    import numpy as np

    d, t = np.asarray(decoded, dtype=float), np.asarray(target, dtype=float)
    N, F = d.shape
    m = np.ones(F)
    m[list(columns)] = w                         # the weight of each feature
    diff = d - t
    T = len(set(int(c) for c in columns))
    return float(np.mean(m * diff**2)), 2.0 * m * diff / (N * F), (F - T) / (w * T)
