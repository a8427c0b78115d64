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

from vrneural.errors import VrnError, check_choice, check_range
from vrneural.outputs import write_json


def opt(default, help: str, **kw):
    """A config field with a default and a one-line help text."""
    if isinstance(default, (list, dict, set)):
        return dataclasses.field(
            default_factory=lambda: type(default)(default), metadata={"help": help, **kw}
        )
    return dataclasses.field(default=default, metadata={"help": help, **kw})


class Config:
    """Base of the configs with list fields (``items=`` on :func:`opt`/:func:`unset`, a parser
    below such as :func:`ints`): they hold tuples, parsed and checked once, when the config is
    built, from the comma-separated text the command line gives or from a sequence (Python)."""

    def __post_init__(self):
        for f in dataclasses.fields(self):
            parse, v = f.metadata.get("items"), getattr(self, f.name)
            if parse and v is not None:
                object.__setattr__(self, f.name, parse("--" + f.name.replace("_", "-"), v))


class QuickConfig(Config):
    """Base of the bench configs with a ``quick`` field: their preset ``QUICK`` (an instance,
    set beside the class: the CI-sized run) applies under the flags given."""

    QUICK = None

    #: the command's own defaults for fields of parts it shares (flat keys), under ``QUICK``
    DEFAULTS: typing.ClassVar[dict] = {}

    def resolved(self, *layers):
        """The fields not given: ``--quick``'s (``QUICK``), then ``layers``', then the command's
        own ``DEFAULTS``, or the fields' defaults."""
        return resolved(self, *([self.QUICK] if self.quick else []), *layers, self.DEFAULTS)


def _items(value) -> tuple[list[str], str]:
    """The items of a list field's value (comma-separated text or a sequence), and its text."""
    if isinstance(value, str):
        return value.split(","), value
    items = [str(v) for v in value]
    return items, ",".join(items)


def ints(lo: int | None = None, hi: int | None = None, even: bool = False):
    """Items parser: comma-separated integers in ``[lo, hi]`` (None: unchecked), each once."""
    return lambda flag, value: int_items(flag, value, lo, hi, even)


def int_items(flag: str, value, lo=None, hi=None, even: bool = False) -> tuple[int, ...]:
    """The integers of a list field (see :func:`ints`; one-line VrnError if not)."""
    items, text = _items(value)
    if any(not t.strip() for t in items) and text.strip():
        raise VrnError(f"{flag} = {text!r} has an empty item; write e.g. 1,2,4")
    try:
        vals = tuple(int(t) for t in items if t.strip())
    except ValueError:
        raise VrnError(f"{flag} = {text!r} must be comma-separated integers") from None
    if not vals:
        raise VrnError(f"{flag} is empty")
    dup = sorted({v for v in vals if vals.count(v) > 1})
    if dup:
        raise VrnError(f"{flag} = {text!r} lists {dup[0]} twice; each value once")
    for v in vals:
        if lo is not None and not lo <= v <= hi:
            raise VrnError(f"{flag} = {text!r}: {v} is out of range; allowed [{lo}, {hi}]")
        if even and v % 2:
            raise VrnError(f"{flag}: {v} must be even (2x2 blocks)")
    return vals


def floats(lo: float, hi: float):
    """Items parser: comma-separated numbers in ``[lo, hi]``; empty text: none."""

    def parse(flag: str, value) -> tuple[float, ...]:
        items, text = _items(value)
        out = []
        for item in items if text.strip() else ():
            try:
                v = float(item)
            except ValueError:
                raise VrnError(f"{flag} = {text!r}: {item.strip()!r} is not a number") from None
            check_range(flag, v, lo, hi)
            out.append(v)
        return tuple(out)

    return parse


def choices(allowed, matches=None):
    """Items parser: comma-separated values, each one of ``allowed`` (or, with ``matches``, a
    value it accepts: a pattern such as ``student:W``, named in ``allowed``), none twice (a
    value named twice would be measured and reported twice), at least one."""

    def parse(flag: str, value) -> tuple[str, ...]:
        items, text = _items(value)
        vals = tuple(t.strip() for t in items)
        names = ", ".join(map(str, allowed))
        if not any(vals):
            raise VrnError(f"{flag} is empty; choose from {names}")
        if not all(vals):
            raise VrnError(f"{flag} = {text!r} has an empty item; choose from {names}")
        for v in vals:
            if not (matches and matches(v)):
                check_choice(flag, v, allowed)
        twice = sorted({v for v in vals if vals.count(v) > 1})
        if twice:
            raise VrnError(f"{flag} names {', '.join(twice)} more than once")
        return vals

    return parse


def words(flag: str, value) -> tuple[str, ...]:
    """Items parser: the non-empty comma-separated words (paths, names checked later)."""
    return tuple(t.strip() for t in _items(value)[0] if t.strip())


def listed(empty: bool = True):
    """Items parser: comma-separated words, none of them empty; empty text: none (``empty``)."""

    def parse(flag: str, value) -> tuple[str, ...]:
        items, text = _items(value)
        vals = tuple(t.strip() for t in items)
        if empty and not text.strip():
            return ()
        if not all(vals):
            raise VrnError(f"{flag} = {text!r} has an empty item")
        return vals

    return parse


def part(cls):
    """A field holding a sub-config that several commands share (a training budget, the
    scored window of a bench): its fields are options of their own (``--crop``, not
    ``--score-crop``) and flat keys of :func:`config_dict`."""
    return dataclasses.field(default_factory=cls, metadata={"part": True})


