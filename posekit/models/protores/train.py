"""Training ProtoRes and its baselines (Oreshkin et al. 2022, Sec. 2.2-2.3, Algorithm 1, Appendix B).

Introduced in ``notebooks/05_protores.ipynb``; ``posekit train protores`` runs :func:`train_protores`.

Losses, on a batch from :func:`~posekit.models.protores.data.draw_batch` (B poses, body joints j)::

    L_gpd-L2  = sum_j w_j mean_xyz (p^gpd_j - p_j)^2 / sum_j w_j      GPD positions      (Eq. 7)
    L_ikd-L2  = the same for the FK positions p^fk                     the final pose     (Eq. 7)
    L_loc-geo = mean_j angle(R^loc_j, R*^loc_j)                        local rotations    (Eq. 8)
    L_glob-geo = sum_j u_j angle(R^glob_j, R*^glob_j) / sum_j u_j      rotation effectors (Eq. 8)
    L_look-at = mean_k angle(R^glob_j(k) v_k, t_k - p^fk_j(k))          look-at effectors  (Eq. 9)
    L = W_pos (L_gpd-L2 + L_ikd-L2) + L_loc-geo + L_glob-geo + L_look-at

**Randomized weighting** (the paper's contribution to the loss): ``w_j = 1`` for a joint without an
effector and ``min(W_M, 1 / sigma)`` for a joint with a position effector of noise scale ``sigma``
(so an exact effector counts a thousand times a free joint, a loose one about ten times); ``u_j`` is
that weight on rotation-effector joints and 0 elsewhere. With ``weighted=False`` (Table 2's ablation)
every ``w_j = u_j = 1``. Paper values: ``W_pos = 100`` (10 for the Transformer in the paper's text;
the authors' configs use 100 for all three, as here), ``W_M = 1000``, ``sigma_M = 0.1``, ``eta = 13``.

``angle(A, B) = arccos(clamp((tr(A^T B) - 1) / 2, -1 + 1e-6, 1 - 1e-6))``: the clamp keeps the gradient
of ``arccos`` finite when a prediction is exactly right (or exactly opposite).

Schedule: Adam (lr 5e-4 here, 2e-4 in the paper with batches of 2048 on a GPU; 200 warm-up steps, then
a cosine decay to a tenth, :func:`_lr_factor`), one thread per process
(:func:`posekit.learn.limit_threads`), fixed step counts per encoder (:data:`STEPS`) so that every run
repeats exactly. The shipped networks are width 256, each trained for a user's hour of two cores: two
processes under ``torchrun`` (:mod:`posekit.learn.distributed`), 128 poses each per step of 256.
"""

from __future__ import annotations

import time

import numpy as np
import torch

from ...learn import limit_threads, merge_settings
from ...progress import finish
from ...learn.trainers import cli_data, cli_settings, print_written, register_trainer
from ...plugins import arg
from ...data.bandai_mini import weights_licence
from .networks import ARCHS, PosingNet, ProtoResConfig, weights_path
from .data import PoseBank, draw_batch
from .fast import WEIGHTS as _WEIGHTS

__all__ = ["DEFAULTS", "STEPS", "WIDTH", "LOSSES", "geodesic", "losses", "train_protores",
           "validation_batches", "evaluate_batches", "command"]

DEFAULTS = dict(steps=None, batch=256, lr=5e-4, warmup=200, w_pos=100.0, w_max=1000.0, n_min=3, n_max=16,
                min_position=3, weighted=True, log_every=250, val_batches=8)
"""Training settings of the shipped weights (``steps=None``: :data:`STEPS` of the encoder)."""

STEPS = {"protores": 20000, "masked-fcr": 42000, "transformer": 10600}
"""Steps per encoder at the shipped width (256), each sized to about the same wall-clock time, an hour of two
processes (``torchrun --nproc-per-node 2``; ``docs/training.md``): Masked-FCR's step is the
cheapest, the Transformer's about twice ProtoRes's."""

WIDTH = 256
"""Units per layer of the shipped networks (the paper: 1024)."""

