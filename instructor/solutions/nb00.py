"""Reference solutions of lesson 00's exercises (instructor version; ``posekit exercises solutions 00`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_local_from_global", "exercise_matrix_to_quat", "exercise_bone_drift"]


def exercise_local_from_global(parents, global_rot, global_pos):
    """Forward kinematics undone: the local rotations and translations of posed skeletons.

    FK (lesson 00, section 2) composes ``R_j = R_p R_loc_j`` and ``x_j = x_p + R_p o_j``. Solved for the local
    quantities: ``R_loc_j = R_p^T R_j`` (a rotation's inverse is its transpose, and it multiplies from the left)
    and ``o_j = R_p^T (x_j - x_p)``, the bone seen from the parent's frame. A root keeps its global rotation and
    position. Each joint needs only its parent, so the joints may come in any order; the ``...`` batch axes ride
    along in ``@`` and ``einsum``. ``posekit.fk(skeleton, local_rot, local_pos=local_pos)`` gives the pose back.

    Parameters
    ----------
    parents : sequence of int, length J
        Parent of each joint, -1 for a root.
    global_rot : ndarray, shape (..., J, 3, 3)
    global_pos : ndarray, shape (..., J, 3), metres

    Returns
    -------
    local_rot : ndarray, shape (..., J, 3, 3)
    local_pos : ndarray, shape (..., J, 3), metres
        The offsets of the pose (a root's row: its position).
    """
    import numpy as np

    Rg = np.asarray(global_rot, dtype=float)
    Pg = np.asarray(global_pos, dtype=float)
    local_rot, local_pos = Rg.copy(), Pg.copy()  # copies: a root keeps its own, the caller's arrays stay
    for j, p in enumerate(parents):
        if p < 0:
            continue
        Rp_T = np.swapaxes(Rg[..., p, :, :], -1, -2)  # the parent's inverse, for every pose of the batch
        local_rot[..., j, :, :] = Rp_T @ Rg[..., j, :, :]
        local_pos[..., j, :] = (Rp_T @ (Pg[..., j, :] - Pg[..., p, :])[..., None])[..., 0]
    return local_rot, local_pos


def exercise_matrix_to_quat(R):
    """Rotation matrices back to unit quaternions ``(x, y, z, w)``, ``w >= 0``, accurate at every angle.

    From ``R(q)`` (the exercise's matrix), the diagonal and the trace give each component's square,
    ``4w^2 = 1 + tr R``, ``4x^2 = 1 + 2 R_11 - tr R``, ``4y^2 = 1 + 2 R_22 - tr R``, ``4z^2 = 1 + 2 R_33 - tr R``,
    and the off-diagonal entries give the products of pairs, ``R_32 - R_23 = 4wx``, ``R_21 + R_12 = 4xy`` and so
    on. Dividing those by ``4w`` (the textbook formula) loses every digit near a half-turn, where ``w -> 0``;
    Shepperd's method (Shepperd 1978) square-roots the *largest* of the four squares (at least 1/4 of their sum,
    1) and divides by it. The sign is then chosen so that ``w >= 0`` (``q`` and ``-q`` are the same rotation).

    Parameters
    ----------
    R : ndarray, shape (..., 3, 3)
        Rotation matrices (acting on column vectors).

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions, scalar last, ``w >= 0``.
    """
    import numpy as np

    R = np.asarray(R, dtype=float)
    m = R.reshape(-1, 3, 3)  # any batch axes, one matrix at a time
    q = np.empty((len(m), 4))
    for i, r in enumerate(m):
        tr = np.trace(r)
        four_squares = [1 + 2 * r[0, 0] - tr, 1 + 2 * r[1, 1] - tr, 1 + 2 * r[2, 2] - tr, 1 + tr]  # 4x^2 ... 4w^2
        k = int(np.argmax(four_squares))
        s = 2.0 * np.sqrt(four_squares[k])  # 4 times the largest component: never near zero
        w4, xy4, xz4, yz4 = r[2, 1] - r[1, 2], r[1, 0] + r[0, 1], r[0, 2] + r[2, 0], r[2, 1] + r[1, 2]
        wx4, wy4, wz4 = w4, r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]
        if k == 0:
            q[i] = [s / 4, xy4 / s, xz4 / s, wx4 / s]
        elif k == 1:
            q[i] = [xy4 / s, s / 4, yz4 / s, wy4 / s]
        elif k == 2:
            q[i] = [xz4 / s, yz4 / s, s / 4, wz4 / s]
        else:
            q[i] = [wx4 / s, wy4 / s, wz4 / s, s / 4]
        if q[i, 3] < 0:
            q[i] = -q[i]
    return q.reshape(R.shape[:-2] + (4,))


def exercise_bone_drift(parents, clip):
    """How far each bone's length drifts over a clip: the largest change against the first frame, metres.

    FK (section 2) moves a joint by turning its parent's frame, so a bone ``|x_j - x_p|`` keeps its length in every
    frame; a pose a network outputs as positions need not. For each bone ``max_t | L_j(t) - L_j(0) |`` with
    ``L_j(t) = |x_j(t) - x_p(t)|``: the absolute change, so that a bone that shrinks counts as much as one that
    grows, and against the first frame, so that a slow drift adds up. A root has no bone (0); its parent ``-1``
    must not be used as an index (NumPy reads it as the last joint).

    Parameters
    ----------
    parents : sequence of int, length J
        Parent of each joint, -1 for a root (several allowed, in any order).
    clip : ndarray, shape (T, J, 3), metres

    Returns
    -------
    ndarray, shape (J,), metres
    """
    import numpy as np

    P = np.asarray(clip, dtype=float)
    drift = np.zeros(P.shape[1])
    for j, p in enumerate(parents):
        if p < 0:  # a root: no bone
            continue
        length = np.linalg.norm(P[:, j] - P[:, p], axis=-1)  # (T,): this bone in every frame
        drift[j] = np.abs(length - length[0]).max()
    return drift
