"""Compiled single-problem path of latent optimisation (:mod:`posekit.models.aegan.latent_opt`).

Introduced in ``notebooks/04_aegan_latent_space.ipynb``. One iteration on one pose is a few small
matrix-vector products through the generator and back; numpy's per-call overhead would cost several
times that arithmetic, so a single solve runs in these numba kernels: the generator's forward and
backward pass (:class:`posekit.models.aegan.numpy_nets.NumpyAEGAN`, parent-only SPL) and the same optimisers —
projected L-BFGS and Adam with the same stopping rule — for one problem. ``tests/models/test_aegan.py``
checks them against the batched numpy path.

The SPL is flattened joint by joint: ``order`` (joints by depth), ``par`` (parent or -1), ``A`` (J, 3, h)
parent weights, ``V`` (J, h, 3) and ``bo`` (J, 3) output layers, ``U`` (in, J h) and ``c`` (J h) the
shared first layer.
"""

from __future__ import annotations

import numpy as np

from ..._jit import njit

__all__ = ["flatten_generator", "needed_joints", "loss_grad", "lbfgs_one", "adam_one"]


def flatten_generator(net) -> tuple:
    """The arrays the kernels read, from a :class:`~posekit.models.aegan.numpy_nets.NumpyAEGAN` (parent-only SPL):
    ``(W, b, U, c, order, par, A, V, bo, UT, WT)``, ``UT`` (J h, H) and ``WT`` (H, d) the first two layers
    transposed, for the backward pass."""
    spl = net.g_spl
    J, h, o = spl.J, spl.hidden, spl.out
    A = np.zeros((J, o, h), np.float32)
    V = np.zeros((J, h, o), np.float32)
    bo = np.zeros((J, o), np.float32)
    par = np.full(J, -1, np.int64)
    order = []
    for js, anc, Al, Vl, bl, _, _ in spl.levels:
        if anc.shape[1] > 1:
            raise ValueError("the compiled path supports parent-only SPLs (ancestors='parent')")
        for r, j in enumerate(js):
            order.append(int(j))
            V[j], bo[j] = Vl[r], bl[r, 0]
            if anc.shape[1]:
                par[j], A[j] = int(anc[r, 0]), Al[r]
    U = np.ascontiguousarray(spl.U)
    W = np.ascontiguousarray(net.g_W)
    return (W, np.ascontiguousarray(net.g_b), U, np.ascontiguousarray(spl.c), np.array(order, np.int64), par, A, V,
            bo, np.ascontiguousarray(U.T), np.ascontiguousarray(W.T))


@njit
def needed_joints(cols, order, par):
    """The joints the loss reads — the targets' joints (feature column // 3) and their ancestors — in ``order``
    (parents first), as an int array: the only ones the forward and backward passes compute."""
    J = len(par)
    need = np.zeros(J, np.bool_)
    for i in range(len(cols)):
        j = cols[i] // 3
        while j >= 0 and not need[j]:
            need[j] = True
            j = par[j]
    n = 0
    for jj in range(J):
        if need[order[jj]]:
            n += 1
    out = np.empty(n, np.int64)
    n = 0
    for jj in range(J):
        if need[order[jj]]:
            out[n] = order[jj]
            n += 1
    return out


@njit
def _forward(z, W, b, U, c, path, par, A, V, bo, acc, hin, a, r, o):
    """The generator on code ``z`` (d,): its outputs ``o`` (J, 3) for the joints of ``path`` (parents first; the
    other rows of ``o`` are left as they were). Every sum runs in the order of the plain matrix product, so a
    joint's output does not depend on which others are computed. ``acc`` (H,) float64 holds the first layer's
    sums before the ReLU; ``hin`` (H,), ``a`` (J h,) and ``r`` (J, h) the hidden activations."""
    d, H = W.shape
    for k in range(H):
        acc[k] = b[k]
    for i in range(d):
        zi = z[i]
        for k in range(H):
            acc[k] += zi * W[i, k]
    for k in range(H):
        hin[k] = acc[k] if acc[k] > 0 else 0.0
    n = a.shape[0]
    for k in range(n):
        a[k] = c[k]
    for i in range(H):  # every column: one long product per hidden unit is faster than a short one per joint
        hi = hin[i]
        if hi != 0.0:
            for k in range(n):
                a[k] += hi * U[i, k]
    J, h, no = V.shape
    for jj in range(len(path)):
        j = path[jj]
        p = par[j]
        lo = j * h
        for u in range(h):
            s = a[lo + u]
            if p >= 0:
                for q in range(no):
                    s += o[p, q] * A[j, q, u]
            r[j, u] = s if s > 0 else 0.0
        for q in range(no):
            s = bo[j, q]
            for u in range(h):
                s += r[j, u] * V[j, u, q]
            o[j, q] = s


