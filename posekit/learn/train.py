"""The one training loop of posekit's learned models: seeded mini-batch descent with optional
early stopping on a validation loss.

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb`` (the inverse-rig network); the learned
solvers of lessons 03-05 train with the same :func:`fit`. Each epoch::

    perm = randperm(N, generator=g)          # g seeded with `seed`: the same batches every run
    for each batch b of perm:  loss_fn(model, *train_data[b]).backward(); optimizer.step()
    val = mean loss_fn over val_data (no gradients), in order

**Past one process.** Inside :func:`posekit.learn.distributed.start` (``posekit train ... --device``, or
``torchrun``) the loop trains on that run's device, and with ``W`` processes each takes every ``W``-th
sample of each batch (the same permutation everywhere) through ``DistributedDataParallel``, which averages
the gradients: the step of one process on the whole batch, shared (``W`` must divide ``batch``; a last
batch smaller than ``W`` is skipped).

**Reproducibility.** For a given ``seed`` the loop is repeatable on one machine: the shuffling
generator and torch's global generator (dropout, noise) are seeded, and nothing else is random.
Build the model under ``torch.manual_seed(seed)`` so its initial weights are seeded too. Another
thread count (``torch.set_num_threads``), CPU or torch build may sum in another order and differ in
the last bits of the floats; use :func:`~posekit.learn.threads.single_thread` when that matters.
"""

from __future__ import annotations

import copy
import math
import time
from dataclasses import dataclass, field

import numpy as np
import torch

__all__ = ["Curves", "fit", "merge_settings"]


@dataclass
class Curves:
    """What :func:`fit` measured.

    Attributes
    ----------
    train : list of float
        Mean training loss of each epoch (over its mini-batches, weighted by batch size).
    val : list of float
        Mean validation loss after each epoch (empty without ``val_data``).
    best_epoch : int
        0-based epoch of the lowest validation loss (of the lowest training loss without
        ``val_data``); with ``patience`` the model holds that epoch's weights.
    stopped_early : bool
        True when ``patience`` epochs passed without a better validation loss.
    seconds : float
        Wall-clock time of the loop.
    """

    train: list = field(default_factory=list)
    val: list = field(default_factory=list)
    best_epoch: int = -1
    stopped_early: bool = False
    seconds: float = 0.0

    @property
    def epochs(self) -> int:
        """Epochs run."""
        return len(self.train)


def merge_settings(name: str, settings: dict, defaults: dict) -> dict:
    """``defaults`` overridden by ``settings``; an unknown key raises a ``ValueError`` listing the valid ones
    (a trainer's ``**settings``)."""
    bad = set(settings) - set(defaults)
    if bad:
        raise ValueError(f"{name}: unknown setting(s) {sorted(bad)}; valid: {sorted(defaults)}")
    return {**defaults, **settings}


def _tensors(data, name: str) -> tuple:
    if isinstance(data, (torch.Tensor, np.ndarray)):
        data = (data,)
    out = []
    for a in data:
        if isinstance(a, np.ndarray) and a.dtype.kind == "f":
            a = torch.as_tensor(a, dtype=torch.float32)
        out.append(torch.as_tensor(a))
    if not out or len({len(a) for a in out}) != 1:
        raise ValueError(f"{name}: expected one or more arrays with the same first dimension (N), got shapes "
                         f"{[tuple(a.shape) for a in out]}")
    if len(out[0]) == 0:
        raise ValueError(f"{name} is empty")
    return tuple(out)


def _optimizer(optimizer, params, lr: float, weight_decay: float):
    if callable(optimizer):
        return optimizer(params)
    if optimizer == "adam":
        return torch.optim.Adam(params, lr=lr, weight_decay=weight_decay)
    if optimizer == "adamw":
        return torch.optim.AdamW(params, lr=lr, weight_decay=weight_decay)
    if optimizer == "sgd":
        return torch.optim.SGD(params, lr=lr, weight_decay=weight_decay)
    raise ValueError(f"optimizer: expected 'adam', 'adamw', 'sgd' or a callable params -> Optimizer, got {optimizer!r}")


def _mean_loss(model, loss_fn, data, batch: int) -> float:
    total = 0.0
    with torch.no_grad():
        for k in range(0, len(data[0]), batch):
            part = tuple(a[k:k + batch] for a in data)
            total += float(loss_fn(model, *part)) * len(part[0])
    return total / len(data[0])


