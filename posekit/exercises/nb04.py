"""Checkers for ``notebooks/04_aegan_latent_space.ipynb``.

Section 1 builds the *sparse* structured prediction layer by hand (each joint reads its parent's output); exercise 1
asks for the *dense* variant it only names (each joint reads all of its ancestors' outputs), in NumPy. Section 2
states the AE-GAN's losses; exercise 3 asks for a discriminator's and the generator's adversarial losses and their
gradients with respect to the logits, finite for logits of any size. Each checker starts with a generic case,
accepts float32 answers, and refuses an answer that calls the posekit function it is compared against or changes
its inputs.
"""

from __future__ import annotations

import numpy as np

from ._check import flat, report
from ._judge import judged


# -- exercise 1: the dense SPL -----------------------------------------------------------------------------------

def _ancestors(parents, j):
    """Joint ``j``'s ancestors, nearest first (parent, grandparent, ..., root)."""
    out, k = [], int(parents[j])
    while k >= 0:
        out.append(k)
        k = int(parents[k])
    return out


def spl_all_reference(h, parents, U, c, A, V, d):
    """What :func:`check_spl_all` expects: the dense SPL (Aksan et al. 2019, Eq. 4 with every ancestor),
    ``o_j = V_j relu(U_j h + A_j [o_parent, o_grandparent, ..., o_root] + c_j) + d_j``, shape (N, J, out).

    Equal to :class:`posekit.models.aegan.spl.StructuredPrediction` with ``ancestors="all"`` when ``U_j``, ``c_j``
    are the rows of its ``shared`` layer, ``A_j`` its ``anc`` matrix transposed and ``V_j``, ``d_j`` its output
    weights transposed and bias (``tests/test_exercises.py`` checks it)."""
    h = np.asarray(h, dtype=float)
    J = len(parents)
    outs: list = [None] * J
    for j in sorted(range(J), key=lambda j: len(_ancestors(parents, j))):  # parents before children
        pre = h @ np.asarray(U[j], float).T + np.asarray(c[j], float)
        anc = _ancestors(parents, j)
        if anc:
            pre = pre + np.concatenate([outs[a] for a in anc], axis=1) @ np.asarray(A[j], float).T
        outs[j] = np.maximum(pre, 0.0) @ np.asarray(V[j], float).T + np.asarray(d[j], float)
    return np.stack(outs, axis=1)


def spl_all_cases(seed: int = 40):
    """The cases of :func:`check_spl_all`: ``(h, parents, U, c, A, V, d)`` tuples, generic first.

    A small tree in index order; a tree whose parents come *after* their children (an answer that visits the joints
    by index reads an output not computed yet); two roots; the body of the Bandai skeleton (21 joints, the lesson's);
    a chain listed backwards (depth 4: every ancestor's place in the concatenation counts); one joint alone; the
    parents as an array; float32 inputs.
    """
    from ..data.bandai_mini import load_bandai_mini
    from ..models.aegan.networks import body_parents

    rng = np.random.default_rng(seed)

    def weights(parents, N, H, k, out, dtype=float):
        J = len(parents)
        U = rng.normal(size=(J, k, H)) / np.sqrt(H)
        c = rng.normal(size=(J, k)) * 0.3
        A = [rng.normal(size=(k, out * len(_ancestors(parents, j)))) / np.sqrt(max(1, out * len(_ancestors(parents, j))))
             for j in range(J)]
        V = rng.normal(size=(J, out, k)) / np.sqrt(k)
        d = rng.normal(size=(J, out)) * 0.3
        h = rng.normal(size=(N, H))
        cast = lambda a: np.asarray(a, dtype=dtype)  # noqa: E731
        return cast(h), cast(U), cast(c), [cast(a) for a in A], cast(V), cast(d)

    out = []
    for parents, (N, H, k, o), dtype in (
            ([-1, 0, 1, 0, 3], (4, 5, 6, 3), float),           # generic: in index order, depth 2
            ([2, -1, 1, 2], (3, 4, 5, 3), float),              # children listed before their parents
            ([-1, -1, 0, 1, 2], (3, 4, 5, 2), float),          # two roots
            (None, (2, 6, 4, 3), float),                       # the lesson's body tree, 21 joints
            ([1, 2, 3, 4, -1], (3, 4, 5, 2), float),           # a chain listed backwards: depth 4
            ([-1], (2, 3, 4, 3), float),                       # one joint: a root alone
            ("array", (3, 4, 5, 3), float),                    # the parents as an int array
            ([-1, 0, 0, 1, 3], (4, 5, 6, 3), np.float32)):     # float32 inputs
        if parents is None:
            parents = [int(p) for p in body_parents(load_bandai_mini().skeleton)]
        as_array = isinstance(parents, str)
        if as_array:
            parents = [3, 0, -1, 2, 0]
        h, U, c, A, V, d = weights(parents, N, H, k, o, dtype)
        out.append((h, np.array(parents) if as_array else list(parents), U, c, A, V, d))
    return out


