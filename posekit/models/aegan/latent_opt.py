"""IK by latent optimisation (Victor & Meyer, JFIG 2020, Sec. 3.3, Eq. 6), on arrays.

Introduced in ``notebooks/04_aegan_latent_space.ipynb``. With a generator ``G`` whose every code is a
pose, IK for *any* set of joints ``T`` is a small optimisation over the code::

    z* = argmin_z  sum_{t in T} || G(z)_t - p_t ||^2,     z in [-1, 1]^d,   from z_0 = E(x_start)   (6)

distances in metres (the z-scored features scaled back by their standard deviations). No network is
trained per joint set: the same generator serves two targets or twenty.

Two optimisers, both starting at ``z_0`` and kept in the prior's cube:

* **Adam** (:func:`adam`) — batched: every problem of a batch takes its own steps, and drops out when it
  has stopped; a step leaving the cube is clipped back to it.
* **L-BFGS** (:func:`lbfgs`) — batched too: limited-memory quasi-Newton directions with a backtracking
  line search, projected on the cube.

**Stopping rule** (both): stop as soon as every effector is within its tolerance; else when the loss has
not fallen by ``stall`` (relative) over ``patience`` iterations; else after ``max_iter`` iterations. The
code returned is the best one seen (lowest loss), so the result is never worse than the start and never
NaN.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Problem", "OPTIMIZERS", "adam", "lbfgs", "optimize"]

OPTIMIZERS = ("adam", "lbfgs")


@dataclass
class Problem:
    """B latent-optimisation problems with one joint set.

    Attributes
    ----------
    z0 : ndarray, shape (B, d)
        Start codes (the encoded start poses).
    columns : ndarray of int, shape (3K,)
        Feature columns of the target joints.
    target : ndarray, shape (B, 3K)
        The targets as z-scored features (the start poses' root frames).
    scale : ndarray, shape (3K,)
        Metres per z-scored unit of those columns (the standard deviations).
    tol : ndarray, shape (B, K), metres
        Each effector's tolerance.
    """

    z0: np.ndarray
    columns: np.ndarray
    target: np.ndarray
    scale: np.ndarray
    tol: np.ndarray

    def loss(self, net, z, rows=slice(None)):
        """Eq. (6) of codes ``z`` (n, d) for problems ``rows``: loss (n,) in m^2, per-effector errors
        (n, K) in metres, and the gradient with respect to ``z`` (n, d)."""
        x, cache = net.forward(z)
        diff = (x[:, self.columns] - self.target[rows]) * self.scale  # metres
        err = np.sqrt((diff.reshape(len(z), -1, 3) ** 2).sum(-1))
        g_x = np.zeros_like(x)
        g_x[:, self.columns] = 2.0 * diff * self.scale
        return (diff ** 2).sum(-1), err, net.vjp(cache, g_x)


def adam(net, prob: Problem, max_iter: int = 100, lr: float = 0.05, patience: int = 10, stall: float = 1e-3,
         betas=(0.9, 0.999)):
    """Batched Adam on Eq. (6); returns ``(z (B, d), iterations (B,), errors (B, K))`` of the best codes."""
    z = np.clip(np.asarray(prob.z0, np.float32), -1, 1).copy()
    B = len(z)
    m, v = np.zeros_like(z), np.zeros_like(z)
    best_z = z.copy()
    best_f = np.full(B, np.inf)
    best_err = np.full(prob.tol.shape, np.inf)
    ref_f = np.full(B, np.inf)  # the loss `patience` iterations ago
    since = np.zeros(B, dtype=np.int64)
    iters = np.zeros(B, dtype=np.int64)
    active = np.arange(B)
    b1, b2 = betas
    for t in range(1, max_iter + 2):
        f, err, g = prob.loss(net, z[active], active)
        better = f < best_f[active]
        idx = active[better]
        best_f[idx], best_z[idx], best_err[idx] = f[better], z[idx], err[better]
        done = (err <= prob.tol[active]).all(-1)
        since[active] += 1
        improved = best_f[active] < ref_f[active] * (1 - stall)
        reset = active[improved | (since[active] >= patience)]
        stalled = (since[active] >= patience) & ~improved
        ref_f[reset], since[reset] = best_f[reset], 0
        stop = done | stalled | (t > max_iter)
        iters[active[stop]] = t - 1
        keep = ~stop
        if not keep.any():
            break
        active, g = active[keep], g[keep]
        m[active] = b1 * m[active] + (1 - b1) * g
        v[active] = b2 * v[active] + (1 - b2) * g * g
        step = lr * (m[active] / (1 - b1 ** t)) / (np.sqrt(v[active] / (1 - b2 ** t)) + 1e-8)
        z[active] = np.clip(z[active] - step, -1, 1)
    return best_z, iters, best_err


def lbfgs(net, prob: Problem, max_iter: int = 100, memory: int = 8, patience: int = 10, stall: float = 1e-3,
          c1: float = 1e-4, backtracks: int = 8):
    """Batched projected L-BFGS on Eq. (6); returns what :func:`adam` does.

    Each problem keeps its own ``memory`` last steps and gradient changes (Nocedal & Wright 2006,
    Alg. 7.4, the two-loop recursion) and takes a backtracking (Armijo, ``c1``) step along the direction,
    projected on the cube: a step is clipped to ``[-1, 1]`` and the parts of the direction that push
    against a face already reached are dropped. A direction that does not descend resets the memory to
    steepest descent. Iterations count direction updates; a backtrack evaluates the generator again.
    """
    z = np.clip(np.asarray(prob.z0, np.float32), -1, 1).astype(np.float32).copy()
    B, d = z.shape
    f, err, g = prob.loss(net, z)
    S = np.zeros((B, memory, d), np.float32)  # newest first
    Y = np.zeros((B, memory, d), np.float32)
    count = np.zeros(B, dtype=np.int64)
    best_z, best_f, best_err = z.copy(), f.copy(), err.copy()
    ref_f, since = f.copy(), np.zeros(B, dtype=np.int64)
    iters = np.zeros(B, dtype=np.int64)
    active = np.arange(B)
    for t in range(1, max_iter + 1):
        done = (err[active] <= prob.tol[active]).all(-1)
        stalled = since[active] >= patience
        stop = done | stalled
        iters[active[stop]] = t - 1
        active = active[~stop]
        if not len(active):
            break
        q = g[active].astype(np.float64)
        Sa, Ya, ca = S[active], Y[active], count[active]
        ys = (Sa * Ya).sum(-1)
        rho = np.where(np.arange(memory)[None] < ca[:, None], 1.0 / np.where(ys == 0, 1, ys), 0.0)
        alpha = np.zeros((len(active), memory))
        for k in range(memory):
            alpha[:, k] = rho[:, k] * (Sa[:, k] * q).sum(-1)
            q -= alpha[:, k, None] * Ya[:, k]
        yy = (Ya[:, 0] ** 2).sum(-1)
        gamma = np.where(ca > 0, ys[:, 0] / np.where(yy == 0, 1, yy), 0.1 / np.maximum(np.abs(q).max(-1), 1e-12))
        r = gamma[:, None] * q
        for k in range(memory - 1, -1, -1):
            beta = rho[:, k] * (Ya[:, k] * r).sum(-1)
            r += Sa[:, k] * (alpha[:, k] - beta)[:, None]
        za, ga, fa = z[active], g[active], f[active]
        dirn = -r
        dirn[((za >= 1) & (dirn > 0)) | ((za <= -1) & (dirn < 0))] = 0.0  # against a face already reached
        slope = (dirn * ga).sum(-1)
        reset = slope >= 0  # not a descent direction: steepest descent, memory cleared
        if reset.any():
            dirn[reset] = -ga[reset] * (0.1 / np.maximum(np.abs(ga[reset]).max(-1), 1e-12))[:, None]
            count[active[reset]] = 0
        step = np.ones(len(active))
        new_z = np.clip(za + dirn, -1, 1).astype(np.float32)
        nf, nerr, ng = prob.loss(net, new_z, active)
        ok = nf <= fa + c1 * (ga * (new_z - za)).sum(-1)
        for _ in range(backtracks):  # halve the step of the problems whose step did not decrease enough
            bad = np.nonzero(~ok)[0]
            if not len(bad):
                break
            step[bad] *= 0.5
            new_z[bad] = np.clip(za[bad] + step[bad, None] * dirn[bad], -1, 1)
            bf, berr, bg = prob.loss(net, new_z[bad], active[bad])
            nf[bad], nerr[bad], ng[bad] = bf, berr, bg
            ok[bad] = bf <= fa[bad] + c1 * (ga[bad] * (new_z[bad] - za[bad])).sum(-1)
        s_, y_ = new_z - za, ng - ga
        keep = ok & ((s_ * y_).sum(-1) > 1e-12)  # curvature condition: only then is the pair stored
        upd = active[keep]
        S[upd] = np.roll(S[upd], 1, axis=1)
        Y[upd] = np.roll(Y[upd], 1, axis=1)
        S[upd, 0], Y[upd, 0] = s_[keep], y_[keep]
        count[upd] = np.minimum(count[upd] + 1, memory)
        moved = active[ok]
        z[moved], f[moved], err[moved], g[moved] = new_z[ok], nf[ok], nerr[ok], ng[ok]
        since[active[~ok]] = patience  # no step decreased the loss: stalled
        better = f[active] < best_f[active]
        idx = active[better]
        best_f[idx], best_z[idx], best_err[idx] = f[idx], z[idx], err[idx]
        since[active] += 1
        improved = best_f[active] < ref_f[active] * (1 - stall)
        ref_f[active[improved]], since[active[improved]] = best_f[active[improved]], 0
    else:
        iters[active] = max_iter
    return best_z, iters, best_err


def optimize(net, prob: Problem, optimizer: str = "adam", **options):
    """:func:`adam` or :func:`lbfgs` by name."""
    if optimizer == "adam":
        return adam(net, prob, **options)
    if optimizer == "lbfgs":
        return lbfgs(net, prob, **options)
    raise ValueError(f"optimizer must be one of {', '.join(OPTIMIZERS)}, got {optimizer!r}")
