"""Training the AE-GAN of Victor & Meyer, JFIG 2020 (Sec. 3.2), and the command that makes the shipped weights.

Introduced in ``notebooks/04_aegan_latent_space.ipynb``; ``posekit train aegan`` runs :func:`train_aegan`.

Losses (Eq. 1-5 of the paper, after Lazarou 2020), on z-scored pose vectors ``x`` and codes ``z`` drawn
from the prior (uniform on ``[-1, 1]^d``, :func:`~posekit.models.aegan.networks.sample_prior`)::

    L_x   = MSE(G(E(x)), x)                                  (1)  pose reconstruction
    L_z   = MSE(E(G(z)), z)                                  (2)  code reconstruction
    L_Dx  = BCE(D_x(x), s) + BCE(D_x(G(z)), 0)               (3)  pose discriminator
    L_Dz  = BCE(D_z(z), s) + BCE(D_z(E(x)), 0)               (4)  latent discriminator
    L_EG  = w_x L_x + w_z L_z + BCE(D_x(G(z)), 1) + BCE(D_z(E(x)), 1)   (5)  encoder and generator

``BCE(p, t) = -t log p - (1 - t) log(1 - p)``. The paper writes the game with the minimax signs, the
encoder and generator *minimising* ``log(1 - D(fake))``; here they minimise ``-log D(fake)``
(``BCE(D(fake), 1)``), the standard *non-saturating* form: the same fixed point, but a strong gradient
while the discriminator still wins easily, when ``log(1 - D)`` is flat.

Schedule (the paper's): Adam with learning rate 1e-3 for ``D_x`` and 2e-4 for the others. Per step the
pose discriminator sees ``batch`` samples, encoder/generator ``2 batch`` and the latent discriminator
``3 batch`` (the paper's 1 : 2 : 3). Stabilisers from Lazarou's implementation: one-sided label
smoothing (``s = 0.9`` for real samples) and Adam ``beta1 = 0.5``. The reconstruction weights ``w_x``,
``w_z`` are ours (the paper gives none).

Everything runs on one thread (:func:`posekit.learn.limit_threads`): small networks, and a second busy
core slows torch's two-thread steps many times over.
"""

from __future__ import annotations

import time

import numpy as np
import torch
import torch.nn.functional as F

from ...learn import limit_threads, merge_settings
from ...learn.trainers import cli_data, cli_settings, print_written, register_trainer
from ...plugins import arg
from ...progress import finish
from ...data.pose_vectors import split_pose_data
from ...data.bandai_mini import weights_licence
from .networks import AEGAN, AEGANConfig, sample_prior, weights_path

__all__ = ["DEFAULTS", "LOSSES", "train_aegan", "command", "recon_mm"]

DEFAULTS = dict(steps=9000, batch=128, lr_dx=1e-3, lr=2e-4, w_x=50.0, w_z=10.0, smooth=0.9, beta1=0.5,
                log_every=250)
"""Training settings of the shipped weights (``posekit train aegan``)."""

LOSSES = ("rec_x", "rec_z", "d_x", "d_z", "adv_x", "adv_z", "acc_x", "acc_z")
"""What the curves record, averaged over each ``log_every`` steps: the reconstruction losses (1), (2);
the discriminators' losses (3), (4); the adversarial terms of (5); each discriminator's accuracy
(real called real and fake called fake, at 0.5)."""


def command(seed: int = 0, data: str = "bandai-mini", structured: bool = True, **settings) -> str:
    """The command line that makes weights with these settings."""
    parts = [f"--seed {seed}"] + [f"--{k.replace('_', '-')} {v}" for k, v in settings.items()
                                  if k in DEFAULTS and v != DEFAULTS[k]]
    parts += ["--dense"] * (not structured) + [f"--data {data}"] * (data != "bandai-mini")
    return "posekit train aegan " + " ".join(parts)