@judged
def check_spl_all(my_spl_all) -> bool:
    """Check ``my_spl_all(h (N, H), parents (J,), U (J, k, H), c (J, k), A (J arrays (k, out * depth_j)),
    V (J, out, k), d (J, out)) -> (N, J, out)``: the dense SPL, every joint reading all of its ancestors' outputs
    nearest first (:func:`spl_all_reference`); ``(N, J * out)``, the layout of posekit's layer, is accepted too."""
    from ..models.aegan.numpy_nets import NumpySPL, tree_levels
    from ..models.aegan.spl import StructuredPrediction

    def describe_for(parents):
        def describe(got, exp):
            err = np.abs(got - exp).max(axis=(0, 2))
            depths = [len(_ancestors(parents, k)) for k in range(len(parents))]
            # the shallowest joint that is off: a mistake there runs down to every joint below it
            j = min((k for k in range(len(parents)) if err[k] > 1e-6 * max(1.0, np.abs(exp[:, k]).max())),
                    key=lambda k: (depths[k], -err[k]), default=int(np.argmax(err)))
            depth = depths[j]
            said = f"joint {j} is off by up to {err[j]:.3g}"
            if np.allclose(got[:, j], 0) and not np.allclose(exp[:, j], 0):
                return said + ": it was never computed (every joint visited? there may be several roots)"
            if depth == 0:
                return (said + " (a root: it reads no ancestor): o_j = V_j relu(U_j h + c_j) + d_j — relu before "
                        "V_j, both biases, h @ U_j.T?")
            if np.allclose(got[:, [k for k in range(len(parents)) if not _ancestors(parents, k)]],
                           exp[:, [k for k in range(len(parents)) if not _ancestors(parents, k)]]) and depth == 1:
                return (said + f" (depth 1: it reads its parent {int(parents[j])}'s output): A_j o_parent inside the "
                        "relu, the parent computed first (parents may come after their children in the list)?")
            return (said + f" (depth {depth}: A_j reads all {depth} ancestors' outputs side by side, nearest first — "
                    "parent, grandparent, ..., root — each computed before it)")
        return describe

    cases = [(args, spl_all_reference(*args), describe_for(args[1])) for args in spl_all_cases()]

    def shaped(h, parents, *rest):
        got = my_spl_all(h, parents, *rest)
        n, J, o = len(h), len(parents), np.shape(rest[-1])[-1]
        if np.shape(got) == (n, J * o):  # posekit's layout: the joints' outputs side by side
            got = np.reshape(got, (n, J, o))
        return got
    return report("check_spl_all", shaped, cases, atol=1e-9,
                  forbid=(StructuredPrediction.forward, NumpySPL.forward, tree_levels, spl_all_reference),
                  arg_names=("h", "parents", "U", "c", "A", "V", "d"))


# -- exercise 2: Eq. (6) and its gradient --------------------------------------------------------------------------

