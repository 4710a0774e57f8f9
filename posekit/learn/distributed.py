"""Training past one CPU: the device to train on and data-parallel runs under ``torchrun``.

Introduced with ``posekit train ... --device`` (``docs/training.md``); every trainer of lessons 02-05
runs through it. torch's own engine does the work: ``torchrun`` starts the processes and sets ``RANK``,
``WORLD_SIZE`` and ``LOCAL_RANK``; :func:`start` joins them into a process group (``gloo`` on CPU, ``nccl``
on CUDA) and each trainer wraps its network in ``DistributedDataParallel`` (:meth:`Run.wrap`), which
averages the gradients of every backward pass across processes::

    torchrun --nproc-per-node 2 -m posekit train protores --batch 512     # two processes, 256 poses each

**Data parallelism.** A step of batch ``B`` on ``W`` processes: each process computes the mean loss of its
own ``B / W`` samples; DDP's average of their gradients is then the gradient of the mean loss over all ``B``
(equal shares: ``W`` must divide ``B``, :meth:`Run.share`). Where a trainer draws its samples (ProtoRes,
AE-GAN), each process draws with its own generator, seeded by :meth:`Run.seed` from the run's seed (rank 0
keeps the seed itself, so a one-process run is the run it always was); where it shuffles a fixed set
(:func:`posekit.learn.fit`), every process draws the same permutation and takes every ``W``-th sample of
each batch. The weights start equal (the same seed; DDP also copies rank 0's) and stay equal, so the
checkpoint is written once, by rank 0, from the plain network: the single-process code loads it.

**Reproducibility.** A run repeats exactly for the same seed, world size and device; another world size
draws other samples (other per-process generators), as another batch size would.
"""

from __future__ import annotations

import os
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import torch

__all__ = ["Run", "current", "start", "check_device", "launched_world", "launcher", "DEVICES"]

DEVICES = "cpu (default), cuda or cuda:N"


def check_device(device: str | None) -> torch.device:
    """The torch device named by ``--device``; a ``ValueError`` names what is wrong (an unknown name, CUDA
    asked on a machine without it, a GPU index the machine does not have)."""
    name = "cpu" if device in (None, "") else str(device).strip().lower()
    try:
        dev = torch.device(name)
    except (RuntimeError, ValueError):
        raise ValueError(f"--device: expected {DEVICES}, got {device!r}") from None
    if dev.type == "cpu":
        return dev
    if dev.type != "cuda":
        raise ValueError(f"--device: expected {DEVICES}, got {device!r} (posekit trains on CPU or CUDA only)")
    if not torch.cuda.is_available():
        raise ValueError(f"--device {name}: this machine has no CUDA GPU that torch can use "
                         f"(torch {torch.__version__}, built {'with' if torch.version.cuda else 'without'} CUDA); "
                         "train with --device cpu")
    if dev.index is not None and dev.index >= torch.cuda.device_count():
        raise ValueError(f"--device {name}: this machine has {torch.cuda.device_count()} CUDA GPU(s), "
                         f"numbered 0-{torch.cuda.device_count() - 1}")
    return dev


