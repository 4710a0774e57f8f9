"""Lesson 03's measured choices: the autoencoder's size and decoder, the solver loss's ``k``, chaining.

Introduced in ``notebooks/03_autoencoder_solvers.ipynb``; ``posekit train ae-studies`` runs
:func:`run_studies` and writes ``data_samples/weights/ae_solvers_studies.json``, which the lesson shows
(its live demo runs a small piece of each study with the same code). Every study is seeded and uses
the Bandai mini set's own split: trained on ``train``, chosen on ``val``, reported on ``test`` (held-out
dataset-1 takes).

* :func:`autoencoder_study` — held-out reconstruction error for d in (16, 32, 64), tied and untied
  decoders (Sec. 3.3.1; the authors' code ties the weights);
* :func:`k_study` — the hands solver trained with several ``k`` of Eq. (1): effector error against
  full-pose error and naturalness, from a same-clip and another clip's start;
* :func:`chain_study` — naive chaining of independent solvers against the chaining-aware copies
  (Sec. 3.5) on the five effectors.
"""

from __future__ import annotations

import copy
import json
import time
from pathlib import Path

import numpy as np
import torch

from ...data.cases import build_cases, case_split
from ...data.metrics import NaturalnessIndex
from ...evaluation.pose_scores import score_poses
from ...ik.api import EFFECTOR_SETS, effector_set
from ...learn.trainers import register_trainer
from ...plugins import arg
from ...data.pose_vectors import pose_data
from .data import training_pairs
from .networks import GROUPS, AEConfig, AESolvers
from .train import DEFAULTS, train_autoencoder, train_solver

__all__ = ["autoencoder_study", "k_study", "chain_study", "run_studies", "studies_path", "reconstruction_mm"]


def studies_path(folder=None) -> Path:
    from ...paths import samples_dir

    return Path(folder or samples_dir() / "weights") / "ae_solvers_studies.json"


def reconstruction_mm(model: AESolvers, x) -> float:
    """Mean per-joint distance (mm) between poses ``x`` (N, F, metres) and their reconstruction D(E(x))."""
    z = torch.as_tensor(model.norm.normalize(x), dtype=torch.float32)
    with torch.no_grad():
        r = model.norm.denormalize(model.ae(z).numpy())
    return float(np.linalg.norm((r - x).reshape(len(x), -1, 3), axis=-1).mean() * 1e3)


def autoencoder_study(motions, latents=(16, 32, 64), tied=(True, False), epochs: int = 40, lr: float = 1e-3,
                      seed: int = 0, progress: bool = True) -> list[dict]:
    """Held-out reconstruction of autoencoders of each size and decoder; one row per configuration."""
    train, val, test, _ = case_split(motions, seed)
    td = pose_data(motions, train)
    vd, ted = (pose_data(motions, f, mirror=False, norm=td.norm) for f in (val, test))
    x, xv = torch.as_tensor(td.normalized()), torch.as_tensor(vd.normalized())
    rows = []
    for t in tied:
        for d in latents:
            m = AESolvers.new(motions.skeleton, td.norm, AEConfig(x.shape[1], latent=d, tied=t), seed)
            c = train_autoencoder(m, x, xv, epochs=epochs, lr=lr, seed=seed, progress=progress)
            rows.append({"latent": d, "decoder": "tied" if t else "untied",
                         "parameters": sum(p.numel() for p in m.ae.parameters()), "val_mse": c.val[-1],
                         "val_mm": reconstruction_mm(m, vd.x), "test_mm": reconstruction_mm(m, ted.x),
                         "seconds": c.seconds, "val_curve": c.val})
    return rows


def _score(solver, cases, e: str, natural) -> dict:
    s = cases.skeleton
    effs = [effector_set(s, e, cases.target_pos[i]) for i in range(len(cases))]
    res = solver.solve_batch([cases.pose(i) for i in range(len(cases))], effs)
    return score_poses(cases, np.stack([r.pose.global_pos for r in res]), effs, None, natural).summary()


