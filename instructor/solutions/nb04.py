"""Reference solutions of lesson 04's exercises (instructor version; ``posekit exercises solutions 04`` pastes
them into the lesson)."""

from __future__ import annotations

__all__ = ["exercise_depths", "exercise_latent_loss", "exercise_generator_loss"]


def exercise_depths(parents):
    """Depth of every joint in its tree: the order in which a structured prediction layer (Aksan et al. 2019)
    can predict the joints, parents before children.

    Parameters
    ----------
    parents : sequence of int, length J
        Parent of each joint, -1 for a root (several roots are fine); in any order.

    Returns
    -------
    ndarray of int, shape (J,)
        0 at a root, 1 for its children, and so on.
    """
    import numpy as np

    depths = np.zeros(len(parents), dtype=int)
    for j in range(len(parents)):
        k = parents[j]
        while k >= 0:  # count the steps up to a root
            depths[j] += 1
            k = parents[k]
    return depths


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


def exercise_generator_loss(fake_logits):
    """The non-saturating generator loss ``BCE(D(G(z)), 1)``: the mean of ``-log sigmoid(logit)``.

    ``-log sigmoid(l) = log(1 + exp(-l))``, written with ``np.logaddexp(0, -l)`` so that it stays finite
    for logits of any size. (The minimax form ``log(1 - D(G(z)))`` of the paper is flat where the
    discriminator wins easily; this one still has a gradient there.)

    Parameters
    ----------
    fake_logits : ndarray, shape (N,)
        The pose discriminator's logits of generated poses.

    Returns
    -------
    float
    """
    import numpy as np

    return float(np.mean(np.logaddexp(0.0, -np.asarray(fake_logits, dtype=float))))
