"""Reference solutions of lesson 00's exercises (instructor version; ``posekit exercises solutions 00`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_local_from_global", "exercise_sixd_to_matrix", "exercise_bone_lengths"]


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


def exercise_sixd_to_matrix(x):
    """A rotation matrix from a 6D vector by Gram-Schmidt (Zhou et al. 2019).

    ``b1 = a1 / |a1|``, ``b2 = (a2 - (b1 . a2) b1) / |...|``, ``b3 = b1 x b2``, ``R = [b1 b2 b3]``.

    Parameters
    ----------
    x : ndarray, shape (6,)
        The first two columns ``a1``, ``a2`` of a rotation matrix, one after the other; need not be
        orthonormal (e.g. a network's output).

    Returns
    -------
    ndarray, shape (3, 3)
        A rotation matrix with columns ``b1, b2, b3``.
    """
    import numpy as np

    a1, a2 = x[:3], x[3:]
    b1 = a1 / np.linalg.norm(a1)
    b2 = a2 - (b1 @ a2) * b1  # remove the part of a2 along b1
    b2 = b2 / np.linalg.norm(b2)
    b3 = np.cross(b1, b2)
    return np.stack([b1, b2, b3], axis=1)  # as columns, not rows


def exercise_bone_lengths(parents, global_pos):
    """Length of every bone (parent -> joint) of a posed skeleton; 0 for the root.

    Parameters
    ----------
    parents : ndarray of int, shape (J,)
        Parent of each joint, -1 for the root.
    global_pos : ndarray, shape (J, 3), metres

    Returns
    -------
    ndarray, shape (J,), metres
    """
    import numpy as np

    lengths = np.zeros(len(parents))
    for j, p in enumerate(parents):
        if p >= 0:  # the root has no bone
            lengths[j] = np.linalg.norm(global_pos[j] - global_pos[p])
    return lengths
