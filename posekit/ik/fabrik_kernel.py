"""The compiled kernel of :class:`posekit.ik.fabrik.FabrikSolver` (numba): full-body FABRIK with the
near-extended chain step. Read :mod:`posekit.ik.fabrik` first — it describes the algorithm and has
the readable numpy version of every step (:func:`~posekit.ik.single_chain.straighten_chain`);
:func:`posekit.ik.fabrik_batched.fabrik_batched` runs the same arithmetic in numpy over a batch (given one
problem at a time, it is the benchmark's uncompiled baseline).

Everything is written with scalar arithmetic and square roots only (no trigonometry), so the single
and the batched solver agree to the last bits.
"""

from __future__ import annotations

import numpy as np

from .._jit import njit
from .effector_errors import position_errors_into

EXTENDED_RATIO = 0.9
"""A chain whose target lies at >= this fraction of its reach is straightened directly (see
:func:`posekit.ik.single_chain.straighten_chain`). Plain FABRIK's contraction per iteration on a two-bone
chain is 0.38 at 90 % of the reach, 0.78 at 97 %, 0.92 at 99 % and 0.99 at 99.9 %. Measured on the
benchmark's 5-effector cases: 0.95 left 3.4 % (DeepMimic) unconverged, 0.9 and 0.8 0.1 %."""

MIN_AXIAL = 0.5
"""Every bone of a straightened chain must point forward along the chain's axis by at least this
cosine (60 deg): the straightening scales the bones' sideways parts, which is a well-behaved
one-parameter family only for bones that already point roughly along the chain."""

SECANT_STEPS = 8
"""Most secant steps for the straightening amount (they stop once converged); 8 bring the span to
within 1e-12 m of the target distance on the benchmark's chains, 6 left up to 1e-8 m on arms."""

_S_MAX = 1e12
_HINGE_SLACK = np.sin(np.radians(15.0))


@njit
def _span(bl, ax, lat, n, ex, ey, ez, sig, write):
    """Span ``sum_i bl[i] * normalize(ax[i] e + sig lat[i])`` of a straightened chain, as (x, y, z);
    with ``write``, ``lat[i]`` becomes the offset of joint ``i + 1`` from the chain's base."""
    sx = 0.0
    sy = 0.0
    sz = 0.0
    for i in range(n):
        vx = ax[i] * ex + sig * lat[i, 0]
        vy = ax[i] * ey + sig * lat[i, 1]
        vz = ax[i] * ez + sig * lat[i, 2]
        s = bl[i] / np.sqrt(vx * vx + vy * vy + vz * vz)
        sx += s * vx
        sy += s * vy
        sz += s * vz
        if write:
            lat[i, 0] = sx
            lat[i, 1] = sy
            lat[i, 2] = sz
    return sx, sy, sz


@njit
def _span2(bl, ax, lat, n, ex, ey, ez, sig):
    """Squared span |sum_i bl[i] * normalize(ax[i] e + sig lat[i])|^2 of a straightened chain."""
    sx, sy, sz = _span(bl, ax, lat, n, ex, ey, ez, sig, False)
    return sx * sx + sy * sy + sz * sz