def fit(model: torch.nn.Module, loss_fn, train_data, val_data=None, *, epochs: int, batch: int, lr: float,
        seed: int, patience: int | None = None, progress: bool = True, optimizer="adam",
        weight_decay: float = 0.0, desc: str = "training") -> Curves:
    """Train ``model`` in place with seeded mini-batches.

    Parameters
    ----------
    model : torch.nn.Module
        Built by the caller (under ``torch.manual_seed(seed)`` for seeded initial weights).
    loss_fn : callable
        ``loss_fn(model, *batch) -> scalar tensor``: ``batch`` holds one slice of each array of
        ``train_data``, in order (``loss_fn(model, x, y)``). It calls ``model(...)`` once per batch and
        nothing else of it: with several processes ``model`` is the ``DistributedDataParallel`` wrapper,
        which shares the gradients of that one call.
    train_data : tuple of Tensor or ndarray, each shape (N, ...)
        Arrays indexed together; floating numpy arrays become float32 tensors.
    val_data : tuple of Tensor or ndarray, each shape (M, ...), optional
        Evaluated after each epoch with ``model.eval()`` and no gradients.
    epochs, batch : int
        At most ``epochs`` passes over ``train_data`` in mini-batches of ``batch`` (the last one
        smaller).
    lr : float
    seed : int
        Seeds the shuffling generator and torch's global generator.
    patience : int, optional
        Early stopping (needs ``val_data``): stop after ``patience`` epochs without a lower
        validation loss and restore the weights of the best epoch.
    progress : bool
        Show a ``tqdm.auto`` bar over the epochs.
    optimizer : {'adam', 'adamw', 'sgd'} or callable
        A callable gets ``model.parameters()`` and returns a ``torch.optim.Optimizer`` (then ``lr``
        and ``weight_decay`` are its business).
    weight_decay : float
    desc : str
        Label of the progress bar.

    Returns
    -------
    Curves

    Raises
    ------
    ValueError
        Bad arguments, or the training loss became NaN or infinite.
    """
    if epochs < 1 or batch < 1:
        raise ValueError(f"fit: epochs and batch must be >= 1, got epochs={epochs}, batch={batch}")
    if patience is not None and (val_data is None or patience < 1):
        raise ValueError("fit: patience (early stopping) needs val_data and patience >= 1")
    from .distributed import current

    run = current()
    run.share(batch, "fit: batch")
    train_data = tuple(a.to(run.device) for a in _tensors(train_data, "train_data"))
    val_data = None if val_data is None else tuple(a.to(run.device) for a in _tensors(val_data, "val_data"))
    n = len(train_data[0])
    torch.manual_seed(run.seed(seed))  # dropout and noise: each process its own stream
    g = torch.Generator().manual_seed(seed)  # the shuffle: the same on every process
    net = run.wrap(model)  # model on the run's device; with several processes inside DDP
    opt = _optimizer(optimizer, model.parameters(), lr, weight_decay)
    curves = Curves()
    best, best_state = math.inf, None
    it = range(epochs)
    if progress:
        from ..progress import tqdm

        it = tqdm(it, desc=desc, unit="epoch")
    t0 = time.perf_counter()
    for epoch in it:
        model.train()
        perm = torch.randperm(n, generator=g)
        total = 0.0
        seen = 0
        for k in range(0, n, batch):
            idx = perm[k:k + batch]
            if run.distributed:
                if len(idx) < run.world:  # every process skips it alike: no process without a share
                    continue
                idx = idx[run.rank::run.world]
            loss = loss_fn(net, *(a[idx] for a in train_data))
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += float(loss.detach()) * len(idx)
            seen += len(idx)
        curves.train.append(run.mean(total) / run.mean(seen))
        if not math.isfinite(curves.train[-1]):
            raise ValueError(f"fit: the training loss became {curves.train[-1]} in epoch {epoch}; "
                             "lower lr or check the data for NaN")
        score = curves.train[-1]
        if val_data is not None:
            model.eval()
            score = _mean_loss(model, loss_fn, val_data, batch)
            curves.val.append(score)
            if not math.isfinite(score):
                raise ValueError(f"fit: the validation loss became {score} in epoch {epoch}; "
                                 "check the validation data for NaN or lower lr")
        if progress:
            it.set_postfix(loss=f"{curves.train[-1]:.4g}", **({"val": f"{score:.4g}"} if val_data is not None else {}))
        if score < best:
            best, curves.best_epoch = score, epoch
            if patience is not None:
                best_state = copy.deepcopy(model.state_dict())
        elif patience is not None and epoch - curves.best_epoch >= patience:
            curves.stopped_early = True
            if progress:
                from ..progress import finish

                finish(it)                 # stopped on purpose: the bar ends at the epochs that ran
            break
    if best_state is not None:
        model.load_state_dict(best_state)
    model.eval()
    curves.seconds = time.perf_counter() - t0
    return curves
