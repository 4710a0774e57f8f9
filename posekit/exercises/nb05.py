"""Checkers for ``notebooks/05_protores.ipynb``.

Section 2 writes the proto-residual step and section 1 states the tolerance's noise scale; the exercises build what
section 4 only names: the look-at loss's angle, accurate at 0 and pi where the training loss clamps its arccos
(exercise 1), and the noise model of a rotation effector, a rotation vector turned into a matrix by Rodrigues'
formula, finite at sigma = 0 (exercise 2); and what the network reads, the centroid and the effector values
re-referenced to it for a batch of requests, which section 1 states and section 2 calls posekit for (exercise 3).
Each checker starts with a generic case, accepts float32 answers, and refuses an answer that calls the posekit
function it is compared against or changes its inputs.
"""

from __future__ import annotations

import numpy as np

from ._check import flat, report
from ._judge import judged


# -- exercise 1: the look-at angle, accurate at 0 and pi ------------------------------------------------------------

def look_at_angle_reference(R, v, t, p):
    """What :func:`check_look_at_angle` expects: the angle (radians, (N,)) between the joint's world direction
    ``R v`` and the direction to the target ``t - p``, as ``atan2(|a x b|, a . b)`` (accurate at every angle)."""
    R, v, t, p = (np.asarray(x, dtype=float) for x in (R, v, t, p))
    a = np.einsum("nij,nj->ni", R, v)
    b = t - p
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("ni,ni->n", a, b))


def _turned(a, angle, rng):
    """``a`` turned by ``angle`` about an axis perpendicular to it."""
    axis = np.cross(a, rng.normal(size=3))
    axis /= np.linalg.norm(axis)
    return np.cos(angle) * a + np.sin(angle) * np.cross(axis, a) + (1 - np.cos(angle)) * (axis @ a) * axis


@judged
def check_look_at_angle(my_angle) -> bool:
    """Check ``my_angle(R (N, 3, 3), v (N, 3), t (N, 3), p (N, 3)) -> (N,)``: the look-at loss's angle of section 4
    between ``R v`` (the joint's local direction ``v`` turned by its world rotation ``R``) and ``t - p``, in
    radians, accurate to 1e-9 rad also at angles near 0 and pi (:func:`look_at_angle_reference`)."""
    from ..rotations import quat_to_matrix, random_rotations

    rng = np.random.default_rng(8)
    cases = []

    def describe_for(R, v, t, p, what=""):
        R, v, t, p = (np.asarray(x, dtype=float) for x in (R, v, t, p))
        a, b = np.einsum("nij,nj->ni", R, v), t - p
        cos = np.einsum("ni,ni->n", a, b) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
        slips = {
            "R^T v: v is in the joint's frame, R turns it into the world's (R v)":
                look_at_angle_reference(np.swapaxes(R, -1, -2), v, t, p),
            "the target itself, not the direction from the joint to it (t - p)":
                look_at_angle_reference(R, v, t, np.zeros_like(p)),
            "degrees: the loss is in radians": np.degrees(look_at_angle_reference(R, v, t, p)),
        }

        def describe(got, exp):
            i = int(np.argmax(np.where(np.isfinite(got), np.abs(got - exp), np.inf)))
            said = f"effector {i}: got {got[i]:.6g} rad, expected {exp[i]:.6g}{what}"
            if not np.isfinite(got[i]):
                return said + ": not finite — a cosine a hair above 1 (or below -1) has no arccos"
            for why, wrong in slips.items():
                if np.allclose(got, wrong, atol=1e-6):
                    return said + ": " + why
            if np.isclose(got[i], np.arccos(np.clip(cos[i], -1, 1)), atol=1e-12, rtol=0) or exp[i] < 1e-6 \
                    or np.pi - exp[i] < 1e-6:
                return (said + ": near 0 and pi arccos loses digits (its slope is infinite there); "
                        "atan2(|a x b|, a . b) keeps them")
            return said + ": the angle between R v and t - p, both of any length?"
        return describe

    def case(R, v, t, p, what=""):
        cases.append(((R, v, t, p), look_at_angle_reference(R, v, t, p), describe_for(R, v, t, p, what)))
    N = 6  # generic: any directions, v of any length, targets metres away
    R, v, p = quat_to_matrix(random_rotations(N, rng)), rng.normal(size=(N, 3)), rng.normal(size=(N, 3))
    case(R, v, p + rng.normal(size=(N, 3)) * 2.0, p)
    R = quat_to_matrix(random_rotations(5, rng))   # angles of 0, 3e-8, 2e-6, pi - 3e-8 and pi
    v = rng.normal(size=(5, 3)) * np.array([[1.0], [0.3], [2.0], [1.0], [0.5]])
    a = np.einsum("nij,nj->ni", R, v)
    p = rng.normal(size=(5, 3))
    d = np.stack([a[0] * 4.0, _turned(a[1], 3e-8, rng) * 10.0, _turned(a[2], 2e-6, rng) * 0.2,
                  _turned(a[3], np.pi - 3e-8, rng) * 3.0, -a[4] * 7.0])
    case(R, v, p + d, p, " (angles near 0 and pi)")
    R, v, p = quat_to_matrix(random_rotations(1, rng)), rng.normal(size=(1, 3)), rng.normal(size=(1, 3))
    case(R, v, p + rng.normal(size=(1, 3)), p, " (one effector)")
    R, v, p = quat_to_matrix(random_rotations(4, rng)), rng.normal(size=(4, 3)), rng.normal(size=(4, 3))
    t = p + rng.normal(size=(4, 3))
    case(*(x.astype(np.float32) for x in (R, v, t, p)), " (float32)")
    return report("check_look_at_angle", my_angle, cases, atol=1e-9, forbid=(look_at_angle_reference,),
                  arg_names=("R", "v", "t", "p"))