@njit
def _straighten(back, chain, q, bl, R, d, wx, wy, wz, ax, lat, may_bend):
    """Straighten the chain ``q[0..n]`` (bone lengths ``bl``) until its span is ``d`` (fully if
    ``d >= R``), turn it about ``q[0]`` onto the direction ``w / d`` and write ``q[1..n]`` into
    ``back[chain[1..n]]``. Returns False (writing nothing) where the chain is not in the regime."""
    n = chain.shape[0] - 1
    ex = q[n, 0] - q[0, 0]
    ey = q[n, 1] - q[0, 1]
    ez = q[n, 2] - q[0, 2]
    S = np.sqrt(ex * ex + ey * ey + ez * ez)
    if S < 1e-12 or (d < S and not may_bend):
        return False
    ex /= S
    ey /= S
    ez /= S
    for i in range(n):  # split every bone into its part along the chain's axis e and sideways
        vx = q[i + 1, 0] - q[i, 0]
        vy = q[i + 1, 1] - q[i, 1]
        vz = q[i + 1, 2] - q[i, 2]
        a = vx * ex + vy * ey + vz * ez
        if a < MIN_AXIAL * bl[i]:
            return False
        ax[i] = a
        lat[i, 0] = vx - a * ex
        lat[i, 1] = vy - a * ey
        lat[i, 2] = vz - a * ez
    sig = 0.0  # d >= R: the paper's unreachable case, straight at the target
    if d < R:
        # span^2(s) with sideways parts scaled by sqrt(s): R^2 at s = 0, S^2 at s = 1, about
        # linear in s; secant steps from those two points (the first one is the linear guess)
        d2 = d * d
        g0 = R * R - d2
        g1 = S * S - d2
        if g0 - g1 < 1e-12 * R * R:
            return False  # straight already: no sideways part to scale
        s0 = 0.0
        s1 = 1.0
        for _ in range(SECANT_STEPS):
            if g1 != g0 and abs(g1) > 1e-13 * d2:  # (stop once converged: no rounding noise)
                s2 = min(max(s1 - g1 * (s1 - s0) / (g1 - g0), 0.0), _S_MAX)
                s0 = s1
                g0 = g1
                s1 = s2
                g1 = _span2(bl, ax, lat, n, ex, ey, ez, np.sqrt(s1)) - d2
        sig = np.sqrt(s1)
    # rebuild as offsets from q[0], then the rotation a -> b (unit vectors, k = a x b, c = a . b):
    # x -> c x + k x x + k (k . x) / (1 + c)
    sx, sy, sz = _span(bl, ax, lat, n, ex, ey, ez, sig, True)
    sL = np.sqrt(sx * sx + sy * sy + sz * sz)
    ax_ = sx / sL
    ay_ = sy / sL
    az_ = sz / sL
    bx = wx / d
    by = wy / d
    bz = wz / d
    kx = ay_ * bz - az_ * by
    ky = az_ * bx - ax_ * bz
    kz = ax_ * by - ay_ * bx
    c = ax_ * bx + ay_ * by + az_ * bz
    if c < -1.0 + 1e-9:
        return False  # pointing straight away from the target: left to the FABRIK passes
    f = 1.0 / (1.0 + c)
    for i in range(n):
        x = lat[i, 0]
        y = lat[i, 1]
        z = lat[i, 2]
        kd = (kx * x + ky * y + kz * z) * f
        j = chain[i + 1]
        back[j, 0] = q[0, 0] + (c * x + (ky * z - kz * y) + kx * kd)
        back[j, 1] = q[0, 1] + (c * y + (kz * x - kx * z) + ky * kd)
        back[j, 2] = q[0, 2] + (c * z + (kx * y - ky * x) + kz * kd)
    return True


@njit
def _extended_chain(back, lengths, chain, tx, ty, tz, ratio, q, bl, ax, lat, may_bend):
    """The near-extended step on one effector's chain ``chain`` (its base first): place the chain
    forward from its base towards the backward positions, find its longest end part whose target
    lies at >= ``ratio`` of its reach and straighten that (:func:`_straighten`)."""
    n = chain.shape[0] - 1
    b = chain[0]
    q[0, 0] = back[b, 0]
    q[0, 1] = back[b, 1]
    q[0, 2] = back[b, 2]
    R = 0.0
    for i in range(1, n + 1):  # the same arithmetic as the forward pass
        j = chain[i]
        ux = back[j, 0] - q[i - 1, 0]
        uy = back[j, 1] - q[i - 1, 1]
        uz = back[j, 2] - q[i - 1, 2]
        L = np.sqrt(ux * ux + uy * uy + uz * uz)
        if L < 1e-12:
            ux, uy, uz, L = 0.0, 1.0, 0.0, 1.0
        ux /= L
        uy /= L
        uz /= L
        q[i, 0] = q[i - 1, 0] + lengths[j] * ux
        q[i, 1] = q[i - 1, 1] + lengths[j] * uy
        q[i, 2] = q[i - 1, 2] + lengths[j] * uz
        bl[i - 1] = lengths[j]
        R += lengths[j]
    for m in range(n - 1):  # end parts of >= 2 bones (one bone is what the forward pass does)
        wx = tx - q[m, 0]
        wy = ty - q[m, 1]
        wz = tz - q[m, 2]
        d = np.sqrt(wx * wx + wy * wy + wz * wz)
        if d >= ratio * R and d > 1e-12:
            if _straighten(back, chain[m:], q[m:], bl[m:], R, d, wx, wy, wz, ax, lat, may_bend):
                return True
        R -= bl[m]
    return False


