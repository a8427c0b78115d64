"""Writing an output: the folders made for it (none before a file is written into one, by
:func:`make_parent`), the checks that it can be written, and the atomic write itself."""

from __future__ import annotations

import contextlib
import itertools
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from vrneural.errors import VrnError


def partial_path(path) -> Path:
    """Where an interrupted write of ``path`` keeps its data: ``<path>.partial`` beside it."""
    path = Path(path)
    return path.with_name(path.name + ".partial")


def check_free_space(path: str | os.PathLike, nbytes: int, reclaimed: int = 0) -> None:
    """Refuse to write ``nbytes`` to ``path`` with less free space (``reclaimed``: bytes of a
    file the write replaces)."""
    p = Path(path)
    try:
        free = shutil.disk_usage(_existing(p.parent)).free + reclaimed
    except OSError:
        return  # nothing to measure: the write itself reports the problem
    if nbytes > free:
        raise VrnError(
            f"{p}: needs {_size(nbytes)} but only {_size(free)} is free on {p.parent}; "
            "use smaller settings or another disk"
        )


def _size(n: int) -> str:
    for unit, k in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= k:
            return f"{n / k:.1f} {unit}"
    return f"{n} B"


def _existing(d: Path) -> Path:
    """``d`` or its nearest ancestor that exists (as anything: a file in the way counts)."""
    while not (d.exists() or d.is_symlink()) and d != d.parent:
        d = d.parent
    return d


def check_writable(d: Path) -> None:
    """A one-line error unless directory ``d`` takes new files or can be made (creates none)."""
    q = _existing(d)
    if not q.is_dir():
        raise VrnError(f"{d}: cannot create output directory ({q} is a file, not a directory)")
    try:  # a real file, not os.access: root passes access() checks on read-only mounts too
        with tempfile.TemporaryFile(dir=q, prefix=".vrneural-probe-"):
            pass
    except OSError as e:
        what = "cannot write here" if q == d else "cannot create output directory"
        raise VrnError(f"{d}: {what} ({e.strerror or e})") from None


def why(p: Path, e: OSError) -> str:
    """An OSError's reason, or the file in ``p``'s way (``File exists`` would mislead)."""
    for q in (p, *p.parents):
        if q.exists() and not q.is_dir():
            return f"{q} is a file, not a directory"
    return e.strerror or str(e)


def make_dirs(d: Path) -> list[Path]:
    """Create directory ``d`` and its parents; returns those created, deepest first."""
    top = _existing(d)
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise VrnError(f"{d}: cannot create output directory ({why(d, e)})") from None
    return list(itertools.takewhile(lambda q: q != top, (d, *d.parents)))


def make_parent(path: str | os.PathLike) -> Path:
    """Create the directory of output file ``path`` (just before writing it)."""
    make_dirs(Path(path).parent)
    return Path(path)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary sibling path, renamed over ``path`` when the block succeeds (atomic on
    POSIX); removed on any exception, leaving ``path`` untouched."""
    p = make_parent(path)
    tmp = p.with_name(f".{p.name}.tmp-{os.getpid()}")
    try:
        yield tmp
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        os.replace(tmp, p)
    except OSError as e:  # a full disk, a directory made read-only meanwhile: one line
        raise VrnError(f"{p}: cannot write ({e.strerror or e})") from None
    finally:
        tmp.unlink(missing_ok=True)
