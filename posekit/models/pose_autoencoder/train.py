"""Training lesson 03's networks (Victor et al. 2021) and the command that makes the shipped weights.

Introduced in ``notebooks/03_autoencoder_solvers.ipynb``; ``posekit train ae-solvers`` runs
:func:`train_ae_solvers`. Every loop is :func:`posekit.learn.fit` (seeded mini-batches, tqdm). In order:

1. the autoencoder on the training poses (mirrored), ``MSE(D(E(x)), x)`` on z-scored vectors, Adam;
   then its weights are rounded to float16, as the checkpoint stores them, so that the solvers are
   trained against the decoder exactly as shipped (the solvers' own float16 rounding is harmless);
2. one solver per joint set of :data:`~posekit.models.pose_autoencoder.networks.GROUPS`, autoencoder frozen, on
   (start, target) pairs of one clip at most 1 s apart (:func:`~posekit.models.pose_autoencoder.data.training_pairs`),
   loss Eq. (1) with ``k`` (:func:`solver_loss`);
3. chaining-aware copies (Sec. 3.5): each solver after the first of :data:`~posekit.models.pose_autoencoder.networks.CHAIN`
   fine-tuned on the codes the earlier solvers produce, its target joints being every joint the chain
   has been asked for so far (so a later stage learns not to undo an earlier one).

Validation losses use the split's ``val`` clips (held-out dataset-1 takes for the Bandai mini set).
"""

from __future__ import annotations

import copy
import time

import numpy as np
import torch

from ...data.bandai_mini import weights_licence
from ...learn import fit, merge_settings
from ...learn.trainers import cli_data, cli_settings, print_written, register_trainer
from ...plugins import arg
from ...data.pose_vectors import split_pose_data
from .data import training_pairs
from .networks import CHAIN, GROUPS, AEConfig, AESolvers, weights_path

__all__ = ["DEFAULTS", "solver_loss", "train_autoencoder", "train_solver", "train_chained",
           "train_ae_solvers", "command"]

DEFAULTS = dict(ae_epochs=80, ae_lr=1e-3, solver_epochs=12, solver_lr=1e-3, chain_epochs=6, pairs=300_000,
                batch=256, k=0.01)
"""Training settings of the shipped weights (``posekit train ae-solvers``)."""


def command(seed: int = 0, latent: int = 64, tied: bool = False, data: str = "bandai-mini", **settings) -> str:
    """The command line that makes weights with these settings."""
    parts = [f"--seed {seed}"] + [f"--{k.replace('_', '-')} {v}" for k, v in settings.items()
                                  if k in DEFAULTS and v != DEFAULTS[k]]
    parts += [f"--latent {latent}"] * (latent != 64) + ["--tied"] * tied + [f"--data {data}"] * (data != "bandai-mini")
    return "posekit train ae-solvers " + " ".join(parts)


def solver_loss(n_features: int, columns, k: float):
    """Eq. (1) as a function ``loss(decoded (N, F), x_target (N, F)) -> scalar``: the mean squared error
    on the feature ``columns`` of the target joints + ``k`` x the mean squared error on the other
    features (z-scored units)."""
    on = torch.zeros(n_features, dtype=torch.bool)
    on[torch.as_tensor(columns)] = True

    def loss(decoded, x_target):
        se = (decoded - x_target) ** 2
        other = se[:, ~on].mean() if (~on).any() else se.new_zeros(())
        return se[:, on].mean() + k * other

    return loss


def train_autoencoder(model: AESolvers, x, x_val, *, epochs: int, lr: float = 1e-4, batch: int = 256, seed: int = 0,
                      progress: bool = True):
    """Fit ``model.ae`` on z-scored poses ``x`` (N, F), validation ``x_val``; returns
    :class:`~posekit.learn.Curves`."""
    return fit(model.ae, lambda ae, xb: torch.mean((ae(xb) - xb) ** 2), (x,), (x_val,), epochs=epochs, batch=batch,
               lr=lr, seed=seed, progress=progress, desc="autoencoder")


def _frozen(model: AESolvers):
    model.ae.eval()
    model.ae.requires_grad_(False)


def train_solver(model: AESolvers, group: str, x, pairs, val_pairs, *, epochs: int, k: float = 0.01, lr: float = 1e-3,
                 batch: int = 256, seed: int = 0, progress: bool = True):
    """Train ``model.solvers[group]`` (a new one) with the autoencoder frozen.

    Parameters
    ----------
    x : Tensor, shape (M, F)
        z-scored training poses (rows the pairs index; validation rows appended after them is fine).
    pairs, val_pairs : (start rows, target rows), each int (P,)
    """
    _frozen(model)
    net = model.solvers[group] = model.new_solver(group, seed)
    cols = torch.as_tensor(model.columns(group))
    loss = solver_loss(model.config.n_features, cols, k)

    def step(net, a, b):
        with torch.no_grad():
            z = model.ae.encode(x[a])
        xt = x[b]
        return loss(model.ae.decode(net(z, xt[:, cols])), xt)

    return fit(net, step, pairs, val_pairs, epochs=epochs, batch=batch, lr=lr, seed=seed, progress=progress,
               desc=f"solver {group}")