@njit
def _fabrik_tree(pos, parents, lengths, child_start, child_idx, active, fixed, slot, eff_idx, targets, tols,
                 max_iter, limit_cos, no_fwd, left_hip, right_hip, use_constraints, chain_start, chain_idx,
                 chain_bend, ext_ratio):
    """Full-body FABRIK in place on ``pos`` (J, 3). Returns (iterations, converged).

    ``chain_idx[chain_start[k]:chain_start[k + 1]]`` is the k-th effector chain, base first (ordered
    so that an effector's chain comes after the chains of effectors above it)."""
    J = pos.shape[0]
    K = targets.shape[0]
    back = pos.copy()
    C = chain_start.shape[0] - 1
    nmax = 1
    for k in range(C):
        nmax = max(nmax, chain_start[k + 1] - chain_start[k])
    q = np.empty((nmax, 3))
    bl = np.empty(nmax)
    ax = np.empty(nmax)
    lat = np.empty((nmax, 3))
    err = np.empty(K)
    it = 0
    while True:
        position_errors_into(pos, eff_idx, targets, err)  # the shared error (posekit.ik.effectors)
        done = True
        for k in range(K):
            if err[k] > tols[k]:
                done = False
        if done or it >= max_iter:
            return it, done
        # ---- backward: effectors on their targets, sub-bases at the centroid of their proposals
        for j in range(J - 1, -1, -1):
            if fixed[j] or not active[j]:
                back[j, 0] = pos[j, 0]
                back[j, 1] = pos[j, 1]
                back[j, 2] = pos[j, 2]
                continue
            if slot[j] >= 0:
                back[j, 0] = targets[slot[j], 0]
                back[j, 1] = targets[slot[j], 1]
                back[j, 2] = targets[slot[j], 2]
                continue
            sx = 0.0
            sy = 0.0
            sz = 0.0
            n = 0
            for ci in range(child_start[j], child_start[j + 1]):
                c = child_idx[ci]
                if not active[c]:
                    continue
                ux = pos[j, 0] - back[c, 0]
                uy = pos[j, 1] - back[c, 1]
                uz = pos[j, 2] - back[c, 2]
                L = np.sqrt(ux * ux + uy * uy + uz * uz)
                if L < 1e-12:
                    ux = pos[j, 0] - pos[c, 0]
                    uy = pos[j, 1] - pos[c, 1]
                    uz = pos[j, 2] - pos[c, 2]
                    L = np.sqrt(ux * ux + uy * uy + uz * uz)
                s = lengths[c] / L
                sx += back[c, 0] + ux * s
                sy += back[c, 1] + uy * s
                sz += back[c, 2] + uz * s
                n += 1
            back[j, 0] = sx / n
            back[j, 1] = sy / n
            back[j, 2] = sz / n
        # ---- near-extended chains: straightened at their targets
        for k in range(C):
            c0 = chain_start[k]
            c1 = chain_start[k + 1]
            e = slot[chain_idx[c1 - 1]]
            _extended_chain(back, lengths, chain_idx[c0:c1], targets[e, 0], targets[e, 1], targets[e, 2],
                            ext_ratio, q, bl, ax, lat, chain_bend[k])
        # ---- forward: from the fixed base outwards, keeping bone lengths
        for j in range(J):
            if fixed[j]:
                continue
            p = parents[j]
            if active[j]:
                ux = back[j, 0] - pos[p, 0]
                uy = back[j, 1] - pos[p, 1]
                uz = back[j, 2] - pos[p, 2]
            else:
                ux = pos[j, 0] - pos[p, 0]
                uy = pos[j, 1] - pos[p, 1]
                uz = pos[j, 2] - pos[p, 2]
            L = np.sqrt(ux * ux + uy * uy + uz * uz)
            if L < 1e-12:
                ux, uy, uz, L = 0.0, 1.0, 0.0, 1.0
            ux /= L
            uy /= L
            uz /= L
            if use_constraints and parents[p] >= 0:
                ux, uy, uz = _constrain(pos, parents, j, p, ux, uy, uz, limit_cos, no_fwd, left_hip, right_hip)
            pos[j, 0] = pos[p, 0] + lengths[j] * ux
            pos[j, 1] = pos[p, 1] + lengths[j] * uy
            pos[j, 2] = pos[p, 2] + lengths[j] * uz
        it += 1


