"""Checkers for ``notebooks/05_protores.ipynb``."""

from __future__ import annotations

import numpy as np

from ._check import flat, report
from ._judge import judged


@judged
def check_prototype_step(my_step) -> bool:
    """Check ``my_step(b (N, d), f (N, d), e_prev (N, d), r) -> (e (N, d), p (d,), x_next (N, d))``: one block of
    Eq. 2 after its layers — ``e = e_prev + f``, the prototype ``p = mean_i e_i``, ``x_next = relu(b - p / r)``
    (:class:`posekit.models.protores.networks.ProtoResEncoder`)."""
    rng = np.random.default_rng(6)
    cases = []

    def describe(got, exp):
        i = int(np.argmax(np.abs(got - exp)))
        return f"entry {i}: got {got.ravel()[i]:.4g}, expected {exp.ravel()[i]:.4g}; p / r, mean over effectors?"
    for N, d, r, dtype in ((3, 4, 1, float), (7, 5, 2, float), (1, 6, 3, float), (4, 3, 5, np.float32)):
        b, f, e0 = (rng.normal(size=(N, d)).astype(dtype) for _ in range(3))
        e = e0.astype(float) + f
        p = e.mean(0)
        cases.append(((b, f, e0, r), np.concatenate([e.ravel(), p, np.maximum(b - p / r, 0).ravel()]), describe))

    def both(*a):
        e, p, x = my_step(*a)
        return flat(e, p, x)
    from ..models.protores.networks import ProtoResEncoder

    return report("check_prototype_step", both, cases, atol=1e-9, forbid=(ProtoResEncoder.forward,),
                  arg_names=("b", "f", "e_prev", "r"))


@judged
def check_tolerance_weight(my_weight) -> bool:
    """Check ``my_weight(lam (K,)) -> (sigma (K,), weight (K,))``: the noise scale ``sigma = sigma_M Lambda^eta``
    (sigma_M = 0.1, eta = 13) and the loss weight ``min(W_M, 1 / sigma)`` (W_M = 1000; an exact effector,
    sigma = 0, gets W_M)."""
    from ..models.protores.networks import ETA, SIGMA_M, tolerance_to_sigma

    def describe(got, exp):
        i = int(np.argmax(np.abs(got - exp) / (np.abs(exp) + 1e-12)))
        return f"entry {i}: got {got[i]:.6g}, expected {exp[i]:.6g}; sigma_M * lam**eta, and min(W_M, 1/sigma)?"
    cases = []
    for lam in (np.array([0.0, 0.5, 1.0]), np.linspace(0, 1, 11), np.array([0.7, 0.75, 0.9]),
                np.array([0.0, 0.0]), np.array([0.6, 0.95], np.float32)):  # exact effectors only; float32
        s = SIGMA_M * lam.astype(float) ** ETA
        with np.errstate(divide="ignore"):
            w = np.minimum(1000.0, 1.0 / s)
        cases.append(((lam,), np.concatenate([s, w]), describe))

    def both(lam):
        s, w = my_weight(lam)
        return flat(s, w)
    return report("check_tolerance_weight", both, cases, atol=1e-9, forbid=(tolerance_to_sigma,), arg_names=("lam",))


@judged
def check_centroid(my_centroid) -> bool:
    """Check ``my_centroid(kind (N,), value (N, 6), lam (N,)) -> (3,)``: the mean of the *position* effectors'
    positions weighted by ``1 - Lambda + 1e-3`` (the origin when there is none;
    :func:`posekit.models.protores.networks.centroid`)."""
    import torch

    from ..models.protores.networks import centroid

    rng = np.random.default_rng(7)

    def describe(got, exp):
        return f"got {np.round(got, 4)}, expected {np.round(exp, 4)}; only kind 0, weights 1 - lam + 1e-3?"
    cases = []
    for kind in (np.array([0, 0, 0]), np.array([0, 1, 2, 0, 1]), np.array([1, 2]), np.array([2, 0, 0, 1, 0, 0]),
                 np.array([1, 0, 2]), np.array([0, 0])):
        value = rng.normal(size=(len(kind), 6))
        lam = rng.uniform(0, 1, len(kind))
        if len(kind) == 2:  # both loose at the limit: weights 1e-3 each, still a mean
            lam = np.ones(2)
        exp = centroid(torch.as_tensor(kind)[None], torch.as_tensor(value)[None], torch.as_tensor(lam)[None])[0].numpy()
        cases.append(((kind, value, lam), exp, describe))
    return report("check_centroid", lambda *a: flat(my_centroid(*a)), cases, atol=1e-9,
                  forbid=(centroid,), arg_names=("kind", "value", "lam"))
