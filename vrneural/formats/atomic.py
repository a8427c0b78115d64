"""Outputs that never lose data: refuse to overwrite without ``force``, write atomically."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
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
    _make_parent(p)
    return p


def _make_parent(p: Path) -> None:
    """Create the directory an output goes into; failure is a one-line :class:`VrnError`."""
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise VrnError(f"{p.parent}: cannot create output directory ({e.strerror})") from None


OUTPUT_MARK = ".vrneural-output"
#: Result files of output directories written before the marker existed, with keys that only
#: vrneural's own files carry (a folder that merely holds *a* results.json is not ours)
_LEGACY_RESULTS = {
    "summary.json": ("adapter", "resolved", "per_frame"),
    "results.json": ("benchmark",),
}


def check_output_dir(
    path: str | os.PathLike, force: bool, remedy: str = "pass --force to overwrite"
) -> Path:
    """Validate an output *directory* before any work starts.

    An existing path needs ``force`` (else the error says ``remedy``), and even then it must
    be a directory that vrneural wrote (it holds :data:`OUTPUT_MARK`, or a result file of an
    older release, recognised by its content) or an empty one: ``--force`` replaces our own
    output, never a folder of the user's files.
    """
    p = Path(path)
    if p.exists() or p.is_symlink():
        if not p.is_dir():
            raise VrnError(f"{p}: output exists and is not a directory; choose another --out")
        if not force:
            raise VrnError(f"{p}: output exists; {remedy}")
        if not is_output_dir(p):
            raise VrnError(
                f"{p}: not a vrneural output directory (no {OUTPUT_MARK}); vrneural only replaces "
                "or reuses its own output, so choose another --out"
            )
    _make_parent(p)
    return p


def is_output_dir(p: Path) -> bool:
    """Whether ``p`` is empty or was written by vrneural (see :func:`check_output_dir`)."""
    if (p / OUTPUT_MARK).exists() or any(_ours(p / f, k) for f, k in _LEGACY_RESULTS.items()):
        return True
    return not any(p.iterdir())


def _ours(f: Path, keys: tuple[str, ...]) -> bool:
    """Whether ``f`` is a JSON result file of an older vrneural (an object with ``keys``)."""
    if not f.is_file():
        return False
    try:
        doc = json.loads(f.read_text())
    except (OSError, ValueError):  # UnicodeDecodeError is a ValueError
        return False
    return isinstance(doc, dict) and all(k in doc for k in keys)


def mark_output_dir(path: str | os.PathLike) -> Path:
    """Create ``path`` (and parents) and mark it as vrneural's output, keeping its contents."""
    p = Path(path)
    try:
        p.mkdir(parents=True, exist_ok=True)
        (p / OUTPUT_MARK).write_text("written by vrneural; --force may replace this directory\n")
    except OSError as e:
        raise VrnError(f"{p}: cannot create output directory ({e.strerror})") from None
    return p


def make_output_dir(path: str | os.PathLike, keep: tuple[str, ...] = ()) -> Path:
    """Empty a directory passed by :func:`check_output_dir` (except the names in ``keep``),
    create it and mark it as vrneural's output. Call it once the inputs are validated, so a
    run that fails early leaves the old output as it was."""
    p = Path(path)
    if p.is_dir():
        if not is_output_dir(p):  # the folder changed since it was checked
            raise VrnError(f"{p}: not a vrneural output directory; choose another --out")
        for child in p.iterdir():
            if child.name in keep:
                continue
            if child.is_dir() and not child.is_symlink():
                shutil.rmtree(child)
            else:
                child.unlink()
    return mark_output_dir(p)


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