def recon_mm(model: AEGAN, x) -> float:
    """Mean per-joint distance of ``G(E(x))`` to z-scored poses ``x`` (N, 3 B), millimetres (on the networks'
    device)."""
    dev = next(model.encoder.parameters()).device
    with torch.no_grad():
        xr = model.generator(model.encoder(torch.as_tensor(np.asarray(x, np.float32), device=dev))).cpu().numpy()
    d = (xr - x) * model.norm.std.astype(np.float32)
    return float(np.linalg.norm(d.reshape(len(x), -1, 3), axis=-1).mean() * 1000)


def _bce(logit, target: float):
    return F.binary_cross_entropy_with_logits(logit, torch.full_like(logit, target))


def _acc(real_logit, fake_logit) -> float:
    return 0.5 * ((real_logit > 0).float().mean().item() + (fake_logit < 0).float().mean().item())


class _Logits(torch.nn.Module):
    """A discriminator's logits of real and fake samples in one call (one forward per backward: what
    ``DistributedDataParallel`` asks)."""

    def __init__(self, disc):
        super().__init__()
        self.disc = disc

    def forward(self, real, fake):
        return self.disc.logit(real), self.disc.logit(fake)


class _EncoderGeneratorLoss(torch.nn.Module):
    """The encoder/generator loss terms of Eq. (5) in one call; the discriminators are read, not trained
    here (kept out of the module's parameters)."""

    def __init__(self, encoder, generator, pose_disc, latent_disc):
        super().__init__()
        self.encoder, self.generator = encoder, generator
        self._discs = (pose_disc, latent_disc)  # a tuple: not submodules, not synchronised with this step

    def forward(self, xb, zp):
        E, G = self.encoder, self.generator
        Dx, Dz = self._discs
        ze = E(xb)
        xg = G(zp)
        rec_x = torch.mean((G(ze) - xb) ** 2)
        rec_z = torch.mean((E(xg) - zp) ** 2)
        # the gradient flows through the discriminators to E and G, not into their weights (their own steps
        # start from zero gradients anyway; under DDP a gradient here would count as a second one of theirs)
        for D in (Dx, Dz):
            D.requires_grad_(False)
        try:
            return rec_x, rec_z, _bce(Dx.logit(xg), 1.0), _bce(Dz.logit(ze), 1.0)
        finally:
            for D in (Dx, Dz):
                D.requires_grad_(True)


def _discriminator_step(opt, logits, real, fake, smooth: float):
    """One step of Eq. (3) or (4): real samples labelled ``smooth``, fake ones 0; returns (loss, accuracy)."""
    lr_, lf = logits(real, fake)
    loss = _bce(lr_, smooth) + _bce(lf, 0.0)
    opt.zero_grad()
    loss.backward()
    opt.step()
    return loss.item(), _acc(lr_, lf)