@njit
def _backward(gx, WT, UT, path, par, A, V, hin, r, go, ga, gh, gz):
    """The gradient ``gz`` (d,) of the loss from its gradient ``gx`` (J 3,) on the outputs, through the joints of
    ``path`` (the others have none); ``WT`` (H, d) and ``UT`` (J h, H) are the first two layers transposed, so
    each product runs along contiguous rows, in the order of the plain matrix product."""
    J, h, no = V.shape
    ga[:] = 0.0
    for jj in range(len(path)):
        j = path[jj]
        for q in range(no):
            go[j, q] = gx[j * no + q]
    for jj in range(len(path) - 1, -1, -1):
        j = path[jj]
        p = par[j]
        for u in range(h):
            g = 0.0
            if r[j, u] > 0:
                for q in range(no):
                    g += V[j, u, q] * go[j, q]
            ga[j * h + u] = g
        if p >= 0:
            for q in range(no):
                s = 0.0
                for u in range(h):
                    s += A[j, q, u] * ga[j * h + u]
                go[p, q] += s
    H, d = WT.shape
    gh[:] = 0.0
    for k in range(UT.shape[0]):  # a zero (a joint off the path, a unit the ReLU closed) adds nothing
        gk = ga[k]
        if gk != 0.0:
            for i in range(H):
                gh[i] += UT[k, i] * gk
    gz[:] = 0.0
    for i in range(H):
        if hin[i] > 0:
            s = gh[i]
            for m in range(d):
                gz[m] += WT[i, m] * s


@njit
def loss_grad(z, cols, target, scale, W, b, U, c, order, par, A, V, bo, UT, WT, path, work, err, gz):
    """Eq. (6) of one code ``z`` (d,): returns the loss (m^2); fills ``err`` (K,) metres and ``gz`` (d,).
    ``path``: :func:`needed_joints` of ``cols``."""
    hin, a, r, o, go, ga, gx, gh = work
    _forward(z, W, b, U, c, path, par, A, V, bo, gh, hin, a, r, o)
    J, no = o.shape
    gx[:] = 0.0
    x = o.reshape(J * no)
    f = 0.0
    for k in range(len(err)):
        e2 = 0.0
        for q in range(3):
            i = 3 * k + q
            dm = (x[cols[i]] - target[i]) * scale[i]
            e2 += dm * dm
            gx[cols[i]] = 2.0 * dm * scale[i]
        err[k] = np.sqrt(e2)
        f += e2
    _backward(gx, WT, UT, path, par, A, V, hin, r, go, ga, gh, gz)
    return f


def workspace(gen) -> tuple:
    """Scratch arrays for :func:`loss_grad` of a flattened generator."""
    W, _, U, _, _, _, _, V, _, _, _ = gen
    J, h, o = V.shape
    f = np.float32
    return (np.zeros(W.shape[1], f), np.zeros(U.shape[1], f), np.zeros((J, h), f), np.zeros((J, o), f),
            np.zeros((J, o), f), np.zeros(U.shape[1], f), np.zeros(J * o, f), np.zeros(W.shape[1], np.float64))


@njit
def _done(err, tol):
    for k in range(len(err)):
        if err[k] > tol[k]:
            return False
    return True


