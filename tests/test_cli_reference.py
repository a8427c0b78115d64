"""The CLI reference page of the built site lists every command and subcommand, and each
option ``--help`` shows, with its help and its default (vrneural/cli/reference.py generates it
from the parsers when the site is built; this checks the built page against ``--help``)."""

from __future__ import annotations

import argparse
import re

import pytest
from docs_helpers import article, built_site, plain

from vrneural.cli import build_parser
from vrneural.cli.reference import PAGE, markdown, walk
from vrneural.errors import ArgumentParser


def _anchor(words: tuple[str, ...]) -> str:
    return "-".join(words)


def sections(html: str) -> dict[str, str]:
    """The page's command sections: heading id -> HTML up to the next command heading."""
    parts = re.split(r'(<h[234] id="vrneural[^"]*")', html)
    out = {}
    for head, body in zip(parts[1::2], parts[2::2], strict=True):
        out[re.search(r'id="([^"]+)"', head).group(1)] = body
    return out


def help_options(parser: argparse.ArgumentParser) -> set[str]:
    """The option strings ``--help`` prints (read from its text, not from the parser)."""
    text = parser.format_help()
    opts = set()
    for line in text.splitlines():
        m = re.match(r"\s{2}(-\S.*?)(?:\s{2,}|$)", line)
        if m:
            opts |= set(re.findall(r"(?<![\w-])--?[A-Za-z][\w-]*", m.group(1)))
    return opts - {"-h", "--help"}


def rows(section_html: str) -> list[list[str]]:
    """The argument table of a section: one list of cell texts per row."""
    out = []
    for tr in re.findall(r"<tr>(.*?)</tr>", section_html, flags=re.S):
        cells = re.findall(r"<td[^>]*>(.*?)</td>", tr, flags=re.S)
        if cells:
            out.append([plain(c) for c in cells])
    return out


def missing(parser: argparse.ArgumentParser, page_html: str) -> list[str]:
    """What the page lacks of ``parser``'s commands and options (empty: complete)."""
    secs = sections(page_html)
    lacks = []
    for words, p, _ in walk(parser):
        name = " ".join(words)
        body = secs.get(_anchor(words))
        if body is None:
            lacks.append(f"{name}: no section")
            continue
        table = rows(body)
        flags = {f for r in table for f in re.findall(r"(?<![\w-])--?[A-Za-z][\w-]*", r[0])}
        lacks += [f"{name} {o}: not in the reference" for o in sorted(help_options(p) - flags)]
        shown = "".join(p.format_help().split())  # what --help prints, wrapping undone
        for a in p.arguments:
            if not a.option_strings:  # a positional: its name heads a row
                if not any(r[0].split()[0] == (a.metavar or a.dest) for r in table):
                    lacks.append(f"{name} {a.dest}: positional not in the reference")
                continue
            row = next((r for r in table if a.option_strings[0] in r[0].split()), None)
            if row is None:
                continue  # counted above
            if "".join(row[1].split()) not in shown or bool(row[1]) != bool(a.help):
                lacks.append(f"{name} {a.option_strings[0]}: help {row[1]!r} not as --help has it")
            default = getattr(a, "shown_default", a.default)  # an unset field's: it parses to None
            if isinstance(default, (int, float, str)) and not isinstance(default, bool):
                if default not in ("", argparse.SUPPRESS) and str(default) not in row[2]:
                    lacks.append(f"{name} {a.option_strings[0]}: default {default!r} missing")
    return lacks


@pytest.fixture(scope="module")
def page_html() -> str:
    return article(built_site() / PAGE.replace(".md", "") / "index.html")


def test_the_reference_lists_every_command_and_option(page_html):
    parser = build_parser()
    assert not missing(parser, page_html)
    commands = [w for w, _, _ in walk(parser)]
    assert len(commands) >= 25  # vrneural, its 10 commands, btf's 5, bench's 12
    assert sum(len(help_options(p)) for _, p, _ in walk(parser)) > 200


def test_a_new_option_is_caught(page_html):
    """The check above fails when a command gains an option that the built page lacks."""
    parser = build_parser()
    run = dict((w, p) for w, p, _ in walk(parser))[("vrneural", "run")]
    run.add_argument("--brand-new-knob", type=int, default=3, help="a knob nobody documented")
    assert missing(parser, page_html) == ["vrneural run --brand-new-knob: not in the reference"]
    # and the generator picks it up, help and default included
    assert "| `--brand-new-knob BRAND_NEW_KNOB` | a knob nobody documented | `3` |" in markdown(
        parser
    )


def test_a_new_subcommand_is_caught(page_html):
    parser = build_parser()
    bench = dict((w, p) for w, p, _ in walk(parser))[("vrneural", "bench")]
    bench.subcommand_group.add_parser("brand-new", help="a bench nobody documented")
    assert missing(parser, page_html) == ["vrneural bench brand-new: no section"]


def test_help_text_is_escaped_for_markdown():
    p = ArgumentParser(prog="vrneural")
    p.add_argument("--out", default="a|b", help="writes <output>.json, *not* __init__ [x]")
    md = markdown(p)
    assert "\\<output\\>" not in md and "&lt;output&gt;.json" in md
    assert "\\*not\\*" in md and "a/b" not in md
