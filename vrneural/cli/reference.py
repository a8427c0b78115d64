"""The CLI reference page of the documentation site, generated from the parsers themselves.

Every command and subcommand of :func:`vrneural.cli.build_parser` gets a section (its help,
description and usage) and a table of its arguments and options: each option's flags, its
help as ``--help`` prints it and its default. The stage options come from the config
dataclasses (:func:`vrneural.config.add_config_args`), so a new field shows up here without a
hand-written line. The parsers are walked through what :class:`vrneural.errors.ArgumentParser`
records (``arguments``, ``subcommands``), not argparse's private attributes. The site's build
hook (``scripts/docs_hooks.py``) calls :func:`markdown`; ``tests/test_cli_reference.py``
checks that every option ``--help`` shows is on the built page.

Not a command (absent from :data:`vrneural.cli.COMMANDS`): ``python -m vrneural.cli.reference``
prints the page.
"""

from __future__ import annotations

import argparse
import html
from collections.abc import Iterator

from vrneural.errors import ArgumentParser

#: the page's path inside the site (``docs/`` relative)
PAGE = "reference/cli.md"


def walk(
    parser: ArgumentParser, words: tuple[str, ...] = ("vrneural",), help_: str = ""
) -> Iterator[tuple[tuple[str, ...], ArgumentParser, str]]:
    """Every (sub)command parser, depth first in ``--help`` order: ``(words, parser, help)``
    with ``words`` the command as typed (``("vrneural", "bench", "quality")``)."""
    yield words, parser, help_
    for name, (sub, h) in parser.subcommands.items():
        yield from walk(sub, (*words, name), h)


def _cell(text: str) -> str:
    """``text`` safe in a Markdown table cell: HTML escaped (``<output>``), pipes and
    emphasis characters escaped, one line."""
    text = html.escape(" ".join(str(text).split()), quote=False)
    for ch in "|*_[]`":
        text = text.replace(ch, "\\" + ch)
    return text


def _default(action: argparse.Action) -> str:
    if hasattr(action, "version"):  # --version
        return ""
    default = getattr(action, "shown_default", action.default)  # an unset field's resolved one
    if action.nargs == 0 and action.const in (True, False):  # store_true / store_false
        return "off" if action.const else "on"
    if action.required:
        return "required"
    if default in (None, "", argparse.SUPPRESS):
        return "none"
    if isinstance(default, bool):
        return "on" if default else "off"
    return f"`{default}`"


def _flags(action: argparse.Action) -> str:
    """The flags as ``--help`` lists them: ``-o OUTPUT, --output OUTPUT``, ``scene``."""
    if action.metavar is not None:
        meta = action.metavar if isinstance(action.metavar, str) else " ".join(action.metavar)
    elif action.choices is not None:
        meta = "{" + ",".join(map(str, action.choices)) + "}"
    else:
        meta = action.dest.upper() if action.option_strings else action.dest
    if not action.option_strings:
        return meta
    if action.nargs == 0:
        return ", ".join(action.option_strings)
    if isinstance(action.nargs, int) and isinstance(action.metavar, (str, type(None))):
        meta = " ".join([meta] * action.nargs)
    return ", ".join(f"{o} {meta}" for o in action.option_strings)


def _row(parser: ArgumentParser, action: argparse.Action) -> str:
    flags = _flags(action)
    if not action.option_strings and action.nargs == "?":
        flags += " (optional)"
    help_ = action.help % {**vars(action), "prog": parser.prog} if action.help else ""
    return f"| `{flags.replace('|', '/')}` | {_cell(help_)} | {_default(action)} |"


def section(words: tuple[str, ...], parser: ArgumentParser, help_: str) -> str:
    """One command's section: heading, summary, usage, table of arguments."""
    level = "#" * min(max(len(words), 2), 4)  # vrneural and its commands ##, subcommands ###
    out = [f"{level} {' '.join(words)}", ""]
    if help_:
        out += [f"*{_cell(help_)}*", ""]
    if parser.description:
        out += [_cell(parser.description), ""]
    usage = " ".join(parser.format_usage().split())
    out += ["```text", usage, "```", ""]
    rows = [_row(parser, a) for a in parser.arguments]
    if rows:
        out += ["| argument / option | help | default |", "|---|---|---|", *rows, ""]
    if parser.subcommands:
        names = ", ".join(f"[{n}](#{'-'.join((*words, n))})" for n in parser.subcommands)
        out += [f"Subcommands: {names}.", ""]
    return "\n".join(out)


def markdown(parser: ArgumentParser | None = None) -> str:
    """The whole reference page (Markdown) for ``parser`` (default: the `vrneural` command)."""
    if parser is None:
        from vrneural.cli import build_parser

        parser = build_parser()
    head = [
        "# CLI reference",
        "",
        "Generated from the command's own parsers when the site is built "
        "(`vrneural/cli/reference.py`), so it always matches `vrneural ... --help`: every "
        "command and subcommand, each argument and option with its help and its default. "
        "The options of the stages come from their config dataclasses, whose resolved values "
        "are written beside every output (`<output>.config.json`).",
        "",
    ]
    return "\n".join(head + [section(w, p, h) for w, p, h in walk(parser)]) + "\n"


if __name__ == "__main__":
    print(markdown(), end="")