@judged
def check_latent_loss(my_loss) -> bool:
    """Check ``my_loss(x (F,), target (3K,), columns (3K,), scale (3K,)) -> (loss, grad_x (F,))``: Eq. (6)'s
    sum of squared target distances in metres (``(x[columns] - target) * scale``) and its gradient with
    respect to the z-scored pose ``x`` (zero outside ``columns``)."""
    from ..models.aegan.latent_opt import Problem

    rng = np.random.default_rng(4)
    cases = []

    def describe(got, exp):
        if not np.isclose(got[0], exp[0], atol=1e-9, rtol=1e-5):
            return (f"the loss is {got[0]:.6g}, expected {exp[0]:.6g}: metres = (z-scored x - target) x scale, "
                    "squared, summed (not a mean)?")
        k = int(np.argmax(np.abs(got[1:] - exp[1:])))
        return (f"the loss is right; the gradient differs at x[{k}]: got {got[1 + k]:.6g}, expected {exp[1 + k]:.6g} "
                "(2 x difference x scale on the target columns, 0 elsewhere?)")

    def case(x, t, cols, sc):
        x, t, sc = (np.asarray(a) for a in (x, t, sc))
        diff = (x[cols].astype(float) - t) * sc
        g = np.zeros(len(x))
        g[cols] = 2 * diff * sc
        cases.append(((x, t, np.array(cols), sc), np.concatenate([[np.sum(diff ** 2)], g]), describe))
    for F, cols in ((9, [3, 4, 5]), (63, list(range(27, 33))), (12, [0, 1, 2, 9, 10, 11])):
        case(rng.normal(size=F), rng.normal(size=len(cols)), cols, rng.uniform(0.05, 0.3, len(cols)))
    # one scale per column (an answer using one scale for all fails); the targets already met: loss and gradient 0
    x = rng.normal(size=15)
    case(x, rng.normal(size=6), [12, 13, 14, 3, 4, 5], np.array([0.01, 0.5, 0.02, 0.3, 0.04, 0.2]))
    case(x, x[[6, 7, 8]].copy(), [6, 7, 8], np.array([0.1, 0.2, 0.3]))
    x32 = rng.normal(size=9).astype(np.float32)  # a float32 pose, as the numpy generator makes them
    case(x32, rng.normal(size=3).astype(np.float32), [0, 1, 2], rng.uniform(0.05, 0.3, 3).astype(np.float32))

    def both(*a):
        loss, grad = my_loss(*a)
        return flat(loss, grad)
    return report("check_latent_loss", both, cases, atol=1e-9, forbid=(Problem.loss,),
                  arg_names=("x", "target", "columns", "scale"))


# -- exercise 3: the adversarial losses and their gradients -----------------------------------------------------------

def _softplus(x):
    return np.logaddexp(0.0, np.asarray(x, float))


def _sigmoid(x):
    x = np.asarray(x, float)
    e = np.exp(-np.abs(x))
    return np.where(x >= 0, 1.0 / (1.0 + e), e / (1.0 + e))


def adversarial_reference(real_logits, fake_logits, smooth):
    """What :func:`check_adversarial` expects, from posekit's training loss (``posekit.models.aegan.train._bce``,
    torch's binary cross-entropy on logits) and torch's autograd, flat: ``[loss_D, dloss_D/dreal (Nr,),
    dloss_D/dfake (Nf,), loss_G, dloss_G/dfake (Nf,)]``."""
    import torch

    from ..models.aegan.train import _bce

    r = torch.tensor(np.asarray(real_logits, float), dtype=torch.float64, requires_grad=True)
    f = torch.tensor(np.asarray(fake_logits, float), dtype=torch.float64, requires_grad=True)
    loss_d = _bce(r, float(smooth)) + _bce(f, 0.0)
    g_real, g_fake = torch.autograd.grad(loss_d, (r, f))
    f2 = torch.tensor(np.asarray(fake_logits, float), dtype=torch.float64, requires_grad=True)
    loss_g = _bce(f2, 1.0)
    (g_gen,) = torch.autograd.grad(loss_g, (f2,))
    return np.concatenate([[loss_d.item()], g_real.numpy(), g_fake.numpy(), [loss_g.item()], g_gen.numpy()])


def adversarial_cases(seed: int = 5):
    """The cases of :func:`check_adversarial`: ``(real_logits, fake_logits, smooth)``, generic first.

    Logits near 0 with the lesson's smoothing 0.9 (real and fake of different counts); no smoothing; the
    discriminator winning (real far above 0, fake far below: the saturating form's flat end); logits of +-1000, +-745
    and 40 in both terms (a naive ``log(sigmoid(l))`` or ``exp(l) / (1 + exp(l))`` is inf or nan there); one logit
    each; another smoothing.
    """
    rng = np.random.default_rng(seed)
    return [
        (rng.normal(0.0, 1.0, 6), rng.normal(0.0, 1.0, 4), 0.9),
        (rng.normal(0.5, 2.0, 5), rng.normal(-0.5, 2.0, 7), 1.0),
        (rng.normal(6.0, 1.0, 4), rng.normal(-6.0, 1.0, 9), 0.9),
        (np.array([-1000.0, 0.0, 1000.0]), np.array([1000.0, -1000.0, 2.0, -745.0]), 0.9),
        (np.array([745.0, 40.0, -40.0]), np.array([-745.0, 40.0]), 1.0),
        (np.array([0.3]), np.array([-2.0]), 0.8),
    ]