def train_chained(model: AESolvers, x, pairs, val_pairs, *, epochs: int, k: float = 0.01, lr: float = 1e-3,
                  batch: int = 256, seed: int = 0, progress: bool = True, chain=CHAIN) -> dict:
    """Chaining-aware copies of the solvers after the first of ``chain``, each fine-tuned on the codes
    the stages before it produce (those stages already chaining-aware); returns {group: Curves}."""
    _frozen(model)
    curves = {}
    for i, g in enumerate(chain[1:], start=1):
        for net in (*model.solvers.values(), *model.chained.values()):
            net.requires_grad_(False)
        net = copy.deepcopy(model.solvers[g]).requires_grad_(True)
        asked = [c for h in chain[: i + 1] for c in model.columns(h)]
        loss_fn = solver_loss(model.config.n_features, asked, k)
        before = chain[:i]

        def step(net, a, b, before=before, g=g, loss_fn=loss_fn):
            xt = x[b]
            with torch.no_grad():
                z = model.ae.encode(x[a])
                z = model.latent(z, {h: xt[:, model.columns(h)] for h in before}, chain=before)
            return loss_fn(model.ae.decode(net(z, xt[:, model.columns(g)])), xt)

        curves[g] = fit(net, step, pairs, val_pairs, epochs=epochs, batch=batch, lr=lr, seed=seed + i,
                        progress=progress, desc=f"chained {g}")
        model.chained[g] = net.eval()
    for net in (*model.solvers.values(), *model.chained.values()):
        net.requires_grad_(True)
    return curves


