"""Reference solutions of lesson 05's exercises (instructor version; ``posekit exercises solutions 05`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_look_at_angle", "exercise_rotation_noise", "exercise_effector_inputs"]


def exercise_look_at_angle(R, v, t, p):
    """The look-at loss's angle (Oreshkin et al. 2022, Sec. 2.2): between the joint's world direction ``R v`` and
    the direction to its target ``t - p``, in radians, accurate at every angle.

    ``arccos`` of the normalised dot product loses digits near 0 and pi (its slope is infinite there: a cosine
    rounded by 1e-16 moves the angle by 1e-8) and has no value for a cosine rounded past +-1.
    ``atan2(|a x b|, a . b)`` reads the angle from its sine and cosine together, unnormalised: both scale with
    ``|a| |b|``, which cancels.

    Parameters
    ----------
    R : ndarray, shape (N, 3, 3)
        The joints' world rotations.
    v : ndarray, shape (N, 3)
        Each joint's local direction that should face its target (any length).
    t, p : ndarray, shape (N, 3), metres
        The targets and the joints' positions.

    Returns
    -------
    ndarray, shape (N,), radians in [0, pi]
    """
    import numpy as np

    a = np.einsum("nij,nj->ni", np.asarray(R, dtype=float), np.asarray(v, dtype=float))  # R v, row by row
    b = np.asarray(t, dtype=float) - np.asarray(p, dtype=float)
    sin_part = np.linalg.norm(np.cross(a, b), axis=-1)
    cos_part = np.einsum("ni,ni->n", a, b)
    return np.arctan2(sin_part, cos_part)


def exercise_rotation_noise(R, n, lam):
    """A rotation effector's noise model (Oreshkin et al. 2022, Appendix B; posekit turns a rotation vector, the
    authors' code Euler angles): ``exp(sigma n) R`` with ``sigma = sigma_M Lambda^eta``.

    The rotation vector ``w = sigma n`` (axis times angle) becomes a matrix by Rodrigues' formula,
    ``exp(w) = I + sin(theta) K + (1 - cos(theta)) K^2`` with ``theta = |w|`` and ``K`` the cross-product matrix of
    the axis ``w / theta``; it multiplies on the left, turning the rotation in the world frame. At ``w = 0`` (an
    exact effector, Lambda = 0) there is no axis: the answer is ``R`` itself.

    Parameters
    ----------
    R : ndarray, shape (N, 3, 3)
        The effectors' target world rotations.
    n : ndarray, shape (N, 3)
        Standard normal draws.
    lam : ndarray, shape (N,)
        Tolerances Lambda in [0, 1].

    Returns
    -------
    ndarray, shape (N, 3, 3)
    """
    import numpy as np

    sigma_m, eta = 0.1, 13
    R, n, lam = (np.asarray(x, dtype=float) for x in (R, n, lam))
    w = sigma_m * lam[:, None] ** eta * n
    out = R.copy()
    for i, wi in enumerate(w):
        theta = np.linalg.norm(wi)
        if theta == 0.0:          # no noise: the rotation as it is
            continue
        k = wi / theta
        K = np.array([[0.0, -k[2], k[1]],
                      [k[2], 0.0, -k[0]],
                      [-k[1], k[0], 0.0]])
        out[i] = (np.eye(3) + np.sin(theta) * K + (1 - np.cos(theta)) * K @ K) @ R[i]
    return out


def exercise_effector_inputs(kind, value, lam):
    """What ProtoRes reads (Oreshkin et al. 2022, Sec. 2.1): the centroid of each request and every effector's six
    values re-referenced to it, for a batch of requests.

    ``c = sum_i w_i p_i / sum_i w_i`` over a request's position effectors, ``w_i = 1 - Lambda_i + 1e-3`` (a tight
    effector counts most; at ``Lambda = 1`` every weight is ``1e-3``, still a mean); rotations and look-at targets do
    not count, and a request with no position effector is centred on the origin. Then what moves with the character
    moves: a position and a look-at target (points) lose ``c``; a rotation's 6D, a look-at direction and a position's
    three zeros stay. Moving every point of a request by ``d`` moves ``c`` by ``d`` and leaves the inputs as they
    were: the network never sees where the character stands.

    Parameters
    ----------
    kind : ndarray of int, shape (B, N)
        0 position, 1 rotation, 2 look-at.
    value : ndarray, shape (B, N, 6)
        ``[p, 0, 0, 0]`` for a position (metres), a rotation's 6D, ``[t, v]`` for a look-at (target in metres, local
        direction).
    lam : ndarray, shape (B, N)
        Tolerances ``Lambda`` in [0, 1].

    Returns
    -------
    c : ndarray, shape (B, 3), metres
    inputs : ndarray, shape (B, N, 6)
    """
    import numpy as np

    kind = np.asarray(kind)
    value = np.asarray(value, dtype=float)
    w = (kind == 0) * (1.0 - np.asarray(lam, dtype=float) + 1e-3)  # 0 for rotations and look-ats
    total = w.sum(axis=1)  # one sum per request
    c = np.zeros((len(kind), 3))
    has = total > 0  # a request with no position effector keeps the origin
    c[has] = (w[has, :, None] * value[has, :, :3]).sum(axis=1) / total[has, None]
    inputs = value.copy()  # the caller's array stays
    points = kind != 1  # positions and look-at targets are points; a rotation is not
    inputs[..., :3] -= points[..., None] * c[:, None, :]
    return c, inputs