@njit
def lbfgs_one(z0, cols, target, scale, tol, W, b, U, c, order, par, A, V, bo, UT, WT, work, max_iter, memory, patience,
              stall, c1, backtracks):
    """:func:`posekit.models.aegan.latent_opt.lbfgs` for one problem: ``(best z (d,), iterations, errors (K,))``."""
    d = len(z0)
    K = len(tol)
    path = needed_joints(cols, order, par)
    z = np.minimum(np.maximum(z0.astype(np.float32), -1.0), 1.0)
    err, g = np.zeros(K), np.zeros(d, np.float32)
    f = loss_grad(z, cols, target, scale, W, b, U, c, order, par, A, V, bo, UT, WT, path, work, err, g)
    S, Y = np.zeros((memory, d), np.float32), np.zeros((memory, d), np.float32)
    count = 0
    best_z, best_f, best_err = z.copy(), f, err.copy()
    ref_f, since = f, 0
    nerr, ng = np.zeros(K), np.zeros(d, np.float32)
    rho, alpha = np.zeros(memory), np.zeros(memory)
    for t in range(1, max_iter + 1):
        if _done(err, tol) or since >= patience:
            return best_z, t - 1, best_err
        q = g.astype(np.float64)
        for k in range(memory):
            ys = 0.0
            for i in range(d):
                ys += S[k, i] * Y[k, i]
            rho[k] = 1.0 / (ys if ys != 0 else 1.0) if k < count else 0.0
            s = 0.0
            for i in range(d):
                s += S[k, i] * q[i]
            alpha[k] = rho[k] * s
            for i in range(d):
                q[i] -= alpha[k] * Y[k, i]
        if count > 0:
            ys, yy = 0.0, 0.0
            for i in range(d):
                ys += S[0, i] * Y[0, i]
                yy += Y[0, i] * Y[0, i]
            gamma = ys / (yy if yy != 0 else 1.0)
        else:
            gamma = 0.1 / max(np.abs(q).max(), 1e-12)
        rr = gamma * q
        for k in range(memory - 1, -1, -1):
            s = 0.0
            for i in range(d):
                s += Y[k, i] * rr[i]
            beta = rho[k] * s
            for i in range(d):
                rr[i] += S[k, i] * (alpha[k] - beta)
        dirn = -rr
        slope = 0.0
        for i in range(d):
            if (z[i] >= 1 and dirn[i] > 0) or (z[i] <= -1 and dirn[i] < 0):
                dirn[i] = 0.0
            slope += dirn[i] * g[i]
        if slope >= 0:
            gm = max(np.abs(g).max(), 1e-12)
            for i in range(d):
                dirn[i] = -g[i] * (0.1 / gm)
            count = 0
        step = 1.0
        ok = False
        nz = z.copy()
        nf = 0.0
        for attempt in range(backtracks + 1):
            for i in range(d):
                nz[i] = min(max(np.float64(z[i]) + step * dirn[i], -1.0), 1.0)
            nf = loss_grad(nz, cols, target, scale, W, b, U, c, order, par, A, V, bo, UT, WT, path, work, nerr, ng)
            dec = 0.0
            for i in range(d):
                dec += g[i] * (nz[i] - z[i])
            if nf <= f + c1 * dec:
                ok = True
                break
            step *= 0.5
        if ok:
            sy = 0.0
            for i in range(d):
                sy += (nz[i] - z[i]) * (ng[i] - g[i])
            if sy > 1e-12:
                for k in range(memory - 1, 0, -1):
                    S[k] = S[k - 1]
                    Y[k] = Y[k - 1]
                for i in range(d):
                    S[0, i] = nz[i] - z[i]
                    Y[0, i] = ng[i] - g[i]
                count = min(count + 1, memory)
            z[:] = nz
            f = nf
            err[:] = nerr
            g[:] = ng
        else:
            since = patience
        if f < best_f:
            best_f, best_z, best_err = f, z.copy(), err.copy()
        since += 1
        if best_f < ref_f * (1 - stall):
            ref_f, since = best_f, 0
    return best_z, max_iter, best_err


@njit
def adam_one(z0, cols, target, scale, tol, W, b, U, c, order, par, A, V, bo, UT, WT, work, max_iter, lr, patience,
             stall, b1, b2):
    """:func:`posekit.models.aegan.latent_opt.adam` for one problem: ``(best z (d,), iterations, errors (K,))``."""
    d = len(z0)
    K = len(tol)
    path = needed_joints(cols, order, par)
    z = np.minimum(np.maximum(z0.astype(np.float32), -1.0), 1.0)
    m, v = np.zeros(d, np.float32), np.zeros(d, np.float32)
    err, g = np.zeros(K), np.zeros(d, np.float32)
    best_z, best_f, best_err = z.copy(), np.inf, np.full(K, np.inf)
    ref_f, since = np.inf, 0
    for t in range(1, max_iter + 2):
        f = loss_grad(z, cols, target, scale, W, b, U, c, order, par, A, V, bo, UT, WT, path, work, err, g)
        if f < best_f:
            best_f, best_z, best_err = f, z.copy(), err.copy()
        since += 1
        improved = best_f < ref_f * (1 - stall)
        stalled = since >= patience and not improved
        if improved or since >= patience:
            ref_f, since = best_f, 0
        if _done(err, tol) or stalled or t > max_iter:
            return best_z, t - 1, best_err
        for i in range(d):
            m[i] = b1 * m[i] + (1 - b1) * g[i]
            v[i] = b2 * v[i] + (1 - b2) * g[i] * g[i]
            st = lr * (m[i] / (1 - b1 ** t)) / (np.sqrt(v[i] / (1 - b2 ** t)) + 1e-8)
            z[i] = min(max(z[i] - st, -1.0), 1.0)
    return best_z, max_iter, best_err