LOSSES = ("total", "gpd_l2", "ikd_l2", "loc_geo", "glob_geo", "look_at")


def command(arch: str = "protores", seed: int = 0, config: dict | None = None, data: str = "bandai-mini",
            **settings) -> str:
    """The command line that makes weights with these settings."""
    parts = ([f"--arch {arch}"] * (arch != "protores") + [f"--data {data}"] * (data != "bandai-mini")
             + [f"--seed {seed}"])
    base = ProtoResConfig(1)
    for k in ("width", "gpd"):
        if config and config.get(k) != getattr(base, k):
            parts.append("--no-gpd" if k == "gpd" else f"--width {config[k]}")
    for k, v in settings.items():
        if k in DEFAULTS and v != DEFAULTS[k] and v is not None:
            parts.append("--fixed-weights" if k == "weighted" else f"--{k.replace('_', '-')} {v}")
    return "posekit train protores " + " ".join(parts)


def geodesic(A, B, eps: float = 1e-6):
    """Angle between rotation matrices (..., 3, 3), radians, with the cosine clamped inside (-1, 1)."""
    c = ((A * B).sum(dim=(-1, -2)) - 1.0) / 2.0
    return torch.arccos(c.clamp(-1.0 + eps, 1.0 - eps))


def _weighted_mse(pred, true, w):
    return ((w * ((pred - true) ** 2).mean(-1)).sum(-1) / w.sum(-1)).mean()


def losses(out: dict, b, body, w_pos: float = 100.0, w_max: float = 1000.0, weighted: bool = True) -> dict:
    """The loss terms of the module docstring for one batch; ``total`` is what training minimises."""
    Bn, N = b.joint.shape
    nb = len(body)
    bi = torch.arange(Bn)[:, None]
    ew = torch.minimum(torch.full_like(b.sigma, w_max), 1.0 / b.sigma.clamp_min(1.0 / w_max))
    if weighted:
        # one position effector per joint at most: w_j = 1 + (weight - 1) on those joints (accumulated, so
        # that another kind's effector on the same joint cannot overwrite it)
        w = torch.ones(Bn, nb).index_put((bi.expand_as(b.joint), b.joint),
                                         torch.where(b.kind == 0, ew - 1.0, torch.zeros_like(ew)), accumulate=True)
        u = torch.zeros(Bn, nb).index_put((bi.expand_as(b.joint), b.joint),
                                          torch.where(b.kind == 1, ew, torch.zeros_like(ew)), accumulate=True)
    else:
        w = torch.ones(Bn, nb)
        u = torch.ones(Bn, nb)
    P, G, Lr = b.global_pos[:, body], b.global_rot[:, body], b.local_rot[:, body]
    fk_pos, fk_rot = out["global_pos"][:, body], out["global_rot"][:, body]
    terms = {"ikd_l2": _weighted_mse(fk_pos, P, w), "loc_geo": geodesic(out["local_rot"][:, body], Lr).mean()}
    gpd = out["gpd_pos"]
    terms["gpd_l2"] = _weighted_mse(gpd[:, body], P, w) if gpd is not None else fk_pos.new_zeros(())
    gg = geodesic(fk_rot, G)
    us = u.sum(-1)
    terms["glob_geo"] = ((u * gg).sum(-1) / us.clamp_min(1e-9)).sum() / (us > 0).sum().clamp_min(1)
    look = b.kind == 2
    if bool(look.any()):
        sk = torch.as_tensor(body)[b.joint]
        d = (out["global_rot"][bi, sk] @ b.axis[..., None])[..., 0]
        t = b.target - out["global_pos"][bi, sk]
        cos = (d * t).sum(-1) / (d.norm(dim=-1) * t.norm(dim=-1)).clamp_min(1e-9)
        terms["look_at"] = torch.arccos(cos.clamp(-1 + 1e-6, 1 - 1e-6))[look].mean()
    else:
        terms["look_at"] = fk_pos.new_zeros(())
    terms["total"] = (w_pos * (terms["gpd_l2"] + terms["ikd_l2"]) + terms["loc_geo"] + terms["glob_geo"]
                      + terms["look_at"])
    return terms