def train_aegan(motions=None, *, seed: int = 0, out=None, progress: bool = True, config: AEGANConfig | None = None,
                seconds: float | None = None, data_label: str | None = None, **settings):
    """Train the AE-GAN on the training poses (mirrored) of ``motions``; save it.

    Parameters
    ----------
    motions : MotionSet, optional
        Default the Bandai mini set (its own train/val split).
    seed : int
    out : str or Path, optional
        Checkpoint to write (default ``data_samples/weights/aegan.pt``); ``False``: none.
    config : AEGANConfig, optional
        Network sizes (default the paper's; ``structured=False`` for dense twins of the SPLs).
    seconds : float, optional
        Stop after this much wall-clock time even if ``steps`` are not done (the notebook's live demo).
    **settings
        Any of :data:`DEFAULTS`.

    Returns
    -------
    model : AEGAN
    report : dict
        ``curves`` ({loss: [mean per log interval]} for :data:`LOSSES`, ``step``, ``val_rec_mm``), settings,
        seconds, steps done.
    """
    from ...learn.distributed import current

    st = merge_settings("train_aegan", settings, DEFAULTS)
    run = current()  # torchrun: each process draws its own share of every batch
    share = run.share(int(st["batch"]))
    t0 = time.perf_counter()
    motions, td, vd, how = split_pose_data(motions, seed)
    x = torch.as_tensor(td.normalized()).to(run.device)
    xv = vd.normalized()[:2000]
    model = AEGAN.new(motions.skeleton, td.norm, config, seed)
    model.x_range = np.stack([td.normalized().min(0), td.normalized().max(0)])
    E, G, Dx, Dz = model.encoder, model.generator, model.pose_disc, model.latent_disc
    # one module per optimiser step, on the run's device, inside DDP with several processes (some SPL weights
    # get no gradient in a step: DDP is told so)
    dz_step, dx_step = run.wrap(_Logits(Dz), unused=True), run.wrap(_Logits(Dx), unused=True)
    eg_step = run.wrap(_EncoderGeneratorLoss(E, G, Dx, Dz), unused=True)
    betas = (st["beta1"], 0.999)
    opt_eg = torch.optim.Adam([*E.parameters(), *G.parameters()], lr=st["lr"], betas=betas)
    opt_dx = torch.optim.Adam(Dx.parameters(), lr=st["lr_dx"], betas=betas)
    opt_dz = torch.optim.Adam(Dz.parameters(), lr=st["lr"], betas=betas)
    gen = torch.Generator().manual_seed(run.seed(seed))
    b, d, s = share, model.config.latent, float(st["smooth"])
    dev = run.device
    curves = {k: [] for k in (*LOSSES, "step", "val_rec_mm")}
    acc = {k: 0.0 for k in LOSSES}
    n_acc = 0
    bar = None
    if progress:
        from ...progress import tqdm

        bar = tqdm(total=int(st["steps"]), desc="AE-GAN", unit="step")
    done = 0
    with limit_threads(1):
        for step in range(int(st["steps"])):
            if seconds is not None and time.perf_counter() - t0 > seconds:
                break
            for net in (E, G, Dx, Dz):
                net.train()
            # latent discriminator: 3 b samples; prior codes are real, encoded poses fake (4)
            xb = x[torch.randint(0, len(x), (3 * b,), generator=gen)]
            with torch.no_grad():
                ze = E(xb)
            zp = sample_prior(3 * b, d, gen).to(dev)
            loss_, acc_ = _discriminator_step(opt_dz, dz_step, zp, ze, s)
            acc["d_z"] += loss_
            acc["acc_z"] += acc_
            # pose discriminator: b samples; training poses real, generated poses fake (3)
            xr = x[torch.randint(0, len(x), (b,), generator=gen)]
            with torch.no_grad():
                xg = G(sample_prior(b, d, gen).to(dev))
            loss_, acc_ = _discriminator_step(opt_dx, dx_step, xr, xg, s)
            acc["d_x"] += loss_
            acc["acc_x"] += acc_
            # encoder and generator: 2 b samples (5)
            xb = x[torch.randint(0, len(x), (2 * b,), generator=gen)]
            zp = sample_prior(2 * b, d, gen).to(dev)
            rec_x, rec_z, adv_x, adv_z = eg_step(xb, zp)
            loss = st["w_x"] * rec_x + st["w_z"] * rec_z + adv_x + adv_z
            opt_eg.zero_grad()
            loss.backward()
            opt_eg.step()
            for k, v in (("rec_x", rec_x), ("rec_z", rec_z), ("adv_x", adv_x), ("adv_z", adv_z)):
                acc[k] += v.item()
            n_acc += 1
            done = step + 1
            if done % int(st["log_every"]) == 0 or done == int(st["steps"]):
                for k in LOSSES:
                    curves[k].append(run.mean(acc[k] / n_acc))
                    acc[k] = 0.0
                n_acc = 0
                for net in (E, G, Dx, Dz):
                    net.eval()
                curves["step"].append(done)
                curves["val_rec_mm"].append(recon_mm(model, xv))
                if bar is not None:
                    bar.set_postfix(rec_mm=f"{curves['val_rec_mm'][-1]:.1f}", acc_x=f"{curves['acc_x'][-1]:.2f}")
            if bar is not None:
                bar.update()
    if bar is not None:
        finish(bar)                    # a time budget stops it early: the bar ends at the steps that ran
        bar.close()
    for net in (E, G, Dx, Dz):
        net.cpu().eval()  # back on the CPU: what the lessons load
    with torch.no_grad():  # evaluated as shipped: float16 weights
        for net in (E, G, Dx, Dz):
            for p in net.parameters():
                p.copy_(p.half().float())
    report = {"split": how, "train_poses": int(td.n), "val_poses": int(vd.n), "settings": st, "steps": done,
              "processes": run.world, "device": str(run.device),
              "curves": curves, "seconds": time.perf_counter() - t0, "val_rec_mm": recon_mm(model, xv)}
    if out is not False:
        label = data_label or motions.source.split(" (")[0]
        cfg = model.config
        data = (f"{label}: training split ({how}), {td.n} poses + mirrored copies; val {vd.n} poses (seed {seed})")
        model.save(weights_path() if out is None else out,
                   command=command(seed=seed, data=label, structured=cfg.structured, **settings), seed=seed,
                   data=data, licence=weights_licence(label),
                   extra={"report": report})
    return model, report