def train_ae_solvers(motions=None, *, seed: int = 0, out=None, groups=tuple(GROUPS), tied: bool = False,
                     latent: int = 64, progress: bool = True, data_label: str | None = None, **settings):
    """Train the autoencoder, the solvers of ``groups`` and the chaining-aware copies; save them.

    Parameters
    ----------
    motions : MotionSet, optional
        With its own ``split`` (train/val/test) or split by clip; default the Bandai mini set.
    seed : int
    out : str or Path, optional
        The checkpoint file to write (default ``data_samples/weights/ae_solvers.pt``); ``False``: none.
    groups : sequence of str
    tied, latent : the autoencoder's decoder and code size (:class:`~posekit.models.pose_autoencoder.networks.AEConfig`).
        Default untied: on the mini set an untied decoder reconstructs held-out poses better than the
        authors' tied one (the lesson measures both, ``posekit train ae-studies``).
    **settings
        Any of :data:`DEFAULTS` (epochs, learning rates, number of pairs, batch, ``k``).

    Returns
    -------
    model : AESolvers
    report : dict
        Curves (train/val per epoch), seconds per stage and in all.
    """
    from ...learn.distributed import current

    st = merge_settings("train_ae_solvers", settings, DEFAULTS)
    run = current()  # --device, torchrun: fit trains each network there, data-parallel
    run.share(int(st["batch"]))
    t0 = time.perf_counter()
    motions, td, vd, how = split_pose_data(motions, seed)
    x = torch.as_tensor(np.concatenate([td.normalized(), vd.normalized()])).to(run.device)
    xv = x[len(td.x):]
    cfg = AEConfig(x.shape[1], latent=latent, tied=tied)
    model = AESolvers.new(motions.skeleton, td.norm, cfg, seed)
    model.ae.to(run.device)  # the solvers' losses read it on the device they train on
    z = td.normalized()
    model.x_range = np.stack([z.min(0), z.max(0)])
    report = {"split": how, "train_poses": int(td.n), "val_poses": int(vd.n), "settings": st, "seconds": {}}
    ae_c = train_autoencoder(model, x[: len(td.x)], xv, epochs=st["ae_epochs"], lr=st["ae_lr"], batch=st["batch"],
                             seed=seed, progress=progress)
    with torch.no_grad():  # the solvers learn the decoder as it is shipped: float16 weights (measured: solvers
        for p in model.ae.parameters():  # trained on the float32 decoder missed the hands by 18 mm, not 12 mm,
            p.copy_(p.half().float())     # once it was rounded)
    report["autoencoder"] = {"train": ae_c.train, "val": ae_c.val}
    report["seconds"]["autoencoder"] = ae_c.seconds
    pairs = tuple(torch.as_tensor(a) for a in training_pairs(motions, td, st["pairs"], seed=seed))
    va, vb = training_pairs(motions, vd, max(1000, st["pairs"] // 50), seed=seed + 1)
    val_pairs = (torch.as_tensor(va + len(td.x)), torch.as_tensor(vb + len(td.x)))
    report["solvers"] = {}
    for g in groups:
        c = train_solver(model, g, x, pairs, val_pairs, epochs=st["solver_epochs"], k=st["k"], lr=st["solver_lr"],
                         batch=st["batch"], seed=seed, progress=progress)
        report["solvers"][g] = {"train": c.train, "val": c.val}
        report["seconds"][f"solver {g}"] = c.seconds
    if all(g in model.solvers for g in CHAIN) and st["chain_epochs"] > 0:
        for g, c in train_chained(model, x, pairs, val_pairs, epochs=st["chain_epochs"], k=st["k"], lr=st["solver_lr"],
                                  batch=st["batch"], seed=seed, progress=progress).items():
            report["solvers"][f"chained {g}"] = {"train": c.train, "val": c.val}
            report["seconds"][f"chained {g}"] = c.seconds
    report["seconds"]["total"] = time.perf_counter() - t0
    report["processes"], report["device"] = run.world, str(run.device)
    for net in (model.ae, *model.solvers.values(), *model.chained.values()):
        net.cpu()  # what the lessons load
    if out is not False:
        label = data_label or motions.source.split(" (")[0]
        data = (f"{label}: training split ({how}), {td.n} poses + mirrored copies; val {vd.n} poses; "
                f"{st['pairs']} training pairs at most 1 s apart (seed {seed})")
        model.save(weights_path() if out is None else out,
                   command=command(seed=seed, latent=latent, tied=tied, data=label, **settings), seed=seed,
                   data=data, licence=weights_licence(label),
                   extra={"report": report})
    return model, report


def _cli(args) -> int:
    """``posekit train ae-solvers``."""

    from ...learn.threads import single_thread

    settings = cli_settings(args, DEFAULTS)
    motions, out = cli_data(args)
    with single_thread():  # these small layers gain little from a second thread, and one thread repeats exactly
        model, report = train_ae_solvers(motions, seed=args.seed, out=out, tied=args.tied, latent=args.latent,
                                         progress=True, **settings)
    path = out or weights_path()
    sec = report["seconds"]
    print(f"trained in {sec['total']:.0f} s (" + ", ".join(f"{k} {v:.0f} s" for k, v in sec.items() if k != "total")
          + ")")
    print(f"autoencoder validation MSE {report['autoencoder']['val'][-1]:.5f} (z-scored units); solvers: "
          + ", ".join(f"{g} {c['val'][-1]:.5f}" for g, c in report["solvers"].items()))
    print_written(path)
    return 0


_WHAT = (("ae_epochs", "autoencoder epochs"), ("ae_lr", "autoencoder learning rate (Adam)"),
         ("solver_epochs", "epochs per solver"), ("solver_lr", "solver learning rate (Adam)"),
         ("chain_epochs", "epochs of each chaining-aware fine-tuning"),
         ("pairs", "training (start, target) pairs, at most 1 s apart"), ("batch", "mini-batch size"),
         ("k", "weight of the non-target joints in the solver loss, Eq. (1)"))

register_trainer(
    "ae-solvers", _cli, help="pose autoencoder + latent-space solvers (lesson 03, Victor et al. 2021)",
    makes="data_samples/weights/ae_solvers.pt (CC BY-NC 4.0, like the Bandai mini set it is trained on)",
    what="pose autoencoder + latent-space solvers hands, feet, head, all five, chaining-aware copies "
         "(Victor et al. 2021)",
    used_by="lesson 03 (03_autoencoder_solvers.ipynb), the neural solvers, posekit bench ik",
    takes="about 7 minutes on one core (it trains on one thread: 7 min 13 s measured)",
    shipped=lambda args: "data_samples/weights/ae_solvers.pt",
    args=[arg("--data", default="bandai-mini", help="training data: bandai-mini (default, its own split), "
              "or any posekit data set name / path (split by clip)")]
         + [arg("--" + key.replace("_", "-"), dest=key, type=type(DEFAULTS[key]), default=DEFAULTS[key],
                help=f"{what} (default: {DEFAULTS[key]})") for key, what in _WHAT]
         + [arg("--latent", type=int, default=64, help="size d of the latent code (default: 64)"),
            arg("--tied", action="store_true", help="the decoder reuses the transposed encoder weights, no biases, "
                "as in the authors' code (default: untied, its own weights and biases: measured better in "
                "lesson 03)"),
            arg("--seed", type=int, default=0, help="(default: 0)"),
            arg("--out", default=None, help="checkpoint file (default data_samples/weights/ae_solvers.pt; required "
                                          "with another --data: a .pt file, checked before training)")])
