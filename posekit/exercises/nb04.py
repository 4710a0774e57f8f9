"""Checkers for ``notebooks/04_aegan_latent_space.ipynb``."""

from __future__ import annotations

import numpy as np

from ._check import report
from ._judge import judged


@judged
def check_tree_depths(my_depths) -> bool:
    """Check ``my_depths(parents) -> (J,) int``: each joint's depth in the tree (0 at a root, parent -1),
    the order in which an SPL can predict the joints (:func:`posekit.models.aegan.spl.tree_levels`)."""
    from ..data.bandai_mini import load_bandai_mini
    from ..models.aegan.networks import body_parents
    from ..models.aegan.spl import tree_levels

    def expected(parents):
        d = np.zeros(len(parents), dtype=float)
        for depth, (js, _) in enumerate(tree_levels(parents)):
            d[js] = depth
        return d

    def describe(got, exp):
        bad = int(np.nonzero(got != exp)[0][0])
        return f"joint {bad}: got depth {got[bad]:.0f}, expected {exp[bad]:.0f} (count the steps up to a root)"
    trees = ([-1, 0, 1, 0, 3], [2, -1, 1, 2], list(body_parents(load_bandai_mini().skeleton)), [-1, -1, 0, 1])
    return report("check_tree_depths", my_depths, [((list(p),), expected(p), describe) for p in trees], atol=0)


@judged
def check_latent_loss(my_loss) -> bool:
    """Check ``my_loss(x (F,), target (3K,), columns (3K,), scale (3K,)) -> (loss, grad_x (F,))``: Eq. (6)'s
    sum of squared target distances in metres (``(x[columns] - target) * scale``) and its gradient with
    respect to the z-scored pose ``x`` (zero outside ``columns``)."""
    rng = np.random.default_rng(4)
    cases = []

    def describe(got, exp):
        return f"got {got.ravel()[:3]}, expected {exp.ravel()[:3]}; metres = z-scored x scale, squared, summed?"
    for F, cols in ((9, [3, 4, 5]), (63, list(range(27, 33))), (12, [0, 1, 2, 9, 10, 11])):
        x = rng.normal(size=F)
        t = rng.normal(size=len(cols))
        sc = rng.uniform(0.05, 0.3, len(cols))
        diff = (x[cols] - t) * sc
        g = np.zeros(F)
        g[cols] = 2 * diff * sc
        cases.append(((x, t, np.array(cols), sc), np.concatenate([[np.sum(diff ** 2)], g]), describe))

    def both(*a):
        loss, grad = my_loss(*a)
        return np.concatenate([[float(loss)], np.asarray(grad, dtype=float).ravel()])
    return report("check_latent_loss", both, cases, atol=1e-9)


@judged
def check_generator_loss(my_loss) -> bool:
    """Check ``my_loss(fake_logits (N,)) -> float``: the non-saturating generator loss, the mean of
    ``-log sigmoid(logit)`` (``BCE(D(G(z)), 1)``; :mod:`posekit.models.aegan.train`)."""
    rng = np.random.default_rng(5)
    cases = []

    def describe(got, exp):
        return (f"got {float(np.ravel(got)[0]):.6g}, expected {float(exp):.6g}; -log D(fake), not log(1 - D(fake)) "
                "(that is the saturating form)?")
    for n, loc in ((8, 0.0), (20, -4.0), (5, 3.0)):
        lg = rng.normal(loc, 1.0, n)
        cases.append(((lg,), np.float64(np.mean(np.logaddexp(0.0, -lg))), describe))
    return report("check_generator_loss", lambda *a: np.float64(my_loss(*a)), cases, atol=1e-9)
