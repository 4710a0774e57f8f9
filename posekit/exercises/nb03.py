"""Checkers for ``notebooks/03_autoencoder_solvers.ipynb``.

Exercise 1 builds the pose vector of section 1 (the lesson calls posekit's); exercise 2 its inverse, a decoded
vector back to a pose in the world, helper root included; exercise 3 the authors' code's weighting of the solver
loss, its gradient and the ``k`` of Eq. (1) it amounts to (section 3 only states the equivalence). Each checker
starts with a generic case, accepts float32 answers, and refuses an answer that calls the posekit function it is
compared against or changes its inputs.
"""

from __future__ import annotations

import numpy as np

from ._check import flat, report
from ._judge import judged


def _pose_vector_with(skeleton, pos, turn=-1.0, keep_height=True, helper=False):
    """The pose vector of one pose with one rule changed (the describe's slips): turned by ``turn`` times the facing
    angle, the pelvis's height subtracted too, the helper root kept."""
    from ..data.metrics import body_joints
    from ..transforms import facing_angle

    P = np.asarray(pos, dtype=float)
    origin = P[skeleton.pelvis()] * (np.array([1.0, 0.0, 1.0]) if keep_height else 1.0)
    a = turn * float(facing_angle(skeleton, P))
    c, s = np.cos(a), np.sin(a)
    local = (P - origin) @ np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]).T
    joints = np.arange(skeleton.n_joints) if helper else body_joints(skeleton)
    return local[joints].ravel()


@judged
def check_pose_vector(my_pose_vector) -> bool:
    """Check ``my_pose_vector(skeleton, global_pos (J, 3)) -> (3B,)``: the body joints (no helper root)
    in the pose's root frame — pelvis projected on the floor at the origin, facing +Z — flattened
    (:func:`posekit.data.pose_vectors.pose_vectors`)."""
    from ..data import load_sample
    from ..data.bandai_mini import load_bandai_mini
    from ..data.pose_vectors import pose_vectors, targets_in_root_frame
    from ..transforms import root_frame, rotate_y_positions, to_root_space

    m = load_bandai_mini()
    other = load_sample()  # another skeleton (DeepMimic's humanoid, no helper root): no index may be hard-coded
    cases = []

    def describe_for(skeleton, pos):
        slips = {
            "turned the wrong way: turn by minus the facing angle, so that the facing direction becomes +Z":
                _pose_vector_with(skeleton, pos, turn=1.0),
            "not turned: the root frame faces +Z": _pose_vector_with(skeleton, pos, turn=0.0),
            "the pelvis's height taken off too: the origin is the pelvis on the floor (y = 0), so heights are kept":
                _pose_vector_with(skeleton, pos, keep_height=False),
        }

        def describe(got, expected):
            d = np.abs(got - expected).reshape(-1, 3).max(-1)
            said = f"largest difference {d.max() * 1e3:.1f} mm at body joint {int(np.argmax(d))}"
            for why, wrong in slips.items():
                if got.shape == wrong.shape and np.allclose(got, wrong, atol=1e-6):
                    return said + ": " + why
            return said + ": the root frame is the pelvis on the floor, facing +Z"
        return describe
    for motion, f in ((m, 0), (other, 100), (m, 4321), (m, 20_000), (other, 1500), (m, 40_000)):
        pos = motion.global_pos[f]
        cases.append(((motion.skeleton, pos.copy()), pose_vectors(motion.skeleton, pos[None])[0][0],
                      describe_for(motion.skeleton, pos)))
    pos = m.global_pos[777].astype(np.float32)
    cases.append(((m.skeleton, pos.copy()), pose_vectors(m.skeleton, pos[None].astype(float))[0][0],
                  describe_for(m.skeleton, pos)))
    return report("check_pose_vector", my_pose_vector, cases, atol=1e-6,
                  forbid=(pose_vectors, to_root_space, root_frame, rotate_y_positions, targets_in_root_frame),
                  arg_names=("skeleton", "global_pos"))


