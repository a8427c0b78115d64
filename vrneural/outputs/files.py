"""Output files: checked before any work (creating nothing: a folder is made when a file is
written into it, by :func:`make_parent`), then written atomically."""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from vrneural.errors import VrnError


def check_suffix(
    path: str, suffix: str, what: str, example: str, ignore_case: bool = False
) -> None:
    """A one-line error unless ``-o path`` ends in ``suffix`` (any case with ``ignore_case``);
    an empty ``-o`` and a bare ``.pt`` get their own message, suggesting ``example``."""
    if not str(path).strip():
        raise VrnError(f"-o is empty; name the output {what} (e.g. -o {example})")
    name = Path(path).name.lower() if ignore_case else Path(path).name
    if name == suffix:
        raise VrnError(f"{path}: the output {what} needs a name before {suffix} ({example})")
    if not name.endswith(suffix) or str(path).endswith(("/", os.sep)):
        raise VrnError(f"{path}: output {what} must end in {suffix}")


def check_output(path: str | os.PathLike, force: bool) -> Path:
    """Output file ``path`` as a :class:`Path`; a one-line error when it is a directory, exists
    without ``force``, or its directory cannot be made or written."""
    p = Path(path)
    # a file goes here: even --force does not replace a directory, and a name given with a
    # trailing slash ("out/new/") means a directory, which Path would silently make a file
    if p.is_dir() or str(path).endswith(("/", os.sep)):
        raise VrnError(
            f"{path}: output path is a directory (a file is written here); choose another"
        )
    if p.exists() and not force:
        raise VrnError(f"{p}: output exists; pass --force to overwrite")
    check_writable(p.parent)
    return p


def check_outputs(
    paths: list[str | os.PathLike],
    force: bool,
    inputs: list[str | os.PathLike] = (),  # type: ignore[assignment]
) -> list[Path]:
    """:func:`check_output` for each of ``paths``, none of them one of ``inputs``."""
    check_not_input(paths, inputs)
    return [check_output(o, force) for o in paths]


def check_not_input(paths: list, inputs: list) -> None:
    """Refuse an output that is one of the (non-empty) ``inputs``, even with ``--force``."""
    for o in paths:
        for i in inputs:
            if i and same_file(i, o):
                raise VrnError(f"{o}: output would overwrite the input {i}; choose another output")


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether ``a`` and ``b`` name one file (hard links too, where both exist)."""
    pa, pb = Path(a), Path(b)
    if pa.exists() and pb.exists():
        return os.path.samefile(pa, pb)
    return pa.resolve() == pb.resolve()


def check_resume_force(resume: bool, force: bool) -> None:
    """``--resume`` continues an output and ``--force`` replaces it: together they contradict."""
    if resume and force:
        raise VrnError(
            "--resume and --force contradict (--resume continues the existing output, --force "
            "starts over and replaces it); pass one of them"
        )


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


def _missing(d: Path) -> list[Path]:
    """``d`` and its ancestors that do not exist, deepest first."""
    out = []
    while not (d.exists() or d.is_symlink()) and d != d.parent:
        out.append(d)
        d = d.parent
    return out


def _existing(d: Path) -> Path:
    """``d`` or its nearest ancestor that exists (as anything: a file in the way counts)."""
    missing = _missing(d)
    return missing[-1].parent if missing else d


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
    missing = _missing(d)
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise VrnError(f"{d}: cannot create output directory ({why(d, e)})") from None
    return missing


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
        if tmp.exists():
            tmp.unlink()


def write_json(path: str | os.PathLike, obj: object) -> Path:
    """Write ``obj`` as indented JSON, atomically (NaN and infinities as ``null``)."""
    p = Path(path)
    text = json.dumps(json_safe(obj), indent=2, sort_keys=False, allow_nan=False)
    with atomic_path(p) as tmp:
        tmp.write_text(text + "\n")
    return p


def json_safe(o: object) -> object:
    """``o`` with numpy values and paths converted, non-finite floats as None."""
    if isinstance(o, dict):
        return {k: json_safe(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [json_safe(v) for v in o]
    if isinstance(o, float):
        return o if math.isfinite(o) else None
    if isinstance(o, (str, int, bool)) or o is None:
        return o
    if isinstance(o, Path):
        return str(o)
    import numpy as np

    if isinstance(o, (np.generic, np.ndarray)):
        return json_safe(o.tolist())
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 of a file's bytes (hex), read in 1 MiB chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()