@dataclass(frozen=True)
class Run:
    """What this process is in a training run.

    Attributes
    ----------
    device : torch.device
        Where the networks train (with ``torchrun`` on CUDA: GPU ``LOCAL_RANK``).
    rank : int
        This process's number, 0 to ``world - 1`` (0 writes the checkpoint and prints).
    world : int
        Processes training together (1: no process group, no DDP).
    """

    device: torch.device = torch.device("cpu")
    rank: int = 0
    world: int = 1

    @property
    def main(self) -> bool:
        """True on the process that writes checkpoints and prints (rank 0)."""
        return self.rank == 0

    @property
    def distributed(self) -> bool:
        return self.world > 1

    def seed(self, seed: int) -> int:
        """This process's seed for what it draws on its own: ``seed`` itself on rank 0, on rank ``r > 0`` a
        number derived from ``(seed, r)`` (``numpy.random.SeedSequence``: unrelated streams)."""
        if self.rank == 0:
            return int(seed)
        return int(np.random.SeedSequence([int(seed), self.rank]).generate_state(1)[0])

    def share(self, batch: int, what: str = "--batch") -> int:
        """This process's part of a batch of ``batch`` samples; refuses a world size that does not divide it."""
        if batch % self.world:
            raise ValueError(f"{what} {batch} does not divide among {self.world} processes (torchrun "
                             f"--nproc-per-node x nodes): use a multiple of {self.world}, e.g. "
                             f"{(batch // self.world + 1) * self.world}")
        return batch // self.world

    def wrap(self, module: torch.nn.Module, unused: bool = False) -> torch.nn.Module:
        """``module`` on :attr:`device`, inside ``DistributedDataParallel`` when several processes train (call
        the wrapper once per backward pass; keep the plain module for evaluation and saving). ``unused``: some
        parameters get no gradient in a step (DDP's ``find_unused_parameters``: a search per step)."""
        module.to(self.device)
        if not self.distributed:
            return module
        from torch.nn.parallel import DistributedDataParallel

        ids = [self.device.index] if self.device.type == "cuda" else None
        return DistributedDataParallel(module, device_ids=ids, find_unused_parameters=unused)

    def mean(self, value: float) -> float:
        """The mean of a number over the processes (a logged loss); the number itself on one process."""
        if not self.distributed:
            return float(value)
        t = torch.tensor([float(value)], dtype=torch.float64, device=self.device)
        torch.distributed.all_reduce(t)
        return float(t.item()) / self.world

    def barrier(self) -> None:
        """Wait for every process (before reading what rank 0 wrote)."""
        if self.distributed:
            torch.distributed.barrier()


_CURRENT = [Run()]


def launched_world() -> int:
    """How many processes ``torchrun`` started for this run (its ``WORLD_SIZE``); 1 outside torchrun."""
    return int(os.environ.get("WORLD_SIZE", "1") or 1)


def launcher(world: int) -> str:
    """What goes in front of a ``posekit ...`` command to start it as this run was started: ``torchrun
    --nproc-per-node N -m `` (and ``--nnodes M`` past one machine, from torchrun's ``LOCAL_WORLD_SIZE``)."""
    local = int(os.environ.get("LOCAL_WORLD_SIZE", "") or world)
    nodes = max(1, int(world) // max(1, local))
    return "torchrun " + (f"--nnodes {nodes} " if nodes > 1 else "") + f"--nproc-per-node {local} -m "


def current() -> Run:
    """The run this process is part of (:func:`start`); outside one: one process on the CPU."""
    return _CURRENT[-1]


@contextmanager
def start(device: str | None = "cpu"):
    """Join the run ``torchrun`` started (``WORLD_SIZE`` > 1: a process group) or run alone; yields the
    :class:`Run`, which :func:`current` returns inside the block. The device is checked first, before any
    process group or data, and the group is left at the end, also on error.

    Raises
    ------
    ValueError
        A bad ``device`` (:func:`check_device`), or ``torchrun``'s variables half set.
    """
    dev = check_device(device)
    world = launched_world()
    if world <= 1:
        _CURRENT.append(Run(dev))
        try:
            yield _CURRENT[-1]
        finally:
            _CURRENT.pop()
        return
    try:
        rank, local = int(os.environ["RANK"]), int(os.environ.get("LOCAL_RANK", "0"))
    except KeyError:
        raise ValueError("WORLD_SIZE is set but RANK is not: start several processes with torchrun, "
                         "e.g. torchrun --nproc-per-node 2 -m posekit train NAME") from None
    if dev.type == "cuda":
        if torch.cuda.device_count() <= local:
            raise ValueError(f"--device cuda under torchrun: process {local} on this node needs GPU {local}, "
                             f"the machine has {torch.cuda.device_count()}")
        dev = torch.device("cuda", local)
        torch.cuda.set_device(dev)
    torch.distributed.init_process_group("nccl" if dev.type == "cuda" else "gloo", rank=rank, world_size=world)
    _CURRENT.append(Run(dev, rank, world))
    try:
        yield _CURRENT[-1]
    finally:
        _CURRENT.pop()
        torch.distributed.destroy_process_group()
