"""Stage configs are dataclasses whose fields carry a one-line ``help`` (it becomes `--help`).

The CLI only parses arguments into a config (:func:`add_config_args`, :func:`config_from_args`)
and calls the stage; the resolved config is written beside every output
(:func:`write_config`), so any result can be reproduced.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import re
import types
import typing
from pathlib import Path

from vrneural.outputs import write_json


def opt(default, help: str, **kw):
    """A config field with a default and a one-line help text."""
    if isinstance(default, (list, dict, set)):
        return dataclasses.field(
            default_factory=lambda: type(default)(default), metadata={"help": help, **kw}
        )
    return dataclasses.field(default=default, metadata={"help": help, **kw})


def add_config_args(
    parser: argparse.ArgumentParser, cls, skip: tuple[str, ...] = (), prefix: str = ""
) -> None:
    """Add one ``--field-name`` option per dataclass field of ``cls``.

    A bool that is off by default becomes a switch (``--force``); one that is on by default
    also gets ``--no-<name>`` (``--no-progress``).
    """
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        if f.name in skip or f.metadata.get("cli") is False:
            continue
        flag = "--" + prefix + f.name.replace("_", "-")
        default = f.default if f.default is not dataclasses.MISSING else f.default_factory()  # type: ignore[misc]
        tp = hints[f.name]
        help_ = f.metadata.get("help", "")
        if tp is bool and not default:  # an off switch: --force, not --force/--no-force
            parser.add_argument(flag, dest=f.name, action="store_true", help=help_)
            continue
        if not re.search(r"default\s*[:)]", help_):  # a help that explains its default: once
            shown = "none" if default in ("", None) else default
            help_ += f" (default: {shown})"
        if tp is bool:  # on by default: --no-<name> turns it off
            parser.add_argument(
                flag,
                dest=f.name,
                action=argparse.BooleanOptionalAction,
                default=default,
                help=help_,
            )
            continue
        if typing.get_origin(tp) in (typing.Union, types.UnionType):  # X | None -> X
            tp = next(a for a in typing.get_args(tp) if a is not type(None))
        kw = {"type": f.metadata.get("type") or (tp if tp in (int, float, str) else str)}
        if "choices" in f.metadata:
            kw["choices"] = f.metadata["choices"]
        parser.add_argument(flag, dest=f.name, default=default, help=help_, **kw)


def config_from_args(cls, args: argparse.Namespace, **overrides):
    """Build ``cls`` from parsed args (fields absent from ``args`` keep their defaults).

    The fields given on the command line (``args._explicit``, set by the CLI) and the
    ``overrides`` are recorded as explicit (:func:`is_explicit`).
    """
    kw = {f.name: getattr(args, f.name) for f in dataclasses.fields(cls) if hasattr(args, f.name)}
    kw.update(overrides)
    cfg = cls(**kw)
    given = getattr(args, "_explicit", None)
    if given is not None:
        names = {f.name for f in dataclasses.fields(cls)}
        mark_explicit(cfg, *(set(given) & names), *overrides)
    return cfg


def mark_explicit(cfg, *names: str):
    """Record ``names`` as fields the user chose (not defaults); returns ``cfg``."""
    cfg.__dict__["_explicit"] = frozenset(cfg.__dict__.get("_explicit", ())) | set(names)
    return cfg


def is_explicit(cfg, name: str) -> bool:
    """Whether the user chose ``cfg.<name>``: given on the command line (or marked with
    :func:`mark_explicit`). A config built in code without marks counts a field as chosen
    when it differs from the default."""
    given = cfg.__dict__.get("_explicit")
    if given is None:
        return getattr(cfg, name) != getattr(type(cfg)(), name)
    return name in given


def name_flag(cfg, name: str, flag: str):
    """Record that the user sets ``cfg.<name>`` with the option ``flag`` (``bench quality``'s
    ``--teacher-epochs`` for its teachers' epochs), for messages; returns ``cfg``."""
    cfg.__dict__["_flags"] = dict(cfg.__dict__.get("_flags", {}), **{name: flag})
    return cfg


def flag(cfg, name: str) -> str:
    """The option that sets ``cfg.<name>``: ``--<name>`` unless :func:`name_flag` said else."""
    return cfg.__dict__.get("_flags", {}).get(name, "--" + name.replace("_", "-"))


def keep_flag_names(old, new):
    """``new`` with the flag names :func:`name_flag` recorded on ``old``; returns ``new``."""
    if "_flags" in old.__dict__:
        new.__dict__["_flags"] = dict(old.__dict__["_flags"])
    return new


def replace_config(cfg, **changes):
    """``dataclasses.replace`` that keeps the explicit-field and flag-name records."""
    new = dataclasses.replace(cfg, **changes)
    for k in ("_explicit", "_flags"):
        if k in cfg.__dict__:
            new.__dict__[k] = cfg.__dict__[k]
    return new


def config_dict(cfg) -> dict:
    """A JSON-ready dict of a config, with its type name."""
    d = dataclasses.asdict(cfg)
    return {"config": type(cfg).__name__, **json.loads(json.dumps(d, default=str))}


def config_path(output: str | Path) -> Path:
    """Where :func:`write_config` puts the config of ``output``: ``<output>.config.json``
    beside an output file (``config.json`` inside an output directory)."""
    out = Path(output)
    return out / "config.json" if out.is_dir() else out.with_name(out.name + ".config.json")


def write_config(output: str | Path, cfg, extra: dict | None = None) -> Path:
    """Write ``<output>.config.json`` beside an output file (or ``config.json`` in a dir)."""
    return write_json(config_path(output), {**config_dict(cfg), **(extra or {})})


def quick_defaults(cfg, **quick):
    """``cfg`` with the ``--quick`` sizes in ``quick``, for the fields the user did not set:
    a flag given explicitly wins over ``--quick`` (and is validated as usual)."""
    keep = {k: v for k, v in quick.items() if not is_explicit(cfg, k)}
    return replace_config(cfg, **keep)
