"""Reference solutions of lesson 04's exercises (instructor version; ``posekit exercises solutions 04`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_spl_all", "exercise_latent_loss", "exercise_adversarial"]


def exercise_spl_all(h, parents, U, c, A, V, d):
    """The dense structured prediction layer (Aksan et al. 2019, Eq. 4 with every ancestor), in NumPy.

    ``o_j = V_j relu(U_j h + A_j [o_parent, o_grandparent, ..., o_root] + c_j) + d_j``: every joint reads the layer's
    input and the outputs of *all* its ancestors, side by side, nearest first. The joints are visited by depth, so
    that every ancestor's output exists before a joint reads it, whatever the order of ``parents``.

    Parameters
    ----------
    h : ndarray, shape (N, H)
        The layer's input, one row per sample.
    parents : sequence of int, length J
        Parent of each joint, -1 for a root (several roots are fine); any order.
    U : ndarray, shape (J, k, H)
    c : ndarray, shape (J, k)
    A : list of J ndarrays, shapes (k, out * depth_j)
        Each joint's weights on its ancestors' outputs (shape (k, 0) at a root).
    V : ndarray, shape (J, out, k)
    d : ndarray, shape (J, out)

    Returns
    -------
    ndarray, shape (N, J, out)
    """
    import numpy as np

    h = np.asarray(h, dtype=float)
    J = len(parents)
    chains = []
    for j in range(J):  # each joint's ancestors, nearest first
        chain, k = [], int(parents[j])
        while k >= 0:
            chain.append(k)
            k = int(parents[k])
        chains.append(chain)
    outs = [None] * J
    for j in sorted(range(J), key=lambda j: len(chains[j])):  # by depth: ancestors first
        pre = h @ np.asarray(U[j], float).T + c[j]
        if chains[j]:
            pre = pre + np.concatenate([outs[a] for a in chains[j]], axis=1) @ np.asarray(A[j], float).T
        outs[j] = np.maximum(pre, 0.0) @ np.asarray(V[j], float).T + d[j]
    return np.stack(outs, axis=1)


def exercise_latent_loss(x, target, columns, scale):
    """Eq. (6) of Victor & Meyer 2020 (AE-GAN) for one decoded pose, and its gradient with respect to the pose.

    ``L = sum_c ((x_c - target_c) scale_c)^2`` over the target joints' feature columns ``c``: squared
    distances in metres, since a z-scored unit of column ``c`` is ``scale_c`` metres. The gradient is
    ``dL/dx_c = 2 (x_c - target_c) scale_c^2`` on those columns and 0 elsewhere; the generator's backward pass
    turns it into ``dL/dz``.

    Parameters
    ----------
    x : ndarray, shape (F,)
        The decoded pose ``G(z)``, z-scored.
    target : ndarray, shape (3 K,)
        The K targets' z-scored features.
    columns : ndarray of int, shape (3 K,)
        Their feature columns in ``x``.
    scale : ndarray, shape (3 K,)
        Metres per z-scored unit of those columns (their standard deviations).

    Returns
    -------
    loss : float, square metres
    grad : ndarray, shape (F,)
    """
    import numpy as np

    diff = (x[columns] - target) * scale  # target distances, metres
    loss = float(np.sum(diff**2))
    grad = np.zeros(len(x))
    grad[columns] = 2.0 * diff * scale    # chain rule: d(diff)/dx = scale
    return loss, grad


def exercise_adversarial(real_logits, fake_logits, smooth):
    """A discriminator's loss and the non-saturating generator loss of section 2, with their gradients with respect to
    the logits, finite for logits of any size.

    ``BCE(l, y) = -[y log sigmoid(l) + (1 - y) log(1 - sigmoid(l))] = y softplus(-l) + (1 - y) softplus(l)`` with
    ``softplus(x) = log(1 + exp(x))`` written ``np.logaddexp(0, x)``, which never overflows. The discriminator's loss
    is ``mean BCE(real, smooth) + mean BCE(fake, 0)``, the generator's ``mean BCE(fake, 1) = mean -log D(fake)``;
    ``d BCE(l, y) / dl = sigmoid(l) - y``, divided by the number of logits of the mean it is in. The sigmoid is
    computed from ``exp(-|l|)``, which never overflows either.

    Parameters
    ----------
    real_logits : ndarray, shape (Nr,)
        The discriminator's logits of real samples.
    fake_logits : ndarray, shape (Nf,)
        Its logits of generated samples.
    smooth : float
        The label of real samples (one-sided label smoothing; 1 for none).

    Returns
    -------
    loss_d : float
    grad_real : ndarray, shape (Nr,)
        ``d loss_d / d real_logits``.
    grad_fake : ndarray, shape (Nf,)
        ``d loss_d / d fake_logits``.
    loss_g : float
    grad_g : ndarray, shape (Nf,)
        ``d loss_g / d fake_logits``.
    """
    import numpy as np

    real = np.asarray(real_logits, dtype=float)
    fake = np.asarray(fake_logits, dtype=float)

    def softplus(x):
        return np.logaddexp(0.0, x)

    def sigmoid(x):
        e = np.exp(-np.abs(x))
        return np.where(x >= 0, 1.0 / (1.0 + e), e / (1.0 + e))

    loss_d = float(np.mean(smooth * softplus(-real) + (1.0 - smooth) * softplus(real)) + np.mean(softplus(fake)))
    grad_real = (sigmoid(real) - smooth) / len(real)
    grad_fake = sigmoid(fake) / len(fake)
    loss_g = float(np.mean(softplus(-fake)))
    grad_g = (sigmoid(fake) - 1.0) / len(fake)
    return loss_d, grad_real, grad_fake, loss_g, grad_g