def k_study(model: AESolvers, motions, ks=(0.0, 0.01, 0.1, 1.0), group: str = "hands", epochs: int | None = None,
            pairs: int | None = None, n_cases: int = 300, seed: int = 0, progress: bool = True) -> list[dict]:
    """The ``group`` solver retrained with each ``k`` on ``model``'s autoencoder, scored before
    post-processing on held-out cases from a same-clip and another clip's start."""
    from .solver import NeuralIKSolver

    epochs = DEFAULTS["solver_epochs"] if epochs is None else epochs
    pairs = DEFAULTS["pairs"] if pairs is None else pairs
    train, val, _, _ = case_split(motions, seed)
    td = pose_data(motions, train, norm=model.norm)
    vd = pose_data(motions, val, mirror=False, norm=model.norm)
    x = torch.as_tensor(np.concatenate([td.normalized(), vd.normalized()]))
    tr = tuple(torch.as_tensor(a) for a in training_pairs(motions, td, pairs, seed=seed))
    va, vb = training_pairs(motions, vd, max(1000, pairs // 50), seed=seed + 1)
    vp = (torch.as_tensor(va + len(td.x)), torch.as_tensor(vb + len(td.x)))
    starts = {st: build_cases(motions, n_cases, seed, st) for st in ("same-clip", "other-clip")}
    natural = NaturalnessIndex(motions.skeleton, motions.global_pos[train], seed=seed)
    e = next(name for name, v in EFFECTOR_SETS.items() if tuple(v) == GROUPS[group])
    rows = []
    for k in ks:
        m = copy.copy(model)
        m.solvers = dict(model.solvers)
        train_solver(m, group, x, tr, vp, epochs=epochs, k=k, seed=seed, progress=progress)
        solver = NeuralIKSolver(motions.skeleton, model=m, post="none")
        for st, cases in starts.items():
            sc = _score(solver, cases, e, natural)
            rows.append({"k": k, "start": st, "effector_mm": sc["effector_error_mm_median"],
                         "mpjpe_mm": sc["mpjpe_mm_median"], "natural_mm": sc["natural_mm_median"]})
    return rows


def chain_study(model: AESolvers, motions, n_cases: int = 300, seed: int = 0) -> list[dict]:
    """Five effectors by the all-five solver, by naive chaining (in the latent space as Sec. 3.5 writes it, and
    decoded and encoded again between the stages as the authors' code does) and by chaining-aware chaining, with
    the start poses themselves (no solve) as the floor of what a solver should improve on."""
    from .solver import NeuralIKSolver

    train, _, _, _ = case_split(motions, seed)
    natural = NaturalnessIndex(motions.skeleton, motions.global_pos[train], seed=seed)
    rows = []
    for st in ("same-clip", "other-clip", "rest"):
        cases = build_cases(motions, n_cases, seed, st)
        effs = [effector_set(motions.skeleton, "5", cases.target_pos[i]) for i in range(len(cases))]
        sc = score_poses(cases, cases.start_pos, effs, None, natural).summary()     # what no solve does
        rows.append({"method": "start pose, unsolved", "start": st, "effector_mm": sc["effector_error_mm_median"],
                     "mpjpe_mm": sc["mpjpe_mm_median"], "natural_mm": sc["natural_mm_median"]})
        for label, kw in (("all-five solver", {}), ("naive chain", {"chain": True, "chain_aware": False}),
                          ("naive chain, re-encoded", {"chain": True, "chain_aware": False, "reencode": True}),
                          ("chaining-aware chain", {"chain": True})):
            sc = _score(NeuralIKSolver(motions.skeleton, model=model, post="none", **kw), cases, "5", natural)
            rows.append({"method": label, "start": st, "effector_mm": sc["effector_error_mm_median"],
                         "mpjpe_mm": sc["mpjpe_mm_median"], "natural_mm": sc["natural_mm_median"]})
    return rows


def run_studies(motions=None, model: AESolvers | None = None, out=None, seed: int = 0, progress: bool = True,
                ae_epochs: int = 40) -> dict:
    """All three studies; written as JSON to ``out`` (default :func:`studies_path`) unless ``out=False``."""
    from ...data.bandai_mini import load_bandai_mini
    from ...learn.distributed import current
    from .solver import load_model

    run = current()
    if run.device.type != "cpu":
        raise ValueError(f"posekit train ae-studies trains on the CPU only (its studies read the shipped model and "
                         f"data on the CPU), not {run.device}: run it with --device cpu (about 9 minutes)")
    motions = load_bandai_mini() if motions is None else motions
    model = load_model(skeleton=motions.skeleton) if model is None else model
    t0 = time.perf_counter()
    result = {"data": motions.source.split(" (")[0], "seed": seed,
              "command": f"posekit train ae-studies --seed {seed}"
                         + (f" --ae-epochs {ae_epochs}" if ae_epochs != 40 else ""),
              "autoencoder": autoencoder_study(motions, epochs=ae_epochs, seed=seed, progress=progress),
              "k": k_study(model, motions, seed=seed, progress=progress),
              "chain": chain_study(model, motions, seed=seed)}
    result["seconds"] = time.perf_counter() - t0
    if out is not False and run.main:
        path = studies_path() if out is None else Path(out)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(result, indent=1) + "\n")
    return result


def _cli(args) -> int:
    """``posekit train ae-studies``."""

    from ...learn.threads import single_thread

    out = Path(args.out) if args.out else studies_path()
    with single_thread():
        res = run_studies(seed=args.seed, out=out, progress=True, ae_epochs=args.ae_epochs)
    for r in res["autoencoder"]:
        print(f"autoencoder d={r['latent']:<3} {r['decoder']:<7} held-out reconstruction {r['test_mm']:.1f} mm")
    print(f"wrote {out} in {res['seconds']:.0f} s")
    return 0


register_trainer(
    "ae-studies", _cli, help="lesson 03's studies on the shipped autoencoder (d, tied/untied, k, chaining)",
    makes="data_samples/weights/ae_solvers_studies.json",
    what="lesson 03's measured choices: autoencoder size and decoder, the loss weight k, chaining",
    used_by="lesson 03 (03_autoencoder_solvers.ipynb)", takes="about 9 minutes on one core (9 min 22 s measured)",
    out=".json",
    args=[arg("--ae-epochs", type=int, default=40, help="epochs of each autoencoder of the size study (default: 40)"),
          arg("--seed", type=int, default=0, help="(default: 0)"),
          arg("--out", default=None, help="JSON file (default data_samples/weights/ae_solvers_studies.json)")])
