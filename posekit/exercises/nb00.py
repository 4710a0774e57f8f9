"""Checkers for ``notebooks/00_skeletons_and_poses.ipynb``."""

from __future__ import annotations

import numpy as np

from ..kinematics import bone_lengths_of, fk
from ..rotations import matrix_to_sixd, quat_to_matrix, random_rotations, sixd_to_matrix
from ._check import report
from ._judge import judged


def _skeleton_and_poses(seed=0, n=4):
    from ..data import load_sample

    ms = load_sample()
    rng = np.random.default_rng(seed)
    frames = rng.choice(ms.n_frames, n, replace=False)
    return ms.skeleton, ms.local_rot[frames], ms.root_pos[frames]


def _worst_joint(skeleton):
    def describe(got, expected):
        err = np.linalg.norm(got - expected, axis=-1).reshape(-1, skeleton.n_joints).max(0)
        j = int(np.argmax(err))
        return f"largest error {err[j] * 100:.2f} cm at joint {skeleton.names[j]} (check its parent's rotation)"
    return describe


@judged
def check_fk(my_fk) -> bool:
    """Check ``my_fk(skeleton, local_rot (J,3,3), root_pos (3,)) -> global_pos (J,3)``
    on real poses of the shipped sample and on a random pose."""
    skel, q, root = _skeleton_and_poses()
    R = quat_to_matrix(q)
    cases = [((skel, R[i], root[i]), fk(skel, R[i], root[i])[0], _worst_joint(skel)) for i in range(len(R))]
    Rr = quat_to_matrix(random_rotations(skel.n_joints, 7))
    cases.append(((skel, Rr, np.zeros(3)), fk(skel, Rr, np.zeros(3))[0], _worst_joint(skel)))
    rest = np.broadcast_to(np.eye(3), Rr.shape).copy()  # every joint unturned: the rest pose, moved by root_pos
    cases.append(((skel, rest, np.array([0.3, 0.9, -1.2])), fk(skel, rest, np.array([0.3, 0.9, -1.2]))[0],
                  _worst_joint(skel)))
    R32, p32 = R[1].astype(np.float32), root[1].astype(np.float32)  # float32 rotations and root
    cases.append(((skel, R32, p32), fk(skel, R32.astype(float), p32.astype(float))[0], _worst_joint(skel)))
    return report("check_fk", my_fk, cases, forbid=(fk,), arg_names=("skeleton", "local_rot", "root_pos"))


@judged
def check_sixd_to_matrix(my_sixd_to_matrix) -> bool:
    """Check ``my_sixd_to_matrix(x (6,)) -> R (3, 3)`` (Gram-Schmidt of Zhou et al. 2019) on exact
    6D vectors and on noisy, unnormalised ones."""
    rng = np.random.default_rng(3)
    R = quat_to_matrix(random_rotations(3, rng))
    inputs = [matrix_to_sixd(r) for r in R] + [matrix_to_sixd(R[0]) * 2.5 + rng.normal(0, 0.2, 6),
                                               rng.normal(size=6), matrix_to_sixd(np.eye(3)),
                                               np.array([1e-3, 0.0, 0.0, 1e-3, 2e-3, 0.0]),  # tiny, unnormalised
                                               matrix_to_sixd(R[1]).astype(np.float32)]  # float32

    def describe(got, expected):
        return f"max entry error {np.abs(got - expected).max():.3g}; columns must be b1, b2, b1 x b2"
    cases = [((x.copy(),), sixd_to_matrix(np.asarray(x, float)), describe) for x in inputs]
    return report("check_sixd_to_matrix", my_sixd_to_matrix, cases, atol=1e-6, forbid=(sixd_to_matrix,),
                  arg_names=("x",))


@judged
def check_bone_lengths(my_bone_lengths) -> bool:
    """Check ``my_bone_lengths(parents (J,), global_pos (J,3)) -> lengths (J,)`` (0 for the root)."""
    skel, q, root = _skeleton_and_poses(seed=5, n=3)
    P = fk(skel, q, root)[0]

    def describe(got, expected):
        j = int(np.argmax(np.abs(got - expected)))
        return f"joint {skel.names[j]}: got {got[j]:.4f} m, expected {expected[j]:.4f} m"
    cases = [((np.array(skel.parents), P[i]), bone_lengths_of(skel, P[i]), describe) for i in range(len(P))]
    cases.append(((list(skel.parents), P[0].copy()), bone_lengths_of(skel, P[0]), describe))  # parents as a list
    cases.append(((np.array(skel.parents), P[1].astype(np.float32)), bone_lengths_of(skel, P[1].astype(np.float32)
                                                                                     .astype(float)), describe))
    # a tree of its own, parents listed after their children: no skeleton's joint order may be assumed
    tree, pos = [3, 0, 0, -1], np.array([[0.0, 1.0, 0.0], [0.2, 1.1, 0.0], [0.0, 1.3, 0.4], [0.0, 0.5, 0.0]])

    def own(got, expected):
        j = int(np.argmax(np.abs(got - expected)))
        return f"joint {j} of parents {tree}: got {got[j]:.4f} m, expected {expected[j]:.4f} m (|p_j - p_parent|, 0 at a root)"
    cases.append(((list(tree), pos), np.array([0.5, np.hypot(0.2, 0.1), np.hypot(0.3, 0.4), 0.0]), own))
    return report("check_bone_lengths", my_bone_lengths, cases, forbid=(bone_lengths_of,),
                  arg_names=("parents", "global_pos"))


__all__ = ["check_fk", "check_sixd_to_matrix", "check_bone_lengths"]