@judged
def check_adversarial(my_adversarial) -> bool:
    """Check ``my_adversarial(real_logits (Nr,), fake_logits (Nf,), smooth) -> (loss_D, grad_real (Nr,),
    grad_fake (Nf,), loss_G, grad_G (Nf,))``: a discriminator's loss of section 2, ``BCE(real, smooth) + BCE(fake,
    0)`` (each a mean over its own logits), and the non-saturating generator loss ``BCE(fake, 1)``, with their
    gradients with respect to the logits, finite for logits of any size (:func:`adversarial_reference`)."""
    from ..models.aegan.train import _bce

    F = __import__("torch.nn.functional", fromlist=["binary_cross_entropy_with_logits"])

    def describe_for(real, fake, smooth):
        nr, nf = len(real), len(fake)
        parts = (("loss_D", "the discriminator's loss", slice(0, 1)),
                 ("grad_real", "the discriminator's gradient with respect to real_logits", slice(1, 1 + nr)),
                 ("grad_fake", "the discriminator's gradient with respect to fake_logits", slice(1 + nr, 1 + nr + nf)),
                 ("loss_G", "the generator's loss", slice(1 + nr + nf, 2 + nr + nf)),
                 ("grad_G", "the generator's gradient with respect to fake_logits", slice(2 + nr + nf, None)))
        logits = {"loss_D": None, "grad_real": real, "grad_fake": fake, "loss_G": None, "grad_G": fake}

        def describe(got, exp):
            bad = [(key, what, s) for key, what, s in parts
                   if not np.allclose(got[s], exp[s], atol=1e-9, rtol=1e-5) or not np.all(np.isfinite(got[s]))]
            key, what, s = bad[0]
            g, e = got[s], exp[s]
            i = int(np.argmax(np.where(np.isfinite(g), np.abs(g - e), np.inf)))
            at = f"[{i}] (logit {logits[key][i]:g})" if logits[key] is not None else ""
            said = f"{what}{at} is {g[i]:.6g}, expected {e[i]:.6g}"
            if not np.isfinite(g[i]):
                return (said + ": not finite — log(sigmoid(l)) and exp(l) overflow far from 0; write "
                        "log(1 + exp(x)) as np.logaddexp(0, x), and sigmoid from exp(-|l|)")
            if key == "loss_D":
                smooth1 = np.mean(_softplus(-real)) + np.mean(_softplus(fake))
                pooled = (smooth * _softplus(-real) + (1 - smooth) * _softplus(real)).sum() + _softplus(fake).sum()
                if np.isclose(g[0], smooth1) and smooth != 1.0:
                    return said + f": real logits are labelled smooth = {smooth:g}, not 1 (the smoothing ignored?)"
                if np.isclose(g[0], pooled) or np.isclose(g[0], pooled / (nr + nf)):
                    return said + ": a mean over the real logits plus a mean over the fake ones (not one sum or mean)"
                return said + (": BCE(l, y) = y log(1 + exp(-l)) + (1 - y) log(1 + exp(l)); real labelled smooth, "
                               "fake 0, each term a mean")
            if key == "loss_G":
                if np.isclose(g[0], -np.mean(_softplus(fake))):
                    return said + (": that is the saturating form log(1 - D(fake)); the non-saturating loss is "
                                   "-log D(fake) = BCE(fake, 1)")
                return said + ": the mean of -log sigmoid(l) = log(1 + exp(-l)) over the fake logits?"
            n = nr if key == "grad_real" else nf
            if np.isclose(g[i], e[i] * n):
                return said + f": the loss is a mean, so its gradient is divided by N = {n}"
            if np.isclose(g[i], -e[i]):
                return said + ": the sign — d BCE(l, y) / dl = sigmoid(l) - y"
            label = {"grad_real": f"smooth = {smooth:g}", "grad_fake": "0", "grad_G": "1"}[key]
            return said + f": (sigmoid(l) - {label}) / {n}, the derivative with respect to the logit (not to D)"
        return describe

    cases = [((np.array(r), np.array(f), s), adversarial_reference(r, f, s), describe_for(r, f, s))
             for r, f, s in adversarial_cases()]

    def flattened(*a):
        return flat(*my_adversarial(*a))
    return report("check_adversarial", flattened, cases, atol=1e-9,
                  forbid=(_bce, F.binary_cross_entropy_with_logits, adversarial_reference),
                  arg_names=("real_logits", "fake_logits", "smooth"))


__all__ = ["check_spl_all", "check_latent_loss", "check_adversarial"]