@njit
def _constrain(pos, parents, j, p, ux, uy, uz, limit_cos, no_fwd, left_hip, right_hip):
    """Joint limits of the forward pass (Sec. 5 of the paper, as cones): the unit bone direction u
    of joint j, turned back into its allowed region relative to the parent bone."""
    g = parents[p]
    ex = pos[p, 0] - pos[g, 0]
    ey = pos[p, 1] - pos[g, 1]
    ez = pos[p, 2] - pos[g, 2]
    eL = np.sqrt(ex * ex + ey * ey + ez * ez)
    if eL <= 1e-12:
        return ux, uy, uz
    ex /= eL
    ey /= eL
    ez /= eL
    if no_fwd[j] and left_hip >= 0:
        # hinge rule: with lat = left hip - right hip and f = lat x e (the side a knee folds to), a
        # bone bending the wrong way (u.f < -sin 15 deg) is mirrored to the right side
        lx = pos[left_hip, 0] - pos[right_hip, 0]
        ly = pos[left_hip, 1] - pos[right_hip, 1]
        lz = pos[left_hip, 2] - pos[right_hip, 2]
        px = ly * ez - lz * ey
        py = lz * ex - lx * ez
        pz = lx * ey - ly * ex
        pL = np.sqrt(px * px + py * py + pz * pz)
        if pL > 1e-12:
            px /= pL
            py /= pL
            pz /= pL
            s = ux * px + uy * py + uz * pz
            if s < -_HINGE_SLACK:
                ux -= 2.0 * s * px
                uy -= 2.0 * s * py
                uz -= 2.0 * s * pz
    cosang = ux * ex + uy * ey + uz * ez
    if cosang < limit_cos[j]:  # outside the cone: rotate onto its rim
        vx = ux - cosang * ex
        vy = uy - cosang * ey
        vz = uz - cosang * ez
        vL = np.sqrt(vx * vx + vy * vy + vz * vz)
        if vL < 1e-12:  # pointing straight back: any perpendicular will do
            vx, vy, vz = -ey, ex, 0.0
            vL = np.sqrt(vx * vx + vy * vy)
            if vL < 1e-12:
                vx, vy, vz, vL = 0.0, -ez, ey, np.sqrt(ez * ez + ey * ey)
        sin_l = np.sqrt(max(0.0, 1.0 - limit_cos[j] * limit_cos[j]))
        ux = limit_cos[j] * ex + sin_l * vx / vL
        uy = limit_cos[j] * ey + sin_l * vy / vL
        uz = limit_cos[j] * ez + sin_l * vz / vL
    return ux, uy, uz
