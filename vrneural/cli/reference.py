"""The CLI reference page of the documentation site, generated from the parsers themselves.

Every command and subcommand of :func:`vrneural.cli.build_parser` gets a section (its help,
description and usage) and a table of its arguments and options: each option's flags, its
help as ``--help`` prints it and its default. The stage options come from the config
dataclasses (:func:`vrneural.config.add_config_args`), so a new field shows up here without a
hand-written line. The site's build hook (``scripts/docs_hooks.py``) calls :func:`markdown`;
``tests/test_cli_reference.py`` checks that every option ``--help`` shows is on the built page.

Not a command (absent from :data:`vrneural.cli.COMMANDS`): ``python -m vrneural.cli.reference``
prints the page.
"""

from __future__ import annotations

import argparse
import html
from collections.abc import Iterator

#: the page's path inside the site (``docs/`` relative)
PAGE = "reference/cli.md"


def walk(
    parser: argparse.ArgumentParser, words: tuple[str, ...] = ("vrneural",)
) -> Iterator[tuple[tuple[str, ...], argparse.ArgumentParser, str]]:
    """Every (sub)command parser, depth first in ``--help`` order: ``(words, parser, help)``
    with ``words`` the command as typed (``("vrneural", "bench", "quality")``)."""
    yield words, parser, ""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help or "" for a in action._choices_actions}
            for name, sub in action.choices.items():
                for w, p, h in walk(sub, (*words, name)):
                    yield w, p, h or helps.get(name, "")


def arguments(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    """The parser's own arguments and options (not ``--help``, not a subcommand group)."""
    return [
        a
        for a in parser._actions
        if not isinstance(a, (argparse._HelpAction, argparse._SubParsersAction))
    ]


def _cell(text: str) -> str:
    """``text`` safe in a Markdown table cell: HTML escaped (``<output>``), pipes and
    emphasis characters escaped, one line."""
    text = html.escape(" ".join(str(text).split()), quote=False)
    for ch in "|*_[]`":
        text = text.replace(ch, "\\" + ch)
    return text


def _default(action: argparse.Action) -> str:
    if isinstance(action, argparse._VersionAction):
        return ""
    if isinstance(action, (argparse._StoreTrueAction, argparse._StoreFalseAction)):
        return "off" if action.default is False else "on"
    if action.required:
        return "required"
    if action.default in (None, "", argparse.SUPPRESS):
        return "none"
    if isinstance(action.default, bool):
        return "on" if action.default else "off"
    return f"`{action.default}`"


def _row(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    fmt = parser._get_formatter()
    flags = fmt._format_action_invocation(action)
    if not action.option_strings and action.nargs == "?":
        flags += " (optional)"
    help_ = fmt._expand_help(action) if action.help else ""
    return f"| `{flags.replace('|', '/')}` | {_cell(help_)} | {_default(action)} |"


def section(words: tuple[str, ...], parser: argparse.ArgumentParser, help_: str) -> str:
    """One command's section: heading, summary, usage, table of arguments."""
    level = "#" * min(max(len(words), 2), 4)  # vrneural and its commands ##, subcommands ###
    out = [f"{level} {' '.join(words)}", ""]
    if help_:
        out += [f"*{_cell(help_)}*", ""]
    if parser.description:
        out += [_cell(parser.description), ""]
    usage = " ".join(parser.format_usage().split())
    out += ["```text", usage, "```", ""]
    rows = [_row(parser, a) for a in arguments(parser)]
    if rows:
        out += ["| argument / option | help | default |", "|---|---|---|", *rows, ""]
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    for group in subs:
        names = ", ".join(f"[{n}](#{'-'.join((*words, n))})" for n in group.choices)
        out += [f"Subcommands: {names}.", ""]
    return "\n".join(out)


def markdown(parser: argparse.ArgumentParser | None = None) -> str:
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