# -- exercise 2: a rotation effector's noise ----------------------------------------------------------------------

def rotation_noise_reference(R, n, lam):
    """What :func:`check_rotation_noise` expects: ``exp([sigma n]_x) R`` with ``sigma = sigma_M lam^eta`` (Rodrigues'
    formula, the rotation vector applied in the world frame, on the left), ``R`` itself where ``sigma n = 0``."""
    from ..models.protores.networks import ETA, SIGMA_M

    R, n, lam = (np.asarray(x, dtype=float) for x in (R, n, lam))
    w = SIGMA_M * lam[:, None] ** ETA * n
    theta = np.linalg.norm(w, axis=-1)
    out = R.copy()
    for i in np.nonzero(theta > 0)[0]:
        k = w[i] / theta[i]
        K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
        E = np.eye(3) + np.sin(theta[i]) * K + (1 - np.cos(theta[i])) * K @ K
        out[i] = E @ R[i]
    return out


@judged
def check_rotation_noise(my_noise) -> bool:
    """Check ``my_noise(R (N, 3, 3), n (N, 3), lam (N,)) -> (N, 3, 3)``: section 4's noise model of a rotation
    effector, ``exp(sigma n) R`` with ``sigma = sigma_M Lambda^eta`` (sigma_M = 0.1, eta = 13) and ``exp`` the
    rotation by the vector ``sigma n`` (axis times angle, radians) in the world frame
    (:func:`rotation_noise_reference`)."""
    from ..models.protores.data import add_noise, axis_angle_matrix
    from ..models.protores.networks import ETA, SIGMA_M, tolerance_to_sigma
    from ..rotations import axis_angle_to_quat, quat_to_matrix, random_rotations

    rng = np.random.default_rng(9)
    cases = []

    def describe_for(R, n, lam, what=""):
        R, n, lam = (np.asarray(x, dtype=float) for x in (R, n, lam))
        slips = {
            "turned in the joint's frame (R exp): the noise turns the world rotation, exp(sigma n) R":
                R @ rotation_noise_reference(np.broadcast_to(np.eye(3), R.shape), n, lam),
            "turned the other way: [k]_x is the cross-product matrix, [k]_x u = k x u":
                rotation_noise_reference(R, -n, lam),
            "sigma = sigma_M Lambda, the power eta = 13 forgotten": _noise_with_sigma(R, n, SIGMA_M * lam),
            "n not scaled by sigma": _noise_with_sigma(R, n, np.ones_like(lam)),
        }

        def describe(got, exp):
            err = np.abs(got - exp).max(axis=(1, 2))
            i = int(np.argmax(np.where(np.isfinite(err), err, np.inf)))
            sigma = SIGMA_M * lam[i] ** ETA
            said = f"effector {i} (Lambda {lam[i]:g}, sigma {sigma:.3g}) is off by {err[i]:.3g}{what}"
            if not np.all(np.isfinite(got[i])):
                return said + ": not finite — at sigma n = 0 there is no axis; the rotation is R itself"
            for why, wrong in slips.items():
                if np.allclose(got, wrong, atol=1e-7) and not np.allclose(wrong, exp, atol=1e-7):
                    return said + ": " + why
            return said + ": exp(sigma n) = I + sin(theta) K + (1 - cos(theta)) K^2, K = [n / |n|]_x, theta = sigma |n|?"
        return describe

    def case(R, n, lam, what=""):
        cases.append(((R, n, lam), rotation_noise_reference(R, n, lam), describe_for(R, n, lam, what)))
    N = 6  # generic: loose effectors, noise of a few degrees
    case(quat_to_matrix(random_rotations(N, rng)), rng.normal(size=(N, 3)), rng.uniform(0.9, 1.0, N))
    case(quat_to_matrix(random_rotations(3, rng)), rng.normal(size=(3, 3)), np.array([0.0, 0.0, 0.95]),
         " (Lambda = 0: exact, no noise)")
    case(quat_to_matrix(random_rotations(2, rng)), rng.normal(size=(2, 3)), np.array([0.5, 0.7]),
         " (tiny sigma)")
    n = rng.normal(size=(2, 3))
    n *= (np.array([3.0, 3.1]) / SIGMA_M / np.linalg.norm(n, axis=-1))[:, None]  # turns of 3 and 3.1 rad
    case(quat_to_matrix(random_rotations(2, rng)), n, np.ones(2), " (Lambda = 1, turns near pi)")
    case(quat_to_matrix(random_rotations(3, rng)).astype(np.float32), rng.normal(size=(3, 3)).astype(np.float32),
         rng.uniform(0.9, 1.0, 3).astype(np.float32), " (float32)")
    return report("check_rotation_noise", my_noise, cases, atol=1e-9,
                  forbid=(axis_angle_matrix, add_noise, tolerance_to_sigma, axis_angle_to_quat,
                          rotation_noise_reference),
                  arg_names=("R", "n", "lam"))


