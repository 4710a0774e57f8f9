"""Reference solutions of lesson 00's exercises (instructor version; ``posekit exercises solutions 00`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_fk", "exercise_sixd_to_matrix", "exercise_bone_lengths"]


def exercise_fk(skeleton, local_rot, root_pos):
    """Forward kinematics of one pose, one joint at a time in index order (parents come first).

    For joint ``j`` with parent ``p`` (lesson 00, section 2):
    ``R_j = R_p R_loc_j`` and ``x_j = x_p + R_p o_j``; the root takes ``root_pos`` and its own local rotation.

    Parameters
    ----------
    skeleton : Skeleton
        ``parents`` (J,), -1 for the root, and rest ``offsets`` (J, 3), metres.
    local_rot : ndarray, shape (J, 3, 3)
        Local rotation matrices, each relative to the joint's parent.
    root_pos : ndarray, shape (3,), metres

    Returns
    -------
    ndarray, shape (J, 3), metres
        Global joint positions.
    """
    import numpy as np

    J = skeleton.n_joints
    R = np.zeros((J, 3, 3))  # global rotations
    x = np.zeros((J, 3))     # global positions
    for j in range(J):
        p = skeleton.parents[j]
        if p < 0:  # the root
            R[j] = local_rot[j]
            x[j] = root_pos
        else:
            R[j] = R[p] @ local_rot[j]
            # the offset lives in the parent's frame, so the parent's rotation turns it
            x[j] = x[p] + R[p] @ skeleton.offsets[j]
    return x


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
