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
    # a list and an array of the same tree: the caller's list must come back as it went in (not sorted, not emptied)
    inputs = [list(p) for p in trees] + [np.array(trees[1])]
    return report("check_tree_depths", my_depths, [((p,), expected(list(p)), describe) for p in inputs], atol=0,
                  forbid=(tree_levels,), arg_names=("parents",))


@judged
def check_latent_loss(my_loss) -> bool:
    """Check ``my_loss(x (F,), target (3K,), columns (3K,), scale (3K,)) -> (loss, grad_x (F,))``: Eq. (6)'s
    sum of squared target distances in metres (``(x[columns] - target) * scale``) and its gradient with
    respect to the z-scored pose ``x`` (zero outside ``columns``)."""
    from ..models.aegan.latent_opt import Problem

    rng = np.random.default_rng(4)
    cases = []

    def describe(got, exp):
        if not np.isclose(got[0], exp[0], atol=1e-9):
            return (f"the loss is {got[0]:.6g}, expected {exp[0]:.6g}: metres = (z-scored x - target) x scale, "
                    "squared, summed?")
        k = int(np.argmax(np.abs(got[1:] - exp[1:])))
        return (f"the loss is right; the gradient differs at x[{k}]: got {got[1 + k]:.6g}, expected {exp[1 + k]:.6g} "
                "(2 x difference x scale on the target columns, 0 elsewhere?)")
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
    return report("check_latent_loss", both, cases, atol=1e-9, forbid=(Problem.loss,),
                  arg_names=("x", "target", "columns", "scale"))


@judged
def check_generator_loss(my_loss) -> bool:
    """Check ``my_loss(fake_logits (N,)) -> float``: the non-saturating generator loss, the mean of
    ``-log sigmoid(logit)`` (``BCE(D(G(z)), 1)``; :mod:`posekit.models.aegan.train`)."""
    from ..models.aegan.train import _bce

    rng = np.random.default_rng(5)
    cases = []

    def describe(got, exp):
        value = float(np.ravel(got)[0])
        if not np.isfinite(value):
            return (f"got {value}, expected {float(exp):.6g}: a logit far from 0 overflows -log(sigmoid(l)); write "
                    "it as log(1 + exp(-l)) computed stably (np.logaddexp(0, -l))")
        return (f"got {value:.6g}, expected {float(exp):.6g}; -log D(fake), not log(1 - D(fake)) "
                "(that is the saturating form)?")
    for n, loc in ((8, 0.0), (20, -4.0), (5, 3.0)):
        lg = rng.normal(loc, 1.0, n)
        cases.append(((lg,), np.float64(np.mean(np.logaddexp(0.0, -lg))), describe))
    for lg in (np.array([-1000.0, 0.0, 1000.0]), np.array([-800.0, -750.0]), np.array([40.0, 745.0])):
        cases.append(((lg,), np.float64(np.mean(np.logaddexp(0.0, -lg))), describe))  # far from 0: no inf, no nan
    return report("check_generator_loss", lambda *a: np.float64(my_loss(*a)), cases, atol=1e-9, forbid=(_bce,),
                  arg_names=("fake_logits",))
