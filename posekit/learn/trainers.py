"""The trainer registry: ``posekit train NAME`` for every model whose weights a lesson ships.

A trainer module registers itself when imported, like a benchmark (``register_trainer("aegan", ...)`` at
the end of :mod:`posekit.models.aegan.train`); the built-in ones are listed in lesson order in
:mod:`posekit.catalogue`. ``posekit train`` builds one subcommand per registered trainer, with its own
arguments (:func:`posekit.plugins.arg`), and ``posekit train --list`` prints what each makes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from .. import catalogue
from ..plugins import Arg, Registry

__all__ = ["Trainer", "register_trainer", "unregister_trainer", "get_trainer", "trainer_names", "cli_settings",
           "cli_data", "print_written"]


@dataclass(frozen=True)
class Trainer:
    """What ``posekit train NAME`` runs and says.

    Attributes
    ----------
    name : str
    run : callable
        ``run(args) -> int``: trains from the parsed arguments, prints what it wrote, returns the exit status.
    help : str
        One line for ``posekit train --help``.
    args : tuple of Arg
    makes : str
        The files it writes.
    what : str
        What they hold.
    used_by : str
        The lesson (and commands) that load them.
    takes : str
        About how long it takes.
    """

    name: str
    run: Callable
    help: str
    args: tuple
    makes: str
    what: str
    used_by: str
    takes: str


_TRAINERS = Registry("trainer", catalogue.TRAINERS)


def register_trainer(name: str, run: Callable, *, help: str, makes: str, what: str, used_by: str, takes: str,
                     args=(), replace: bool = False) -> Trainer:
    """Make ``posekit train NAME`` run ``run(args)``; see :class:`Trainer` for the fields.

    Raises
    ------
    ValueError
        When ``name`` is taken (unless ``replace``) or an argument is not an :class:`~posekit.plugins.Arg`.
    """
    if not name or not isinstance(name, str) or name.startswith("-"):
        raise ValueError(f"trainer name must be a non-empty string, got {name!r}")
    for a in args:
        if not isinstance(a, Arg):
            raise ValueError(f"trainer {name!r}: arguments must be made with arg(...), got {a!r}")
    t = Trainer(name, run, help, tuple(args), makes, what, used_by, takes)
    return _TRAINERS.add(name, t, owner=getattr(run, "__module__", ""), replace=replace)


def unregister_trainer(name: str) -> None:
    """Remove a trainer (tests, notebooks)."""
    _TRAINERS.remove(name)


def get_trainer(name: str) -> Trainer:
    """The registered trainer ``name``; a clear error lists the valid names."""
    return _TRAINERS.get(name)


def trainer_names() -> list[str]:
    """Every registered trainer, the built-in ones first, in lesson order."""
    return _TRAINERS.names()


def cli_settings(args, defaults: dict) -> dict:
    """The training settings a ``posekit train NAME`` command line changed from the trainer's ``defaults``
    (only those, so a weight file's recorded command shows what was asked for)."""
    return {k: getattr(args, k) for k in defaults if hasattr(args, k) and getattr(args, k) != defaults[k]}


def cli_data(args):
    """The :class:`~posekit.data.MotionSet` named by ``--data`` (a shipped set's name or a BVH folder,
    :func:`posekit.data.open_dataset`) and the ``--out`` path (None: the shipped file's place)."""
    from pathlib import Path

    from ..data.sources import open_dataset

    return open_dataset(args.data, progress=True), (Path(args.out) if args.out else None)


def print_written(path) -> None:
    """The last line of every trainer: which file it wrote, and its size."""
    print(f"wrote {path} ({path.stat().st_size / 1e3:.0f} kB)")