@judged
def check_pose_from_vector(my_pose_from_vector) -> bool:
    """Check ``my_pose_from_vector(skeleton, x (3B,), origin (3,), angle) -> global_pos (J, 3)``: exercise 1
    undone — the body joints turned back by the facing angle and moved to the origin, a helper root (Bandai's
    ``joint_Root``) put back at its rest offset from the pelvis
    (:func:`posekit.data.pose_vectors.poses_from_vectors`)."""
    from ..data import load_sample
    from ..data.bandai_mini import load_bandai_mini
    from ..data.pose_vectors import poses_from_vectors, pose_vectors
    from ..transforms import from_root_space, rotate_y_positions

    m, other = load_bandai_mini(), load_sample()
    cases = []

    def describe_for(skel, x, origin, angle, what=""):
        body = [j for j in range(skel.n_joints) if j not in _helpers(skel)]
        local = poses_from_vectors(skel, x[None].astype(float))[0]
        slips = {"turned the wrong way: the vector was turned by minus the facing angle, so turn back by plus it":
                     rotate_y_positions(local, -angle) + origin,
                 "not moved to origin (add it after turning)": rotate_y_positions(local, angle),
                 "moved before turning: turn about the root frame's origin, then add origin":
                     rotate_y_positions(local + origin, angle)}

        def describe(got, exp):
            err = np.linalg.norm(got - exp, axis=-1)
            j = int(np.argmax(err))
            said = f"joint {skel.names[j]} is {err[j] * 1e3:.1f} mm off (angle {float(angle):.3g} rad{what})"
            for why, wrong in slips.items():
                if np.allclose(got[body], wrong[body], atol=1e-6) and not np.allclose(wrong[body], exp[body],
                                                                                        atol=1e-6):
                    return said + ": " + why
            if j not in body:
                return (said + ": a helper root carries no pose; put it back at its rest offset from the pelvis "
                        "(skeleton.offsets of the joints above it)")
            return said + ": x holds the body joints in order, 3 numbers each; turn about +Y by angle, add origin?"
        return describe

    for motion, f, what in ((m, 0, ""), (m, 4321, ""), (other, 100, ", a skeleton without a helper root"),
                            (m, 20_000, ""), (other, 1500, ", a skeleton without a helper root")):
        x, origin, angle = (a[0] for a in pose_vectors(motion.skeleton, motion.global_pos[f][None]))
        cases.append(((motion.skeleton, x, origin, angle), motion.global_pos[f],
                      describe_for(motion.skeleton, x, origin, angle, what)))
    x, origin, angle = (a[0] for a in pose_vectors(m.skeleton, m.global_pos[[30_000]]))
    for o, a, what in ((np.zeros(3), 0.0, ", the root frame itself"), (origin, np.pi - 1e-3, ", facing nearly -Z"),
                       (np.array([2.0, 0.0, -3.0]), -2.5, ", a negative angle")):
        cases.append(((m.skeleton, x.copy(), o, a), poses_from_vectors(m.skeleton, x[None], o[None], np.array([a]))[0],
                      describe_for(m.skeleton, x, o, a, what)))
    x32 = x.astype(np.float32)
    cases.append(((m.skeleton, x32, origin.astype(np.float32), np.float32(angle)),
                  poses_from_vectors(m.skeleton, x32[None].astype(float), origin[None].astype(np.float32)
                                     .astype(float), np.array([np.float32(angle)], float))[0],
                  describe_for(m.skeleton, x32, origin.astype(np.float32), np.float32(angle), ", float32")))
    return report("check_pose_from_vector", my_pose_from_vector, cases, atol=1e-6,
                  forbid=(poses_from_vectors, from_root_space, rotate_y_positions),
                  arg_names=("skeleton", "x", "origin", "angle"))


def _helpers(skel):
    """The joints above the pelvis (a helper root such as Bandai's ``joint_Root``)."""
    out, j = [], int(skel.pelvis())
    while j != 0:
        j = int(skel.parents[j])
        out.append(j)
    return out


# -- exercise 3: the authors' weighting and its gradient ----------------------------------------------------------