def validation_batches(bank: PoseBank, n: int = 8, batch: int = 256, seed: int = 1234, **draw) -> list:
    """``n`` fixed batches of ``bank`` (a seed of their own), for curves comparable across runs."""
    gen = torch.Generator().manual_seed(seed)
    return [draw_batch(bank, batch, gen, **draw) for _ in range(n)]


@torch.no_grad()
def evaluate_batches(net: PosingNet, batches) -> dict:
    """Mean of the paper's metrics over ``batches``: ``ikd_l2`` (MSE of the FK positions over every body
    joint's coordinates, m^2), ``gpd_l2`` (the same for the GPD), ``loc_geo`` (mean local-rotation angle,
    radians) and ``mpjpe_mm`` (mean per-joint distance of the FK pose, millimetres)."""
    body = net.body
    acc = {"ikd_l2": 0.0, "gpd_l2": 0.0, "loc_geo": 0.0, "mpjpe_mm": 0.0}
    for b in batches:
        out = net(b.joint, b.kind, b.value, b.tol)
        P = b.global_pos[:, body]
        acc["ikd_l2"] += float(((out["global_pos"][:, body] - P) ** 2).mean())
        acc["gpd_l2"] += float(((out["gpd_pos"][:, body] - P) ** 2).mean()) if out["gpd_pos"] is not None else np.nan
        acc["loc_geo"] += float(geodesic(out["local_rot"][:, body], b.local_rot[:, body]).mean())
        acc["mpjpe_mm"] += float((out["global_pos"][:, body] - P).norm(dim=-1).mean() * 1000)
    return {k: v / len(batches) for k, v in acc.items()}


def _lr_factor(step: int, steps: int, warmup: int) -> float:
    """Linear warm-up over ``warmup`` steps, then a cosine from 1 to 0.1 (ours: the paper keeps the rate
    constant over a far longer run; a short CPU budget ends better with a decay)."""
    if step < warmup:
        return (step + 1) / warmup
    t = (step - warmup) / max(1, steps - warmup)
    return 0.1 + 0.45 * (1 + np.cos(np.pi * min(t, 1.0)))


