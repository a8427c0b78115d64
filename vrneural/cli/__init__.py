"""The `vrneural` command. Each subcommand is a module here with ``register(subparsers)``: at
its top it imports the config dataclasses its parser is built from (light modules: no numpy),
and its handler imports the stage when the command runs, so start-up and `--help` load no stage
(tests/test_cli_startup.py).

User errors (:class:`~vrneural.errors.VrnError`) print one line and exit with code 2.
"""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys

from vrneural import __version__
from vrneural.errors import ArgumentParser, VrnError

#: Subcommand modules, in `--help` order. Only commands that work are listed.
COMMANDS = ["info", "btf", "teach", "distill", "export", "eval", "run", "view", "bench", "atlas"]


def build_parser() -> argparse.ArgumentParser:
    p = ArgumentParser(
        prog="vrneural",
        description="Neural materials at VR frame rates: BTF -> distilled student -> WGSL -> "
        "texture-space shading with reuse.",
    )
    p.add_argument("--version", action="version", version=f"vrneural {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"vrneural.cli.{name}").register(sub)
    return p


#: argparse ``dest`` of each command's own subcommand (``vrneural bench quality``, ...)
SUBCOMMAND_DEST = ("benchmark", "btf_command")


def command_name(args: argparse.Namespace) -> str:
    """The command as typed, for message prefixes: ``vrneural bench quality``."""
    words = ["vrneural", args.command]
    words += [getattr(args, d) for d in SUBCOMMAND_DEST if getattr(args, d, None)]
    return " ".join(words)


def main(argv: list[str] | None = None) -> int:
    """The command line (``argv``: default ``sys.argv[1:]``, the process's own; a list given
    here is an in-process call, as the tests make, and gets its signal handlers back)."""
    from vrneural import interrupt

    in_process = argv is not None
    argv = sys.argv[1:] if argv is None else list(argv)
    before_term = interrupt.terminate_as_interrupt()  # before the imports, as Ctrl-C is
    code = 130
    try:
        try:  # the subcommand modules are imported here: Ctrl-C at start-up, no traceback
            parser = build_parser()
        except KeyboardInterrupt:
            print("vrneural: interrupted", file=sys.stderr)
            return code
        code = _run(parser, argv)
        return code
    finally:
        if in_process:
            interrupt.put_back({} if before_term is None else {signal.SIGTERM: before_term})
        else:  # the interpreter shuts down (under a second): the command's outcome stands.
            # SIGTERM is ignored (Python puts back the default for its own handlers while it
            # shuts down, so a handler would not last); Ctrl-C exits at once with the code
            signal.signal(signal.SIGTERM, signal.SIG_IGN)
            signal.signal(signal.SIGINT, lambda *_: os._exit(code))


def _run(parser: argparse.ArgumentParser, argv: list[str]) -> int:
    """Parse ``argv`` and run its command; user errors, Ctrl-C and SIGTERM become exit codes
    (each command's :class:`vrneural.outputs.OutputDir` seals its output however it ends)."""
    args, extra = parser.parse_known_args(argv)
    if extra:  # named by the subcommand's parser: its usage line, not the top level's
        args.command_parser.error(f"unrecognized arguments: {' '.join(extra)}")
    try:
        code = int(args.func(args) or 0)
        sys.stdout.flush()  # a closed pipe (`| head`) shows here, not at interpreter exit
        return code
    except BrokenPipeError:  # the reader went away: stop quietly, as `cat` does
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 141  # 128 + SIGPIPE, what a shell reports for a command killed by it
    except VrnError as e:
        print(f"{command_name(args)}: error: {e}", file=sys.stderr)
        return e.exit_code
    except ModuleNotFoundError as e:  # torch (the train extra): the training stages import it
        if e.name != "torch":
            raise
        print(
            f"{command_name(args)}: error: needs PyTorch, which is not installed: "
            "pip install 'vrneural[train]' (bash scripts/setup.sh installs it)",
            file=sys.stderr,
        )
        return 2
    except KeyboardInterrupt as e:  # one line, with what was kept (interrupt.interrupt_saying)
        said = f" {e}" if e.args and str(e) else ""
        print(f"{command_name(args)}: interrupted{said}", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