def _noise_with_sigma(R, n, sigma):
    """``exp(sigma n) R`` for a given ``sigma`` (the describe's slips)."""
    from ..models.protores.networks import ETA, SIGMA_M

    lam = (np.asarray(sigma, float) / SIGMA_M) ** (1.0 / ETA)
    return rotation_noise_reference(R, n, lam)


# -- exercise 3: what the network reads ------------------------------------------------------------------------------

def effector_inputs_reference(kind, value, lam):
    """What :func:`check_effector_inputs` expects: ``(c (B, 3), inputs (B, N, 6))`` for a batch of requests, the
    centroid of Sec. 2.1 (each request's position effectors weighted by ``1 - Lambda + 1e-3``, the origin when it
    has none) and the values re-referenced to it: a position and a look-at target minus ``c``, a rotation's 6D, a
    look-at direction and a position's three zeros unchanged."""
    kind, value, lam = np.asarray(kind), np.asarray(value, dtype=float), np.asarray(lam, dtype=float)
    w = (kind == 0) * (1.0 - lam + 1e-3)
    s = w.sum(axis=1)
    c = np.zeros((len(kind), 3))
    has = s > 0
    c[has] = (w[has, :, None] * value[has, :, :3]).sum(axis=1) / s[has, None]
    inputs = value.copy()
    moves = kind != 1
    inputs[..., :3] -= moves[..., None] * c[:, None, :]
    return c, inputs


