"""The documentation pages the code writes: ``posekit docs build``.

Three pages under ``docs/`` are reference, not prose, so they are generated and never typed:

* ``docs/cli.md`` — every ``posekit`` subcommand and option, from the argument parser
  (:mod:`posekit.docs.cli_page`);
* ``docs/benchmarks.md`` — every measured figure the documentation shows, from the results files under
  ``data_samples/results``, each with the command, machine and date inside the file
  (:mod:`posekit.docs.bench_page`);
* ``docs/tested-versions.md`` — the newest notebook stack ``make test-latest`` last passed with, from the record
  that run wrote (:mod:`posekit.docs.versions_page`).

``posekit docs build`` rewrites them; ``posekit docs build --check`` writes nothing and exits 1 naming every page
that differs from what the code writes now (``tests/test_docs.py`` runs the same comparison). The other pages of
``docs/`` are guides written by hand (``docs/index.md`` lists them all).

The CLI sits above this package: it builds the argument parser (:func:`posekit.cli.build_parser`) and hands it in
(``parser`` below; :func:`add_commands` keeps the parser it is given for ``posekit docs build``), so no module here
imports the CLI it documents.
"""

from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["GENERATED", "docs_dir", "pages", "build", "stale", "add_commands"]

GENERATED = ("cli.md", "benchmarks.md", "tested-versions.md")
"""The pages ``posekit docs build`` writes into ``docs/``."""


def docs_dir() -> Path:
    """``docs/`` of the posekit checkout, beside ``notebooks/`` (:func:`posekit.paths.notebooks_dir`)."""
    from ..paths import notebooks_dir

    return notebooks_dir().parent / "docs"


def pages(parser, results=None) -> dict:
    """What the generated pages hold now: ``{file name: Markdown}``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The ``posekit`` command line the CLI page documents (:func:`posekit.cli.build_parser`).
    results : str or Path, optional
        The results folder the benchmarks page is rendered from (default ``data_samples/results``).
    """
    from . import bench_page, cli_page, versions_page

    return {"cli.md": cli_page.markdown(parser), "benchmarks.md": bench_page.markdown(results),
            "tested-versions.md": versions_page.markdown(docs_dir() / versions_page.RECORD)}


def build(parser, out=None, results=None) -> list[Path]:
    """Write :data:`GENERATED` into ``out`` (default :func:`docs_dir`) from ``parser`` (the CLI page) and ``results``
    (:func:`pages`); returns the paths written."""
    folder = Path(out) if out is not None else docs_dir()
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name, text in pages(parser, results).items():
        path = folder / name
        path.write_text(text, encoding="utf-8")
        written.append(path)
    return written


def stale(parser, out=None, results=None) -> list[str]:
    """The generated pages in ``out`` (default :func:`docs_dir`) that are missing or differ from what the code
    writes now (:func:`pages` of ``parser`` and ``results``)."""
    folder = Path(out) if out is not None else docs_dir()
    bad = []
    for name, text in pages(parser, results).items():
        path = folder / name
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            bad.append(name)
    return bad


def _build(args) -> int:
    if args.check:
        bad = stale(args.cli_parser, args.out)
        for name in bad:
            print(f"posekit docs: {name} differs from what the code writes now; run `posekit docs build`",
                  file=sys.stderr)
        if not bad:
            print(f"posekit docs: {', '.join(GENERATED)} are up to date")
        return 1 if bad else 0
    for path in build(args.cli_parser, args.out):
        print(f"wrote {path}")
    return 0


def add_commands(sub, parser) -> None:
    """``posekit docs build [--out DIR] [--check]`` on the CLI's subcommand parsers ``sub`` of ``parser``, the whole
    command line, which the command documents (it is complete by the time a command runs)."""
    docs = sub.add_parser("docs", help="write the generated documentation pages (docs/cli.md, docs/benchmarks.md, "
                          "docs/tested-versions.md)")
    dsub = docs.add_subparsers(dest="cmd", required=True)
    p = dsub.add_parser("build", help="write docs/cli.md from the argument parser, docs/benchmarks.md from the "
                        "results files under data_samples/results and docs/tested-versions.md from make test-latest's "
                        "record")
    p.add_argument("--out", default=None, help="folder to write into (default: docs/ of the checkout)")
    p.add_argument("--check", action="store_true",
                   help="write nothing; exit 1 naming every page that differs from what the code writes now")
    p.set_defaults(fn=_build, cli_parser=parser)