def train_protores(motions=None, *, arch: str = "protores", seed: int = 0, out=None, progress: bool = True,
                   config: ProtoResConfig | None = None, seconds: float | None = None, data_label: str | None = None,
                   **settings):
    """Train a :class:`~posekit.models.protores.networks.PosingNet` on the training poses (mirrored) of ``motions``.

    Parameters
    ----------
    motions : MotionSet, optional
        Default the Bandai mini set (its own train/val split; the test clips stay unseen).
    arch : str
        One of :data:`~posekit.models.protores.networks.ARCHS`.
    seed : int
    out : str or Path, optional
        Checkpoint to write (default :func:`weights_path` of ``arch``); ``False``: none.
    config : ProtoResConfig, optional
        Sizes (default :class:`ProtoResConfig` at the shipped :data:`WIDTH`; ``arch`` overrides its ``arch``).
    seconds : float, optional
        Stop after this much wall-clock time (the notebook's live demo).
    **settings
        Any of :data:`DEFAULTS`.

    Returns
    -------
    net : PosingNet
    report : dict
        ``curves`` (:data:`LOSSES` averaged per ``log_every`` steps, ``step``, ``seconds`` and the validation
        metrics of :func:`evaluate_batches`), settings, steps done, seconds, seconds per step.
    """
    from ...data.bandai_mini import load_bandai_mini
    from ...data.cases import case_split
    from ...data.metrics import body_joints

    from ...learn.distributed import current

    st = merge_settings("train_protores", settings, DEFAULTS)
    if arch not in ARCHS:
        raise ValueError(f"arch must be one of {', '.join(ARCHS)}, got {arch!r}")
    steps = int(st["steps"] or STEPS[arch])
    run = current()  # torchrun: each process draws its own share of every batch
    share = run.share(int(st["batch"]))
    t0 = time.perf_counter()
    motions = load_bandai_mini() if motions is None else motions
    train, val, _, how = case_split(motions, seed)
    bank = PoseBank(motions, train, mirror=True)
    vbank = PoseBank(motions, val)
    draw = dict(n_min=int(st["n_min"]), n_max=int(st["n_max"]), min_position=int(st["min_position"]))
    vb = validation_batches(vbank, int(st["val_batches"]), **draw)
    torch.manual_seed(seed)
    cfg = config or ProtoResConfig(len(body_joints(motions.skeleton)), width=WIDTH)
    cfg = ProtoResConfig(**{**cfg.to_dict(), "arch": arch})
    net = PosingNet(motions.skeleton, cfg)
    # on the run's device; with several processes inside DDP (net: the plain network). The last residual block's
    # skip layer of each FCR feeds nothing (its output is not read): DDP is told some parameters get no gradient
    model = run.wrap(net, unused=True)
    opt = torch.optim.Adam(net.parameters(), lr=float(st["lr"]))
    sched = torch.optim.lr_scheduler.LambdaLR(opt, lambda i: _lr_factor(i, steps, int(st["warmup"])))
    gen = torch.Generator().manual_seed(run.seed(seed))
    curves = {k: [] for k in (*LOSSES, "step", "seconds", "val_ikd_l2", "val_gpd_l2", "val_loc_geo", "val_mpjpe_mm")}
    acc = {k: 0.0 for k in LOSSES}
    n_acc, done, bar = 0, 0, None
    if progress:
        from ...progress import tqdm

        bar = tqdm(total=steps, desc=f"train {arch}", unit="step")
    train_seconds = 0.0
    with limit_threads(1):
        for step in range(steps):
            if seconds is not None and time.perf_counter() - t0 > seconds:
                break
            ts = time.perf_counter()
            net.train()
            b = draw_batch(bank, share, gen, **draw).to(run.device)
            terms = losses(model(b.joint, b.kind, b.value, b.tol), b, net.body, st["w_pos"], st["w_max"],
                           bool(st["weighted"]))
            opt.zero_grad()
            terms["total"].backward()
            opt.step()
            sched.step()
            train_seconds += time.perf_counter() - ts
            for k in LOSSES:
                acc[k] += float(terms[k].detach())  # this process's share; averaged over processes when logged
            n_acc += 1
            done = step + 1
            if done % int(st["log_every"]) == 0 or done == steps:
                for k in LOSSES:
                    curves[k].append(run.mean(acc[k] / n_acc))
                    acc[k] = 0.0
                n_acc = 0
                net.eval()
                m = evaluate_batches(net, [v.to(run.device) for v in vb])
                for k, v in m.items():
                    curves[f"val_{k}"].append(v)
                curves["step"].append(done)
                curves["seconds"].append(train_seconds)
                if bar is not None:
                    bar.set_postfix(val_world_mm=f"{m['mpjpe_mm']:.1f}")  # the world joint error, not MPJPE (lesson 05)
            if bar is not None:
                bar.update()
    if bar is not None:
        finish(bar)                    # a time budget stops it early: the bar ends at the steps that ran
        bar.close()
    net.cpu().eval()  # the plain network, back on the CPU: what the lessons load
    with torch.no_grad():  # evaluated as shipped: float16 weights
        for p in net.parameters():
            p.copy_(p.half().float())
    final = evaluate_batches(net, vb)
    report = {"split": how, "train_poses": int(len(bank)), "val_poses": int(len(vbank)), "settings": st,
              "processes": run.world, "device": str(run.device),
              "steps": done, "curves": curves, "seconds": time.perf_counter() - t0, "train_seconds": train_seconds,
              "seconds_per_step": train_seconds / max(done, 1), "val": final, "parameters": net.n_parameters()}
    if out is not False:
        label = data_label or motions.source.split(" (")[0]
        data = (f"{label}: training split ({how}), {len(train)} poses + mirrored copies; val {len(val)} poses "
                f"(seed {seed})")
        net.save(weights_path(arch) if out is None else out,
                 command=command(arch, seed, cfg.to_dict(), data=label, **settings), seed=seed, data=data,
                 licence=weights_licence(label), extra={"report": report})
    return net, report