def _cli(args) -> int:
    """``posekit train aegan``."""

    from ...data.metrics import body_joints

    settings = cli_settings(args, DEFAULTS)
    motions, out = cli_data(args)
    config = AEGANConfig(len(body_joints(motions.skeleton)), structured=not args.dense)
    model, report = train_aegan(motions, seed=args.seed, out=out, config=config, progress=True,
                                **settings)
    path = out or weights_path()
    c = report["curves"]
    print(f"trained {report['steps']} steps in {report['seconds']:.0f} s; held-out reconstruction "
          f"{report['val_rec_mm']:.1f} mm; last interval: pose discriminator accuracy {c['acc_x'][-1]:.2f}, "
          f"latent discriminator accuracy {c['acc_z'][-1]:.2f}")
    print_written(path)
    return 0


_WHAT = (("steps", "training steps"), ("batch", "pose discriminator samples per step (encoder/"
         "generator see 2x, the latent discriminator 3x)"),
         ("lr_dx", "pose discriminator learning rate (Adam)"), ("lr", "the other networks' learning rate"),
         ("w_x", "weight of the pose reconstruction loss"), ("w_z", "weight of the code reconstruction "
         "loss"), ("smooth", "label of real samples (one-sided label smoothing)"),
         ("beta1", "Adam beta1"), ("log_every", "steps per point of the loss curves"))

register_trainer(
    "aegan", _cli, help="AE-GAN pose latent space with SPL layers (lesson 04, Victor & Meyer, JFIG 2020)",
    makes="data_samples/weights/aegan.pt (CC BY-NC 4.0, like the Bandai mini set it is trained on)",
    what="AE-GAN pose latent space with structured prediction layers (Victor & Meyer, JFIG 2020)",
    used_by="lesson 04 (04_aegan_latent_space.ipynb), the latent-opt solvers, posekit bench ik",
    takes="about 9-11 minutes on one core (it trains on one thread: 8 min 35 s measured idle, 11 min "
          "beside another training)",
    shipped=lambda args: "data_samples/weights/aegan.pt",
    args=[arg("--data", default="bandai-mini", help="training data: bandai-mini (default, its own split), "
              "or any posekit data set name / path (split by clip)")]
         + [arg("--" + key.replace("_", "-"), dest=key, type=type(DEFAULTS[key]), default=DEFAULTS[key],
                help=f"{what} (default: {DEFAULTS[key]})") for key, what in _WHAT]
         + [arg("--dense", action="store_true", help="dense layers of equal width instead of SPLs (a comparison)"),
            arg("--seed", type=int, default=0, help="(default: 0)"),
            arg("--out", default=None, help="checkpoint file (default data_samples/weights/aegan.pt; required "
                                          "with another --data: a .pt file, checked before training)")])
