"""Checkers for ``notebooks/00_skeletons_and_poses.ipynb``.

Section 2 writes forward kinematics; exercise 1 asks for its other half, the local rotations and offsets of a posed
skeleton from its global rotations and positions, for any batch of poses and any tree. Each checker starts with a
generic case, accepts float32 answers, and refuses an answer that calls the posekit function it is compared against
or changes its inputs.
"""

from __future__ import annotations

import numpy as np

from ..kinematics import bone_lengths_of, fk
from ..rotations import matrix_to_sixd, quat_to_matrix, random_rotations, sixd_to_matrix
from ._check import flat, report
from ._judge import judged


def _skeleton_and_poses(seed=0, n=4):
    from ..data import load_sample

    ms = load_sample()
    rng = np.random.default_rng(seed)
    frames = rng.choice(ms.n_frames, n, replace=False)
    return ms.skeleton, ms.local_rot[frames], ms.root_pos[frames]


def local_from_global_reference(parents, global_rot, global_pos):
    """What :func:`check_local_from_global` expects: FK undone, ``(local_rot, local_pos)`` with
    ``local_rot[j] = R_p^T R_j`` and ``local_pos[j] = R_p^T (x_j - x_p)`` for a joint with parent ``p``, a root's
    own global rotation and position kept; any leading batch dimensions. ``fk(skeleton, local_rot,
    local_pos=local_pos)`` gives the pose back."""
    Rg, Pg = np.asarray(global_rot, dtype=float), np.asarray(global_pos, dtype=float)
    L, O = Rg.copy(), Pg.copy()
    for j, p in enumerate(parents):
        p = int(p)
        if p >= 0:
            Rp = Rg[..., p, :, :]
            L[..., j, :, :] = np.swapaxes(Rp, -1, -2) @ Rg[..., j, :, :]
            O[..., j, :] = np.einsum("...ba,...b->...a", Rp, Pg[..., j, :] - Pg[..., p, :])
    return L, O


def local_from_global_cases(seed: int = 0):
    """The cases of :func:`check_local_from_global`: ``(parents, global_rot, global_pos)``, generic first.

    One real pose of the shipped sample; three at once (a leading batch dimension: ``global_rot[p]`` would pick a
    pose, not a joint); the rest pose moved (every local rotation the identity, every ``local_pos`` the offset);
    random rotations; a tree of its own with two roots and parents listed after their children, as a list;
    a (2, 2) batch; float32 rotations and positions.
    """
    skel, q, root = _skeleton_and_poses(seed=seed, n=4)
    R = quat_to_matrix(q)
    P, G = fk(skel, R, root)
    parents = np.array(skel.parents)
    out = [(parents, G[0], P[0]), (parents, G[1:4], P[1:4])]
    rest = np.broadcast_to(np.eye(3), R[0].shape).copy()
    Pr, Gr = fk(skel, rest, np.array([0.3, 0.9, -1.2]))
    out.append((parents, Gr, Pr))
    Rr = quat_to_matrix(random_rotations(skel.n_joints, 7))
    Pn, Gn = fk(skel, Rr, np.zeros(3))
    out.append((parents, Gn, Pn))
    rng = np.random.default_rng(seed + 1)
    tree = [3, -1, 1, -1, 0, 2]  # two roots (1 and 3); joint 0's parent 3 and joint 2's parent 1 come later or earlier
    out.append((list(tree), quat_to_matrix(random_rotations(len(tree), 9)), rng.normal(size=(len(tree), 3))))
    Rb = quat_to_matrix(random_rotations((2, 2, skel.n_joints), 11))
    Pb, Gb = fk(skel, Rb, rng.normal(size=(2, 2, 3)))
    out.append((parents, Gb, Pb))
    out.append((parents, G[0].astype(np.float32), P[0].astype(np.float32)))
    return out


@judged
def check_local_from_global(my_local_from_global) -> bool:
    """Check ``my_local_from_global(parents (J,), global_rot (..., J, 3, 3), global_pos (..., J, 3)) ->
    (local_rot (..., J, 3, 3), local_pos (..., J, 3))``: forward kinematics undone, the local rotations and the
    translations that ``fk(skeleton, local_rot, local_pos=local_pos)`` turns back into the pose
    (:func:`local_from_global_reference`)."""
    def describe_for(parents, shape):
        J, lead = len(parents), int(np.prod(shape[:-3], dtype=int))

        def describe(got, exp):
            n = lead * J * 9
            gr, er = got[:n].reshape(lead, J, 3, 3), exp[:n].reshape(lead, J, 3, 3)
            gp, ep = got[n:].reshape(lead, J, 3), exp[n:].reshape(lead, J, 3)
            err_r, err_p = np.abs(gr - er).max(axis=(0, 2, 3)), np.abs(gp - ep).max(axis=(0, 2))
            batch = f" (global_rot shaped {tuple(shape)}: the joints are axis -3, after any batch axes)" \
                if len(shape) > 3 else ""
            if err_r.max() > 1e-5 * max(1.0, np.abs(er).max()):
                j = int(np.argmax(err_r))
                p = int(parents[j])
                if p < 0:
                    return f"local_rot of joint {j}, a root, is off by {err_r[j]:.3g}: a root keeps its global rotation{batch}"
                flipped = np.swapaxes(gr[:, j], -1, -2)
                if np.allclose(flipped, er[:, j], atol=1e-5):
                    return (f"local_rot of joint {j} (parent {p}) is the transpose of the expected one: "
                            f"R_loc = R_parent^T R_joint, not R_joint^T R_parent{batch}")
                return (f"local_rot of joint {j} (parent {p}) is off by {err_r[j]:.3g}: R_j = R_p R_loc, so "
                        f"R_loc = R_p^T R_j (the parent's inverse on the left){batch}")
            j = int(np.argmax(err_p))
            p = int(parents[j])
            if p < 0:
                return f"local_pos of joint {j}, a root, is off by {err_p[j]:.3g} m: a root keeps its global position{batch}"
            return (f"local_pos of joint {j} (parent {p}) is off by {err_p[j]:.3g} m: x_j = x_p + R_p o_j, so the "
                    f"offset is R_p^T (x_j - x_p), in the parent's frame{batch}")
        return describe

    cases = []
    for parents, G, P in local_from_global_cases():
        exp = flat(*local_from_global_reference(parents, G, P))
        cases.append(((parents, G, P), exp, describe_for(parents, np.shape(G))))

    def both(parents, G, P):
        return flat(*my_local_from_global(parents, G, P))
    return report("check_local_from_global", both, cases, atol=1e-9,
                  forbid=(fk, local_from_global_reference),
                  arg_names=("parents", "global_rot", "global_pos"))


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


__all__ = ["check_local_from_global", "check_sixd_to_matrix", "check_bone_lengths"]
