"""What the plug-in registries share: a registry that fills itself from the catalogue, and argument specs.

Solvers (:mod:`posekit.ik.registry`), trainers (:mod:`posekit.learn.trainers`), benchmarks
(:mod:`posekit.bench.plugin`) and the extra methods of ``posekit bench ik`` (:mod:`posekit.bench.ik`) are
each a :class:`Registry`: the first time one is asked, it imports the built-in modules that
:mod:`posekit.catalogue` names, and each of them registers itself. A name is taken once: registering it
again is an error unless ``replace=True`` is asked for (a notebook redefining its own solver); the message names the module that holds the name. Command-line arguments of a plug-in are :class:`Arg` specs (:func:`arg`), added to its
subparser by :func:`add_arguments`.
"""

from __future__ import annotations

import argparse
import importlib
import textwrap
from dataclasses import dataclass, field

__all__ = ["Registry", "Arg", "arg", "add_arguments", "HelpFormatter"]


class Registry:
    """Name -> entry for one kind of plug-in, the catalogue's modules imported when first asked.

    Parameters
    ----------
    what : str
        The kind, for messages (``"solver"``, ``"benchmark"``).
    modules : sequence of str
        The built-in modules (:mod:`posekit.catalogue`), imported in this order.
    load_on_add : bool
        Import the built-in modules before another module registers a name, so that they keep theirs
        (False where registering must stay cheap: a notebook's solver does not import every model).
    """

    def __init__(self, what: str, modules, load_on_add: bool = True):
        self.what = what
        self.modules = tuple(modules)
        self.load_on_add = load_on_add
        self._entries: dict = {}
        self._owners: dict = {}
        self._loading = False
        self._loaded = False

    def load(self) -> None:
        """Import the built-in modules (once; a no-op while they are being imported)."""
        if self._loaded or self._loading:
            return
        self._loading = True
        try:
            for m in self.modules:
                importlib.import_module(m)
            self._loaded = True
        finally:
            self._loading = False

    def add(self, name: str, entry, *, owner: str = "", replace: bool = False):
        """Register ``entry`` as ``name``. ``owner``: the module registering it (a module that is not in the
        catalogue has the built-in ones imported first, when ``load_on_add``).

        Raises
        ------
        ValueError
            When ``name`` is taken and ``replace`` is not asked for.
        """
        if self.load_on_add and owner not in self.modules:
            self.load()
        if name in self._entries and not replace:
            by = self._owners.get(name)
            raise ValueError(f"a {self.what} named {name!r} is already registered" + (f" (by {by})" if by else "")
                             + "; pass replace=True to redefine it")
        self._entries[name] = entry
        self._owners[name] = owner
        return entry

    def remove(self, name: str) -> None:
        self._entries.pop(name, None)
        self._owners.pop(name, None)

    def __contains__(self, name) -> bool:
        return name in self._entries

    def get(self, name: str):
        """The entry ``name``; a clear error lists the valid names."""
        self.load()
        if name not in self._entries:
            raise ValueError(f"unknown {self.what} {name!r}; valid: {', '.join(self._entries)}")
        return self._entries[name]

    def names(self) -> list[str]:
        """Every registered name: the built-in ones in catalogue order, then the others as registered."""
        self.load()
        return list(self._entries)


@dataclass(frozen=True)
class Arg:
    """One command-line argument: the positional and keyword arguments of ``ArgumentParser.add_argument``."""

    flags: tuple
    kwargs: dict = field(default_factory=dict)

    @property
    def dest(self) -> str:
        return self.kwargs.get("dest") or self.flags[0].lstrip("-").replace("-", "_")


def arg(*flags, **kwargs) -> Arg:
    """An argument spec, written like ``parser.add_argument`` (``arg("--cases", type=int, default=1000,
    help="cases per start condition")``)."""
    return Arg(tuple(flags), dict(kwargs))


class HelpFormatter(argparse.HelpFormatter):
    """``--help`` that never breaks a name at its hyphen (``same-clip``, ``fabrik-constrained``)."""

    def _split_lines(self, text, width):
        return textwrap.wrap(" ".join(text.split()), width, break_on_hyphens=False)


def add_arguments(parser: argparse.ArgumentParser, args, default_in_help: bool = True) -> None:
    """Add argument specs to a subparser; ``default_in_help``: append ``(default: ...)`` to a help that
    does not say it."""
    for a in args:
        if not isinstance(a, Arg):
            raise ValueError(f"arguments must be made with arg(...), got {a!r}")
        kw = dict(a.kwargs)
        if (default_in_help and "help" in kw and "default" in kw and kw.get("action") != "store_true"
                and "default" not in kw["help"]):
            kw["help"] = f"{kw['help']} (default: %(default)s)"
        parser.add_argument(*a.flags, **kw)
