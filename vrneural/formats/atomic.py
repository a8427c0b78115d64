"""Outputs that never lose data: refuse to overwrite without ``force``, write atomically."""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Iterator
from pathlib import Path

from vrneural.errors import VrnError


def check_output(path: str | os.PathLike, force: bool) -> Path:
    """Validate an output path before any work starts.

    Raises :class:`VrnError` when ``path`` exists and ``force`` is false, or when its parent
    directory cannot be created. Returns the path as :class:`Path`.
    """
    p = Path(path)
    if p.exists() and not force:
        raise VrnError(f"{p}: output exists; pass --force to overwrite")
    if p.exists() and p.is_dir() and p.suffix:
        raise VrnError(f"{p}: output path is a directory")
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise VrnError(f"{p.parent}: cannot create output directory ({e.strerror})") from None
    return p


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary sibling path; on success it is renamed over ``path`` (atomic on POSIX).

    On any exception the temporary file is removed and ``path`` is left untouched.
    """
    p = Path(path)
    tmp = p.with_name(f".{p.name}.tmp-{os.getpid()}")
    try:
        yield tmp
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        os.replace(tmp, p)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_json(path: str | os.PathLike, obj: object) -> Path:
    """Write ``obj`` as indented JSON, atomically."""
    p = Path(path)
    with atomic_path(p) as tmp:
        tmp.write_text(json.dumps(obj, indent=2, sort_keys=False, default=_json_default) + "\n")
    return p


def _json_default(o: object) -> object:
    import numpy as np

    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")