def _inputs_with(kind, value, lam, weights="1 - lam", counted=(0,), shifted=(0, 2), columns=slice(0, 3),
                 whole_batch=False):
    """:func:`effector_inputs_reference` with one rule changed (the describe's slips)."""
    kind, value, lam = np.asarray(kind), np.asarray(value, dtype=float), np.asarray(lam, dtype=float)
    w = np.isin(kind, counted) * {"1 - lam": 1.0 - lam + 1e-3, "lam": lam, "equal": np.ones_like(lam),
                                      "no 1e-3": 1.0 - lam}[weights]
    with np.errstate(invalid="ignore", divide="ignore"):
        if whole_batch:
            c = np.broadcast_to((w[..., None] * value[..., :3]).sum(axis=(0, 1)) / w.sum(), (len(kind), 3))
        else:
            c = (w[..., None] * value[..., :3]).sum(axis=1) / w.sum(axis=1)[:, None]
    c = np.where(np.isfinite(c), c, 0.0)
    inputs = value.copy()
    inputs[..., columns] -= np.isin(kind, shifted)[..., None] * np.tile(c, 2)[:, None, columns]
    return c, inputs


@judged
def check_effector_inputs(my_inputs) -> bool:
    """Check ``my_inputs(kind (B, N), value (B, N, 6), lam (B, N)) -> (c (B, 3), inputs (B, N, 6))``: what the
    network of section 1 reads, the tolerance-weighted centroid of each request's position effectors and the six
    values of every effector re-referenced to it (:func:`effector_inputs_reference`)."""
    from ..models.protores.blocks import centroid, effector_inputs
    from ..models.protores.fast import NumpyPosingNet
    from ..rotations import matrix_to_sixd, quat_to_matrix, random_rotations

    rng = np.random.default_rng(7)
    names = ("position", "rotation", "look-at")

    def request(kinds, at, rng):
        """The values of one request: positions and look-at targets about ``at`` (metres), rotations in 6D, look-at
        directions of unit length."""
        kinds = np.asarray(kinds)
        value = np.zeros((len(kinds), 6))
        for i, k in enumerate(kinds):
            if k == 0:
                value[i, :3] = at + rng.normal(size=3) * 0.5
            elif k == 1:
                value[i] = matrix_to_sixd(quat_to_matrix(random_rotations(1, rng))[0])
            else:
                d = rng.normal(size=3)
                value[i] = np.concatenate([at + rng.normal(size=3) * 2.0, d / np.linalg.norm(d)])
        return value

    def describe_for(kind, value, lam, what):
        kind = np.asarray(kind)
        slips = {
            "the weights are 1 - Lambda + 1e-3 (a tight effector counts most), not Lambda":
                _inputs_with(kind, value, lam, weights="lam"),
            "a plain mean: the weights are 1 - Lambda + 1e-3": _inputs_with(kind, value, lam, weights="equal"),
            "the weights are 1 - Lambda + 1e-3: without the 1e-3 a loose effector (Lambda = 1) would not count":
                _inputs_with(kind, value, lam, weights="no 1e-3"),
            "look-at targets counted: only position effectors make the centroid":
                _inputs_with(kind, value, lam, counted=(0, 2)),
            "one centroid for the whole batch: each request has its own": _inputs_with(kind, value, lam,
                                                                                     whole_batch=True),
            "a rotation's 6D moved: a rotation does not change when the character moves":
                _inputs_with(kind, value, lam, shifted=(0, 1, 2)),
            "a look-at target left where it was: a point moves with the character":
                _inputs_with(kind, value, lam, shifted=(0,)),
            "the last three values moved too: a direction (and a position's zeros) does not move":
                _inputs_with(kind, value, lam, columns=slice(0, 6)),
        }
        B = len(kind)

        def describe(got, exp):
            gc, ec = got[:B * 3].reshape(B, 3), exp[:B * 3].reshape(B, 3)
            gi, ei = got[B * 3:].reshape(kind.shape + (6,)), exp[B * 3:].reshape(kind.shape + (6,))
            if not np.all(np.isfinite(got)):
                b = int(np.nonzero(~np.all(np.isfinite(gc), axis=1) | ~np.all(np.isfinite(gi), axis=(1, 2)))[0][0])
                return (f"request {b}{what} is not finite — "
                        + ("it has no position effector: its centroid is the origin" if not (kind[b] == 0).any()
                           else "a sum of weights of 0?"))
            for why, (sc, si) in slips.items():
                if np.allclose(gc, sc, atol=1e-7) and np.allclose(gi, si, atol=1e-7) \
                        and not (np.allclose(sc, ec, atol=1e-7) and np.allclose(si, ei, atol=1e-7)):
                    return why + what
            err_c = np.abs(gc - ec).max(axis=1)
            if err_c.max() > 1e-9 * max(1.0, np.abs(ec).max()):
                b = int(np.argmax(err_c))
                return (f"the centroid of request {b}{what}: got {np.round(gc[b], 4)}, expected {np.round(ec[b], 4)}"
                        + ("; it has no position effector: the origin" if not (kind[b] == 0).any() else ""))
            err = np.abs(gi - ei).max(axis=-1)
            b, i = np.unravel_index(int(np.argmax(err)), err.shape)
            return (f"request {b}, effector {i} (a {names[int(kind[b, i])]}){what}: got {np.round(gi[b, i], 4)}, "
                    f"expected {np.round(ei[b, i], 4)}")
        return describe

    cases = []

    def case(kind, value, lam, what=""):
        kind = np.asarray(kind)
        cases.append(((kind, value, lam), flat(*effector_inputs_reference(kind, value, lam)),
                      describe_for(kind, value, lam, what)))

    kinds = np.array([[0, 1, 2, 0, 2, 1, 0], [2, 0, 0, 1, 0, 2, 2], [0, 0, 0, 1, 2, 2, 1]])  # generic: 3 requests
    at = np.array([[4.0, 0.9, -3.0], [-20.0, 1.0, 7.0], [0.5, 1.2, 60.0]])
    case(kinds, np.stack([request(k, a, rng) for k, a in zip(kinds, at)]), rng.uniform(0, 1, kinds.shape))
    kinds = np.array([[1, 2, 2, 1], [0, 2, 0, 1]])  # the first request pins no position
    case(kinds, np.stack([request(k, a, rng) for k, a in zip(kinds, at[:2])]), rng.uniform(0, 1, kinds.shape),
         " (request 0 has no position effector)")
    kinds = np.array([[0, 0, 2, 0], [0, 1, 0, 2]])  # every position loose at the limit; one tight, one loose
    case(kinds, np.stack([request(k, a, rng) for k, a in zip(kinds, at[1:])]),
         np.array([[1.0, 1.0, 0.3, 1.0], [0.0, 0.5, 1.0, 0.2]]), " (Lambda = 1: weights of 1e-3)")
    case(np.array([[0]]), request([0], at[0], rng)[None], np.array([[0.4]]), " (one request, one effector)")
    kinds = np.array([[2, 0, 1, 0, 2]])
    case(kinds, request(kinds[0], at[2], rng)[None].astype(np.float32),
         rng.uniform(0, 1, kinds.shape).astype(np.float32), " (float32)")

    def both(kind, value, lam):
        return flat(*my_inputs(kind, value, lam))
    return report("check_effector_inputs", both, cases, atol=1e-9,
                  forbid=(centroid, effector_inputs, NumpyPosingNet._centroid, effector_inputs_reference),
                  arg_names=("kind", "value", "lam"))


__all__ = ["check_look_at_angle", "check_rotation_noise", "check_effector_inputs"]