def authors_loss_reference(decoded, target, columns, w):
    """What :func:`check_authors_loss` expects: ``(loss, grad (N, F), k)`` — the authors' one weighted mean
    ``L = mean_{n,c} m_c (decoded - target)^2`` with ``m_c = w`` on the target ``columns`` and 1 elsewhere, its
    gradient with respect to ``decoded``, ``2 m_c (decoded - target) / (N F)``, and the ``k`` for which
    ``L = (w T / F) (MSE_t + k MSE_others)``, Eq. (1) scaled: ``k = (F - T) / (w T)``, ``T = len(columns)``."""
    d, t = np.asarray(decoded, dtype=float), np.asarray(target, dtype=float)
    N, F = d.shape
    m = np.ones(F)
    m[np.asarray(columns)] = w
    T = len(np.unique(np.asarray(columns)))
    diff = d - t
    return float(np.mean(m * diff**2)), 2.0 * m * diff / (N * F), (F - T) / (w * T)


@judged
def check_authors_loss(my_loss) -> bool:
    """Check ``my_loss(decoded (N, F), target (N, F), columns, w) -> (loss, grad (N, F), k)``: the authors' code's
    weighting, one mean over every feature with the target ``columns`` weighted ``w``, its gradient with respect
    to ``decoded``, and the ``k`` of Eq. (1) it equals up to a constant factor (:func:`authors_loss_reference`)."""
    from ..models.pose_autoencoder.train import solver_loss

    rng = np.random.default_rng(3)
    cases = []

    def describe_for(N, F, T, w):
        def describe(got, exp):
            if not np.isclose(got[0], exp[0], atol=1e-9, rtol=1e-5):
                return (f"the loss is {got[0]:.6g}, expected {exp[0]:.6g} (N = {N}, F = {F}, {T} target columns, "
                        f"w = {w:g}): one mean over all N x F squared errors, the target columns' ones times w?")
            if not np.isclose(got[-1], exp[-1], rtol=1e-5):
                return (f"k is {got[-1]:.6g}, expected {exp[-1]:.6g}: write the weighted mean as "
                        "(w T / F) (MSE_t + k MSE_others) and read k off")
            g, e = got[1:-1], exp[1:-1]
            i = int(np.argmax(np.abs(g - e)))
            said = f"the loss is right; the gradient differs at entry {i}: got {g[i]:.6g}, expected {e[i]:.6g}"
            if np.isclose(g[i], e[i] * N * F):
                return said + f": the mean divides by N F = {N * F}, and so does its gradient"
            if np.isclose(g[i], e[i] / 2):
                return said + ": d(u^2)/du = 2u"
            return said + ": 2 m_c (decoded - target) / (N F), m_c = w on the target columns, 1 elsewhere"
        return describe

    def case(d, t, cols, w):
        exp = flat(*authors_loss_reference(d, t, cols, w))
        cases.append(((d, t, cols, w), exp, describe_for(*np.shape(d), len(np.unique(cols)), w)))
    for N, F, cols, w in ((4, 9, [0, 1, 2], 100.0),                     # generic
                          (10, 63, list(range(27, 33)), 100.0),         # the lesson's size, two hands' worth
                          (3, 12, np.array([9, 10, 11, 0, 1, 2]), 5.0),  # an index array, not in order
                          (5, 6, [3, 4, 5], 1.0),                       # w = 1: a plain mean, k = (F - T) / T
                          (1, 9, [6, 7, 8], 0.5)):                      # one pose; targets weighted below the rest
        case(rng.normal(size=(N, F)), rng.normal(size=(N, F)), cols, w)
    t = rng.normal(size=(3, 9))
    case(t.copy(), t, [0, 1, 2], 100.0)                                # decoded == target: loss and gradient 0
    case(rng.normal(size=(4, 9)).astype(np.float32), rng.normal(size=(4, 9)).astype(np.float32), [3, 4, 5], 100.0)

    def flattened(*a):
        return flat(*my_loss(*a))
    return report("check_authors_loss", flattened, cases, atol=1e-9, forbid=(solver_loss, authors_loss_reference),
                  arg_names=("decoded", "target", "columns", "w"))


__all__ = ["check_pose_vector", "check_pose_from_vector", "check_authors_loss"]
