"""The `vrneural` command. Each subcommand is a module here with ``register(subparsers)``;
modules import heavy libraries (torch, wgpu) only inside their handlers, so `--help` is fast.

User errors (:class:`~vrneural.errors.VrnError`) print one line and exit with code 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from vrneural import __version__
from vrneural.errors import VrnError

#: Subcommand modules, in `--help` order. Only commands that work are listed.
COMMANDS = ["info", "btf", "teach", "distill", "export", "run", "bench", "atlas"]


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="vrneural",
        description="Neural materials at VR frame rates: BTF -> distilled student -> WGSL -> "
        "texture-space shading with reuse.",
    )
    p.add_argument("--version", action="version", version=f"vrneural {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"vrneural.cli.{name}").register(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except VrnError as e:
        print(f"vrneural {args.command}: error: {e}", file=sys.stderr)
        return e.exit_code
    except KeyboardInterrupt:
        print(f"vrneural {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
