"""User-facing errors.

A :class:`VrnError` is a problem with the user's input (a file, a field, a value). The CLI prints
its message on one line and exits with code 2; it never shows a traceback for one.
"""

from __future__ import annotations

import argparse
import math
import numbers
from pathlib import Path


class VrnError(Exception):
    """An input problem reported to the user as one line, exit code 2."""

    exit_code = 2


class ArgumentParser(argparse.ArgumentParser):
    """argparse with a one-line error (the problem and where the help is) instead of the
    command's whole usage, exit code 2; subcommand parsers inherit it.

    It keeps what it was given, for the CLI reference (:mod:`vrneural.cli.reference`) and the
    error of an unknown option: ``arguments``, the actions of its ``add_argument`` calls (not
    ``--help``), and ``subcommands``, ``{name: (parser, help)}`` of its ``add_subparsers``
    group; ``args.command_parser`` is the innermost (sub)command's parser.
    """

    def __init__(self, *args, **kw):
        super().__init__(*args, **kw)
        self.arguments: list[argparse.Action] = []
        self.subcommands: dict[str, tuple[ArgumentParser, str]] = {}
        self.set_defaults(command_parser=self)

    def add_argument(self, *args, **kw) -> argparse.Action:
        action = super().add_argument(*args, **kw)
        if hasattr(self, "arguments"):  # after __init__, which adds --help
            self.arguments.append(action)
        return action

    def add_subparsers(self, **kw):
        group = super().add_subparsers(**kw)
        add = group.add_parser

        def add_parser(name: str, **kw) -> ArgumentParser:
            p = add(name, **kw)
            self.subcommands[name] = (p, kw.get("help") or "")
            return p

        group.add_parser = add_parser
        self.subcommand_group = group  # where a test adds a subcommand
        return group

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def input_file(path, what: str, missing: str = "no such file") -> Path:
    """``path`` as a :class:`Path`; a one-line error where nothing is there (``missing``) or
    a directory is (``what``: the file expected, e.g. "a mesh file")."""
    p = Path(path)
    if not p.exists():
        raise VrnError(f"{p}: {missing}")
    if p.is_dir():
        raise VrnError(f"{p}: is a directory, expected {what}")
    return p


def count(n: int, noun: str, plural: str | None = None) -> str:
    """``"1 light"``, ``"3 lights"``: a number and its noun, for messages."""
    return f"{n} {noun if n == 1 else plural or noun + 's'}"


def check_range(name: str, value: float, lo=None, hi=None, lo_open=False, open_inf=False) -> None:
    """Raise :class:`VrnError` unless ``lo <= value <= hi`` (``lo < value`` with ``lo_open``;
    the bounds optional numbers) and finite. ``open_inf``: no ``hi`` written ``inf)``, not
    ``inf]``."""
    bad = isinstance(value, float) and not math.isfinite(value)
    bad = bad or (lo is not None and (value <= lo if lo_open else value < lo))
    if bad or (hi is not None and value > hi):
        lo_s = ("(" if lo_open else "[") + ("-inf" if lo is None else number_text(lo))
        hi_s = ("inf" + (")" if open_inf else "]")) if hi is None else number_text(hi) + "]"
        raise VrnError(f"{name} = {value!r} is out of range; allowed {lo_s}, {hi_s}")


def check_int(name: str, value, lo: int | None = None, hi: int | None = None) -> None:
    """Raise :class:`VrnError` unless ``value`` is a whole number (an int, not a bool, a float
    or a string) with ``lo <= value <= hi`` (bounds optional)."""
    if not isinstance(value, numbers.Integral) or isinstance(value, bool):
        raise VrnError(f"{name} = {value!r} must be a whole number")
    check_range(name, value, lo, hi)


#: Every seed option (teach, distill, btf synth, bench quality, split seeds) takes [0, SEED_MAX]:
#: numpy and torch take 32-bit seeds without surprises (torch wraps larger ones, and refuses
#: negative ones or ones beyond 64 bits with a traceback).
SEED_MAX = 2**32 - 1


def check_seed(name: str, value: int) -> None:
    """Raise :class:`VrnError` unless ``value`` is a seed in ``[0, SEED_MAX]``."""
    check_range(name, value, 0, SEED_MAX)


def number_text(x: float) -> str:
    """A bound as people write it: whole numbers in full (16777216, not 1.67772e+07)."""
    if float(x).is_integer() and abs(x) < 1e15:
        return str(int(x))
    return f"{x:g}"


def check_choice(name: str, value: object, allowed: tuple | list | set, ordered=False) -> None:
    """Raise :class:`VrnError` unless ``value`` is one of ``allowed`` (listed sorted, or in the
    given order with ``ordered``)."""
    if value not in allowed:
        opts = ", ".join(str(a) for a in (allowed if ordered else sorted(allowed, key=str)))
        raise VrnError(f"{name} = {value!r} is not allowed; choose one of: {opts}")
