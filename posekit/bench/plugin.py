"""Benchmark plug-ins: what ``posekit bench NAME`` runs and prints, declared once per benchmark.

Introduced in ``notebooks/01_fabrik.ipynb``. A benchmark registers its name, its command-line
arguments, a ``run(args) -> list[dict]`` of rows and the tables that show them; the CLI
(:mod:`posekit.cli`) builds one ``posekit bench NAME`` subcommand per registered benchmark and prints
every one the same way: text tables (under 100 columns) or ``--json``. A lesson or a student adds a
benchmark without editing the CLI::

    from posekit.bench.plugin import arg, register_benchmark

    register_benchmark("mine", lambda args: [{"method": "x", "ms": 1.0 * args.n}],
                       help="my benchmark", args=[arg("--n", type=int, default=3, help="repeats")],
                       tables=[("My table", ["method", "ms"])])

The built-in benchmarks (``fk``, ``ik``, ``invrig``, ``ae-scale``, ``protores``, ``all``, ``studio``) register themselves
when their modules are imported; :data:`posekit.catalogue.BENCHMARKS` names them, and the registry imports
them the first time it is asked.
"""

from __future__ import annotations

import argparse
import textwrap
from dataclasses import dataclass, field
from typing import Callable

from .. import catalogue, plugins
from ..plugins import Arg, HelpFormatter, Registry, arg
from .report import format_table, format_tables

__all__ = ["Arg", "arg", "Benchmark", "register_benchmark", "unregister_benchmark", "get_benchmark",
           "benchmark_names", "add_arguments", "HelpFormatter", "WIDTH"]

WIDTH = 100
"""Text output stays within this many columns."""


@dataclass(frozen=True)
class Benchmark:
    """A registered benchmark (see :func:`register_benchmark` for the fields)."""

    name: str
    run: Callable
    help: str = ""
    args: tuple = ()
    tables: tuple = ()
    labels: dict = field(default_factory=dict)
    header: Callable | None = None
    group_by: str | None = None
    group_title: Callable | None = None
    wide: bool = False
    lesson: str = ""
    footer: Callable | None = None

    def namespace(self, **overrides) -> argparse.Namespace:
        """The arguments ``run`` receives, at their defaults unless overridden (``json=False``)."""
        parser = argparse.ArgumentParser(add_help=False)  # argparse itself decides every default
        for a in self.args:
            parser.add_argument(*a.flags, **a.kwargs)
        values = {"json": False, "wide": False, **vars(parser.parse_args([]))}
        unknown = set(overrides) - set(values)
        if unknown:
            raise ValueError(f"benchmark {self.name!r} has no argument(s) {', '.join(sorted(unknown))}; "
                             f"valid: {', '.join(sorted(values))}")
        values.update(overrides)
        return argparse.Namespace(**values)

    def wide_columns(self) -> list:
        """Every column of every table, in order (``--wide``)."""
        cols = [c for t in self.tables for c in t[1]]
        return list(dict.fromkeys(cols))

    def render(self, rows: list[dict], args=None) -> str:
        """The text output of ``posekit bench NAME``: the header, then the tables (once per value of
        ``group_by``, under its title), or a single table of every column with ``args.wide``, then the footer."""
        parts = []
        if self.header is not None:
            parts.append(_wrap(self.header(rows, args)))
        groups = [(None, rows)]
        if self.group_by:
            values = list(dict.fromkeys(r.get(self.group_by) for r in rows))
            groups = [(v, [r for r in rows if r.get(self.group_by) == v]) for v in values]
        for value, grouped in groups:
            if value is not None:
                parts.append(_wrap(self.group_title(value) if self.group_title else f"{self.group_by}: {value}"))
            if args is not None and getattr(args, "wide", False):
                parts.append(format_table(grouped, self.wide_columns(), self.labels))
            else:
                parts.append(format_tables(grouped, list(self.tables), self.labels))
        if self.footer is not None:
            parts.append(_wrap(self.footer(rows, args)))
        return "\n\n".join(p for p in parts if p)


def _wrap(text: str) -> str:
    return "\n".join(textwrap.fill(line, WIDTH) if len(line) > WIDTH else line for line in text.splitlines())


_REGISTRY = Registry("benchmark", catalogue.BENCHMARKS)


def register_benchmark(name: str, run: Callable, *, help: str = "", args=(), tables=(), labels=None,
                       header: Callable | None = None, group_by: str | None = None,
                       group_title: Callable | None = None, wide: bool = False, lesson: str = "",
                       footer: Callable | None = None, replace: bool = False) -> Benchmark:
    """Make ``posekit bench NAME`` run a benchmark.

    Parameters
    ----------
    name : str
        The subcommand.
    run : callable
        ``run(args) -> list[dict]``: ``args`` is the parsed ``argparse.Namespace`` (every argument of
        ``args``, plus ``json`` and ``wide``); one dict per row, JSON-serialisable values.
    help : str
        One line for ``posekit bench --help``.
    args : sequence of Arg
        Its own arguments (:func:`arg`); ``--json`` (and ``--wide`` with ``wide=True``) are added.
    tables : sequence of (title, columns) or (title, columns, where)
        The text tables (:func:`posekit.bench.report.format_tables`); ``where`` (a dict of required
        values, or a predicate on a row) picks the rows of a table.
    labels : dict, optional
        Column key -> short header (units in the header), so the tables fit 100 columns.
    header : callable, optional
        ``header(rows, args) -> str``: lines printed above the tables.
    group_by : str, optional
        Print the tables once per value of this row key (e.g. ``"start"``), under ``group_title(value)``.
    wide : bool
        Offer ``--wide``: one table with every column.
    lesson : str
        The notebook that introduces it.
    footer : callable, optional
        ``footer(rows, args) -> str``: lines printed under the tables (empty: none).
    replace : bool
        Redefine an existing name (e.g. while editing a notebook); otherwise a taken name is an error.
    """
    if not name or not isinstance(name, str) or name.startswith("-"):
        raise ValueError(f"benchmark name must be a non-empty string, got {name!r}")
    for a in args:
        if not isinstance(a, Arg):
            raise ValueError(f"benchmark {name!r}: arguments must be made with arg(...), got {a!r}")
    b = Benchmark(name, run, help, tuple(args), tuple(tables), dict(labels or {}), header, group_by, group_title,
                  bool(wide), lesson, footer)
    return _REGISTRY.add(name, b, owner=getattr(run, "__module__", ""), replace=replace)


def unregister_benchmark(name: str) -> None:
    """Remove a benchmark (tests, notebooks)."""
    _REGISTRY.remove(name)


def get_benchmark(name: str) -> Benchmark:
    """The registered benchmark ``name``; a clear error lists the valid names."""
    return _REGISTRY.get(name)


def benchmark_names() -> list[str]:
    """Every registered benchmark, the built-in ones first."""
    return _REGISTRY.names()


def add_arguments(parser: argparse.ArgumentParser, b: Benchmark) -> None:
    """Add a benchmark's arguments (and ``--json``, ``--wide``) to its subparser."""
    plugins.add_arguments(parser, b.args)
    if b.wide:
        parser.add_argument("--wide", action="store_true", help="one wide table instead of several")
    parser.add_argument("--json", action="store_true", help="print the rows as JSON")