def _parts(cfg) -> list:
    return [f for f in dataclasses.fields(cfg) if f.metadata.get("part")]


def add_config_args(
    parser: argparse.ArgumentParser,
    cls,
    skip: tuple[str, ...] = (),
    prefix: str = "",
    helps: dict[str, str] | None = None,
    own: dict | None = None,
) -> None:
    """Add one ``--field-name`` option per dataclass field of ``cls`` (``helps``: a command's
    own help for some of them, as the viewer's defaults; ``own``: defaults of a part's fields
    that the command sets for itself, its class's ``DEFAULTS``, shown by ``--help``).

    A bool that is off by default becomes a switch (``--force``); one that is on by default
    also gets ``--no-<name>`` (``--no-progress``). An :func:`unset` field not given parses to
    None; its help shows the default it resolves to.
    """
    hints = typing.get_type_hints(cls)
    own = {**getattr(cls, "DEFAULTS", {}), **(own or {})}
    for f in dataclasses.fields(cls):
        if f.name in skip or f.metadata.get("cli") is False:
            continue
        if f.metadata.get("part"):
            add_config_args(parser, hints[f.name], skip, prefix, helps, own)
            continue
        flag = "--" + prefix + f.name.replace("_", "-")
        default = f.default if f.default is not dataclasses.MISSING else f.default_factory()  # type: ignore[misc]
        shown = own.get(f.name, f.metadata.get("default", default))
        if isinstance(shown, tuple):  # a list field: as it is typed
            shown = ",".join(map(str, shown))
        tp = hints[f.name]
        if typing.get_origin(tp) in (typing.Union, types.UnionType):  # X | None -> X
            tp = next(a for a in typing.get_args(tp) if a is not type(None))
        help_ = (helps or {}).get(f.name) or f.metadata.get("help", "")
        if tp is bool and not shown:  # an off switch: --force, not --force/--no-force
            parser.add_argument(flag, dest=f.name, action="store_true", default=default, help=help_)
            continue
        if not re.search(r"default\s*[:)]", help_):  # a help that explains its default: once
            help_ += f" (default: {'none' if shown in ('', None) else shown})"
        kw = {"action": argparse.BooleanOptionalAction}  # on by default: --no-<name> too
        if tp is not bool:
            kw = {"type": f.metadata.get("type") or (tp if tp in (int, float, str) else str)}
        if "choices" in f.metadata:
            kw["choices"] = f.metadata["choices"]
        action = parser.add_argument(flag, dest=f.name, default=default, help=help_, **kw)
        action.shown_default = shown  # for the CLI reference: an unset field's parses to None


def config_from_args(cls, args: argparse.Namespace, **overrides):
    """Build ``cls`` from parsed args (fields absent from ``args`` keep their defaults; an
    :func:`unset` field the user did not give stays None for :func:`resolved`)."""
    hints = typing.get_type_hints(cls)
    kw = {f.name: config_from_args(hints[f.name], args) for f in _parts(cls)}
    kw |= {f.name: getattr(args, f.name) for f in dataclasses.fields(cls) if hasattr(args, f.name)}
    return cls(**(kw | overrides))


def unset(default, help: str, **kw):
    """A field whose default depends on context (a preset such as ``--quick``, a resumed
    checkpoint, the viewer): None ("not given") until :func:`resolved` fills it in; ``default``
    is the value it takes where nothing else sets it (and what ``--help`` shows)."""
    return dataclasses.field(default=None, metadata={"help": help, "default": default, **kw})


def given(cfg) -> set[str]:
    """The :func:`unset` fields of ``cfg`` that were given (not None)."""
    return {
        f.name
        for f in dataclasses.fields(cfg)
        if "default" in f.metadata and getattr(cfg, f.name) is not None
    }


def resolved(cfg, *layers):
    """``cfg`` with each :func:`unset` field that is None taken from the first of ``layers``
    (preset instances or dicts: a checkpoint's config) that has it, else its default. Fields
    given win over every layer: a preset applies under the user's flags."""
    changes = {}
    for f in _parts(cfg):  # a preset's part is the layer of the part; a dict holds flat keys
        under = [x if isinstance(x, dict) else getattr(x, f.name) for x in layers]
        changes[f.name] = resolved(getattr(cfg, f.name), *under)
    for f in dataclasses.fields(cfg):
        if "default" not in f.metadata or getattr(cfg, f.name) is not None:
            continue
        for layer in layers:
            v = layer.get(f.name) if isinstance(layer, dict) else getattr(layer, f.name, None)
            if v is not None:
                changes[f.name] = v
                break
        else:
            changes[f.name] = f.metadata["default"]
    return dataclasses.replace(cfg, **changes) if changes else cfg


def config_dict(cfg) -> dict:
    """A JSON-ready dict of a config, with its type name (the fields of its parts flat, as
    their options are)."""
    d = dataclasses.asdict(cfg)
    for f in _parts(cfg):
        d |= d.pop(f.name)
    return {"config": type(cfg).__name__, **json.loads(json.dumps(d, default=str))}


def config_path(output: str | Path) -> Path:
    """Where :func:`write_config` puts the config of ``output``: ``<output>.config.json``
    beside an output file (``config.json`` inside an output directory)."""
    out = Path(output)
    return out / "config.json" if out.is_dir() else out.with_name(out.name + ".config.json")


def write_config(output: str | Path, cfg, extra: dict | None = None) -> Path:
    """Write ``<output>.config.json`` beside an output file (or ``config.json`` in a dir)."""
    return write_json(config_path(output), {**config_dict(cfg), **(extra or {})})
