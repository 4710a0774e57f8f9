"""``docs/cli.md``: the command-line reference, written from the argument parser (:func:`posekit.cli.build_parser`,
which the CLI hands in: this module never imports the CLI it documents).

Every subcommand, positional argument and option appears with its help text, in the parser's order, so the page
cannot drift from what ``posekit ... --help`` says. The usage lines are composed here rather than taken from
argparse's formatter, whose wrapping follows the terminal's width and whose layout changes between Python
releases: the page is the same wherever it is built. The figures of the help texts are the parser's settings
(defaults, tolerances, conversions), never measurements, and each carries the marker that says so
(:data:`SETTING`, :mod:`posekit.docs.prose`).
"""

from __future__ import annotations

import argparse

__all__ = ["markdown", "commands", "SETTING"]

SETTING = "<!-- setting: posekit's argument parser -->"
"""The source marker after every figure of the page: what the parser's help says is a setting of the code."""

INTRO = """\
# The `posekit` command line

*Written by `posekit docs build` from the argument parser (`posekit/cli.py` and every registered benchmark and
trainer); do not edit by hand. `tests/test_docs.py` fails when this page differs from what the parser says.*

Run it as `posekit ...` inside the environment `make lab` or `make test` set up (`.venv/bin/posekit`), or as
`python -m posekit ...`. Distributed training runs the same command under `torchrun`:
`torchrun --standalone --nproc-per-node 2 -m posekit train NAME ...` ([training at scale](training.md)).
Malformed input files give one line, `file:line: what was expected`, and exit status 2; warnings print as
`posekit: warning: ...`. Every command takes `--help`.
"""


def commands(parser: argparse.ArgumentParser, path=("posekit",), help_text: str = "") -> list:
    """Every command of ``parser``, depth first in the parser's order: ``(words, parser, help)``, where ``words``
    is the command line up to the command (``("posekit", "bench", "ik")``) and ``help`` the one line its parent
    gives it."""
    out = [(tuple(path), parser, help_text)]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help or "" for a in action._choices_actions}
            for name, sub in action.choices.items():
                out += commands(sub, (*path, name), helps.get(name, ""))
    return out


def _metavar(a: argparse.Action) -> str:
    if a.metavar is not None:
        return a.metavar if isinstance(a.metavar, str) else " ".join(a.metavar)
    if a.choices is not None and not isinstance(a, argparse._SubParsersAction):
        return "{" + ",".join(map(str, a.choices)) + "}"
    return a.dest.upper() if a.option_strings else a.dest


def _usage_part(a: argparse.Action) -> str:
    if isinstance(a, argparse._SubParsersAction):
        return "{" + ",".join(a.choices) + "} ..."
    if not a.option_strings:
        m = _metavar(a)
        return {"?": f"[{m}]", "*": f"[{m} ...]", "+": f"{m} [{m} ...]"}.get(a.nargs, m)
    flag = a.option_strings[-1]
    text = flag if a.nargs == 0 else f"{flag} {_metavar(a)}"
    return text if a.required else f"[{text}]"


def _shown(a: argparse.Action) -> bool:
    return not isinstance(a, argparse._HelpAction) and a.help is not argparse.SUPPRESS


def _help(a: argparse.Action, prog: str) -> str:
    text = a.help or ""
    params = {**vars(a), "prog": prog}
    if params.get("choices") is not None:
        params["choices"] = ", ".join(map(str, params["choices"]))
    try:
        text = text % params
    except (KeyError, TypeError, ValueError):
        pass
    if a.option_strings and a.nargs != 0 and a.default not in (None, False, argparse.SUPPRESS) \
            and "default" not in text:
        text += f" (default: {a.default})"
    return " ".join(text.split())


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def _anchor(words) -> str:
    """GitHub's heading anchor for ``## `posekit bench ik```."""
    return "-".join(w.lower() for w in words if w)


def markdown(parser: argparse.ArgumentParser) -> str:
    """The page: an introduction, a contents list, then one section per command with its usage line and a table
    of its arguments.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The whole ``posekit`` command line (:func:`posekit.cli.build_parser`).
    """
    cmds = commands(parser)
    toc, body = [], []
    for words, p, help_text in cmds[1:]:
        line = " ".join(words)
        depth = len(words) - 2
        toc.append(f"{'  ' * depth}- [`{line}`](#{_anchor(words)}){' — ' + _cell(help_text) if help_text else ''}")
        usage = " ".join([line] + [_usage_part(a) for a in p._actions if _shown(a)])
        body += ["", f"## `{line}`", ""]
        if help_text:
            body += [help_text[0].upper() + help_text[1:].rstrip(".") + ".", ""]
        if p.description and p.description != help_text:
            body += [" ".join(p.description.split()), ""]
        body += ["```", usage, "```"]
        rows = [a for a in p._actions if _shown(a) and not isinstance(a, argparse._SubParsersAction)]
        if rows:
            body += ["", "| argument | what it does |", "|:--|:--|"]
            for a in rows:
                name = ", ".join(a.option_strings) if a.option_strings else _metavar(a)
                if a.option_strings and a.nargs != 0:
                    name += f" {_metavar(a)}"
                body.append(f"| `{_cell(name)}` | {_cell(_help(a, p.prog))} |")
    from .prose import mark_figures

    return INTRO + "\n## Commands\n\n" + mark_figures("\n".join(toc) + "\n" + "\n".join(body), SETTING) + "\n"