def _cli(args) -> int:
    """``posekit train protores``."""
    from pathlib import Path

    from ...data.bandai_mini import load_bandai_mini
    from ...data.metrics import body_joints

    settings = cli_settings(args, DEFAULTS)
    if args.fixed_weights:
        settings["weighted"] = False
    motions = load_bandai_mini() if args.data == "bandai-mini" else cli_data(args)[0]
    config = ProtoResConfig(len(body_joints(motions.skeleton)), arch=args.arch, width=args.width, gpd=not args.no_gpd)
    out = Path(args.out) if args.out else None
    net, report = train_protores(motions, arch=args.arch, seed=args.seed, out=out, config=config,
                                 progress=True, **settings)
    v = report["val"]
    print(f"trained {args.arch} ({report['parameters']} parameters) {report['steps']} steps in "
          f"{report['seconds']:.0f} s ({report['seconds_per_step'] * 1000:.0f} ms/step); validation: L_ikd-L2 "
          f"{v['ikd_l2'] * 1000:.2f}e-3 m^2, L_loc-geo {v['loc_geo']:.3f} rad, MPJPE {v['mpjpe_mm']:.1f} mm")
    path = out or weights_path(args.arch)
    print_written(path)
    return 0


_WHAT = (("batch", "poses per step"), ("lr", "learning rate (Adam)"), ("warmup", "warm-up steps"),
         ("w_pos", "W_pos, weight of the two position losses"), ("w_max", "W_M, largest effector weight"),
         ("log_every", "steps per point of the curves"))

register_trainer(
    "protores", _cli, help="ProtoRes or one of its baselines: effectors -> pose (lesson 05, Oreshkin et al. 2022)",
    makes="data_samples/weights/protores.pt, protores_masked_fcr.pt, protores_transformer.pt (CC BY-NC 4.0, "
          "like the Bandai mini set they are trained on); one per --arch",
    what="ProtoRes and its Masked-FCR and Transformer baselines (Oreshkin et al. 2022)",
    used_by="lesson 05 (05_protores.ipynb), the protores solvers, posekit bench protores",
    takes="about an hour each on 2 cores under torchrun --standalone --nproc-per-node 2 (the shipped networks; "
          "one process: about twice as long)",
    shipped=lambda args: f"data_samples/weights/{_WEIGHTS[args.arch]}",
    args=[arg("--data", default="bandai-mini", help="training data: bandai-mini (default, its own split), or any "
              "posekit data set name / path (split by clip; e.g. bandai1 for the full Bandai set 1)"),
          arg("--arch", choices=ARCHS, default="protores",
              help="encoder: protores (default), masked-fcr or transformer (the paper's baselines)"),
          arg("--steps", type=int, default=None,
              help="training steps (default: " + ", ".join(f"{k} {v}" for k, v in STEPS.items()) + ")")]
         + [arg("--" + key.replace("_", "-"), dest=key, type=type(DEFAULTS[key]), default=DEFAULTS[key],
                help=f"{what} (default: {DEFAULTS[key]})") for key, what in _WHAT]
         + [arg("--width", type=int, default=WIDTH, help=f"units per layer (default: {WIDTH}; the paper: 1024)"),
            arg("--no-gpd", action="store_true", help="no global position decoder (Table 2's ablation)"),
            arg("--fixed-weights", action="store_true",
                help="every joint weighted 1 instead of the randomized min(W_M, 1/sigma) (Table 2's ablation)"),
            arg("--seed", type=int, default=0, help="(default: 0)"),
            arg("--out", default=None, help="checkpoint file (default data_samples/weights/protores*.pt; required "
                                          "with another --data: a .pt file, checked before training)")])
