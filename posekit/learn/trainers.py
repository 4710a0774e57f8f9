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
           "cli_data", "print_written", "check_out", "DATA_SUFFIXES"]

DATA_SUFFIXES = (".npz", ".npy", ".bvh", ".fbx", ".c3d", ".amc", ".asf", ".csv", ".txt", ".h5", ".hdf5", ".pkl")
"""File endings of motion data: ``posekit train ... --out`` refuses them (a checkpoint never replaces data)."""


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
    out : str
        What ``--out`` names: the ending of the file it writes (``".pt"``, ``".json"``), or ``"/"`` for a folder.
    shipped : callable or None
        ``shipped(args) -> str``: the shipped file that training writes when ``--out`` is not given (a path
        relative to the checkout, said in :func:`check_out`'s refusal); None for a trainer without ``--data``.
    """

    name: str
    run: Callable
    help: str
    args: tuple
    makes: str
    what: str
    used_by: str
    takes: str
    out: str = ".pt"
    shipped: Callable | None = None


_TRAINERS = Registry("trainer", catalogue.TRAINERS)


def register_trainer(name: str, run: Callable, *, help: str, makes: str, what: str, used_by: str, takes: str,
                     args=(), out: str = ".pt", shipped: Callable | None = None, replace: bool = False) -> Trainer:
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
    t = Trainer(name, run, help, tuple(args), makes, what, used_by, takes, out, shipped)
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


def _default(trainer: Trainer, dest: str):
    return next((a.kwargs.get("default") for a in trainer.args if a.dest == dest), None)


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and a.resolve() == b.resolve()
    except OSError:
        return False


def check_out(trainer: Trainer, args) -> None:
    """Refuse a ``posekit train NAME`` command line whose ``--out`` would lose something, before any data is read.

    * ``--data`` other than the trainer's default without ``--out``: training would replace the shipped weights
      (``trainer.shipped(args)``) with a model of other data; the shipped file is written only when ``--out``
      names it.
    * ``--out`` a folder (or ending in ``/``) where the trainer writes a file, a file where it writes a folder;
      the ``--data`` file itself; a name ending like motion data (:data:`DATA_SUFFIXES`); another ending than
      ``trainer.out``; an existing ``.pt`` that is not a posekit checkpoint; a place that cannot be written
      (its folder is a file, or not writable).

    Raises
    ------
    ValueError
        With a sentence that names the option, what was given and what was expected.
    """
    import os
    from pathlib import Path

    out, data = getattr(args, "out", None), getattr(args, "data", None)
    cmd = f"posekit train {trainer.name}"
    if out is None:
        default = _default(trainer, "data")
        if data is not None and data != default and trainer.shipped is not None:
            shipped = trainer.shipped(args)
            raise ValueError(f"{cmd} --data {data}: without --out the model would replace the shipped {shipped} "
                             f"(made from {default}, loaded by the lessons); give --out FILE.pt for your model, e.g. "
                             f"--out my_weights/{Path(shipped).name}, or --out {shipped} to replace the shipped file "
                             "on purpose")
        return
    text, path = str(out), Path(out).expanduser()
    want = "a folder" if trainer.out == "/" else f"a {trainer.out} file"
    if not text.strip():
        raise ValueError(f"{cmd} --out: empty; expected {want}")
    if trainer.out == "/":
        if path.exists() and not path.is_dir():
            raise ValueError(f"{cmd} --out {out}: a file, not a folder; expected the folder to write the weights in")
    else:
        if text.endswith(("/", os.sep)) or path.is_dir():
            example = trainer.shipped(args) if trainer.shipped is not None else f"results{trainer.out}"
            raise ValueError(f"{cmd} --out {out}: a folder; expected {want} to write, e.g. "
                             f"--out {Path(text) / Path(example).name}")
        if data is not None and _same_file(path, Path(str(data)).expanduser()):
            raise ValueError(f"{cmd} --out {out}: that is the --data file, which training would overwrite; "
                             f"expected a new {trainer.out} file for the model")
        if path.suffix.lower() in DATA_SUFFIXES:
            raise ValueError(f"{cmd} --out {out}: a {path.suffix} name is motion data, not a model; expected "
                             f"{want}")
        if path.suffix.lower() != trainer.out:
            raise ValueError(f"{cmd} --out {out}: expected {want} (a name ending in {trainer.out}"
                             + (", what --weights DIR reads)" if trainer.out == ".pt" else ")"))
        if path.is_file() and trainer.out == ".pt":
            from ..paths import checkpoint_identity

            if checkpoint_identity(path) is None:
                raise ValueError(f"{cmd} --out {out}: the file exists and is not a posekit checkpoint, so training "
                                 "would destroy it; expected a new .pt file or one that posekit train wrote")
    parent = path if trainer.out == "/" else path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise ValueError(f"{cmd} --out {out}: {parent} is a file, so nothing can be written under it; expected "
                         f"{want} in a folder")
    if not os.access(parent, os.W_OK | os.X_OK) or (path.exists() and not os.access(path, os.W_OK)):
        raise ValueError(f"{cmd} --out {out}: {path if path.exists() else parent} is not writable; expected {want} "
                         "in a folder you can write")


def print_written(path) -> None:
    """The last line of every trainer: which file it wrote, and its size."""
    print(f"wrote {path} ({path.stat().st_size / 1e3:.0f} kB)")
