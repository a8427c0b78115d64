"""The output layer, through which every command writes: output files checked before any
work (:func:`check_outputs`), :class:`OutputDir` (an ``--out`` directory for a ``with`` block,
with its marker), :func:`output_lock` (files being trained, ``-o x.pt``) and atomic writes
(:func:`write_json`; :func:`atomic_path` of :mod:`vrneural.outputs.files`)."""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import json
import math
import os
import shutil
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

import filelock

from vrneural.errors import VrnError
from vrneural.interrupt import hold_signals, put_back
from vrneural.outputs.files import (  # noqa: F401 (the rest of the layer, re-exported)
    atomic_path,
    check_free_space,
    check_writable,
    make_dirs,
    make_parent,
    partial_path,
)

OUTPUT_MARK = ".vrneural-output"


def check_suffix(path: str, suffix: str, what: str, example: str, ignore_case=False) -> None:
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


def check_outputs(paths: Sequence, force: bool, inputs: Sequence = ()) -> list[Path]:
    """:func:`check_output` for each of ``paths``, none of them one of the (non-empty)
    ``inputs`` (refused even with ``force``)."""
    for o, i in itertools.product(paths, inputs):
        if i and same_file(i, o):
            raise VrnError(f"{o}: output would overwrite the input {i}; choose another output")
    return [check_output(o, force) for o in paths]


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether ``a`` and ``b`` name one file (hard links too, where both exist)."""
    if Path(a).exists() and Path(b).exists():
        return os.path.samefile(a, b)
    return Path(a).resolve() == Path(b).resolve()


def check_resume_force(resume: bool, force: bool) -> None:
    """``--resume`` continues an output and ``--force`` replaces it: together they contradict."""
    if resume and force:
        raise VrnError(
            "--resume and --force contradict (--resume continues the existing output, --force "
            "starts over and replaces it); pass one of them"
        )


def _take_lock(output: Path, flag: str) -> filelock.FileLock | None:
    """The lock of ``output`` (which need not exist): a :mod:`filelock` ``flock`` on a file
    named by its absolute path, released by the kernel however its holder ends. Held by another
    process: a one-line error (``flag``: the option to change), never a wait; None where there
    are no locks (outputs then go without one)."""
    key = hashlib.sha256(str(output.resolve()).encode()).hexdigest()[:32]
    path = Path(tempfile.gettempdir()) / "vrneural-locks" / f"{key}.lock"
    try:
        path.parent.mkdir(mode=0o777, exist_ok=True)
        lock = filelock.FileLock(path, thread_local=False, fallback_to_soft=False)
        lock.acquire(timeout=0)
    except filelock.Timeout:
        raise VrnError(
            f"{output}: another vrneural process is writing this output right now; wait for it "
            f"to finish or choose another {flag}"
        ) from None
    except OSError:
        return None  # no locks here (ENOLCK, a read-only /tmp, another user's file)
    return lock


def _release(lock: filelock.FileLock | None) -> None:
    """Release ``lock``, removing its file while still held (filelock then sees a file removed
    under it and takes a new one)."""
    if lock is not None:
        with contextlib.suppress(OSError):
            Path(lock.lock_file).unlink()
        lock.release()


@contextlib.contextmanager
def output_lock(*outputs: str | os.PathLike) -> Iterator[None]:
    """Hold the lock of each output file for the block (a checkpoint or BTF being written);
    under ``torchrun`` only rank 0, which alone writes."""
    with contextlib.ExitStack() as stack:  # (released in reverse order)
        for o in [] if int(os.environ.get("RANK", "0") or 0) else outputs:
            stack.callback(_release, _take_lock(Path(o), "output"))
        yield


def read_mark(p: Path) -> dict | None:
    """The marker of ``p`` (``{"command", "entries"}``); ``{}`` when unreadable, None if none."""
    f = Path(p) / OUTPUT_MARK
    if not f.is_file():
        return None
    try:
        doc = json.loads(f.read_text())
    except (OSError, ValueError):  # UnicodeDecodeError is a ValueError
        return {}
    return doc if isinstance(doc, dict) else {}


def mark_output(path: str | os.PathLike, command: str, sealed: bool = True) -> Path:
    """Mark ``path`` as ``vrneural <command>``'s output: in progress (``entries`` None), or
    ``sealed``: of the names now in it, which ``--force`` of that command may replace."""
    p = Path(path)
    entries = sorted(c.name for c in p.iterdir() if c.name != OUTPUT_MARK) if sealed else None
    doc = {"written_by": f"vrneural {command}", "command": command, "entries": entries,
           "note": "--force of the same command may replace the entries listed here"}  # fmt: skip
    with atomic_path(p / OUTPUT_MARK) as tmp:  # a killed write never leaves half a marker
        tmp.write_text(json.dumps(doc, indent=1) + "\n")
    return p


class OutputDir:
    """``with OutputDir(path, command, force=..., resume=...) as out:`` the output directory of
    ``vrneural <command>``. :meth:`check` refuses, before any work, what may not be replaced;
    :meth:`open` (checking too) locks, empties (but the names in ``keep``) and marks it; the
    block's end seals it (:meth:`close`). An existing non-empty one must be this command's and
    needs ``force`` or ``resume`` (else the error says ``remedy``). ``resume`` keeps what is
    there (so neither an unsealed output nor added files are refused); ``keep=True`` keeps
    everything too, as strict as ``force``."""

    def __init__(self, path, command: str, *, force=False, resume=False, keep=(), remedy=""):
        if not str(path).strip():  # Path("") is ".": the current directory, never meant
            raise VrnError("--out is empty; name the output directory")
        self.path, self.command, self.keep = Path(path), command, keep  # keep: names or True
        self.force, self.resume, self.remedy = force, resume, remedy or "pass --force to overwrite"
        self._lock: filelock.FileLock | None = None
        self._created: list[Path] = []  # directories made here, deepest first
        self.opened = False

    def __enter__(self) -> OutputDir:
        return self

    def __exit__(self, typ, value, tb) -> None:
        self.close(failed=typ is not None)

    def __truediv__(self, name: str) -> Path:
        return self.path / name

    def check(self) -> Path:
        """Refuse what this output may not replace (one-line errors)."""
        p = self.path
        if p.exists() or p.is_symlink():
            if not p.is_dir():
                raise VrnError(f"{p}: output exists and is not a directory; choose another --out")
            if any(p.iterdir()):
                self._check_mark(read_mark(p))
        check_writable(p.parent)
        return p

    def _check_mark(self, mark: dict | None) -> None:
        p, command = self.path, self.command
        if mark is None:  # checked first: no flag helps here, so none is suggested
            raise VrnError(
                f"{p}: not a vrneural output directory (no {OUTPUT_MARK}); vrneural only "
                "replaces or reuses its own output, so choose another --out"
            )
        if mark.get("command") != command:
            by = mark.get("command")
            by = f"`vrneural {by}`" if by else "an older vrneural release"
            raise VrnError(
                f"{p}: holds the output of {by}, not of `vrneural {command}`; choose another --out"
            )
        if mark.get("entries") is None and self._lock is None:  # another process writing it?
            _release(_take_lock(p, "--out"))  # (--force would not help)
        if not (self.force or self.resume):
            raise VrnError(f"{p}: output exists; {self.remedy}")
        if self.resume:
            return
        if not isinstance(mark.get("entries"), list):  # (a running writer: refused above)
            raise VrnError(
                f"{p}: an unfinished `vrneural {command}` output (its process was killed), so "
                "--force cannot tell its files from others; check it and delete it yourself, or "
                "choose another --out"
            )
        ours = {*mark["entries"], OUTPUT_MARK}
        foreign = sorted(c.name for c in p.iterdir() if c.name not in ours)
        if foreign:
            shown = ", ".join(foreign[:3]) + (", ..." if len(foreign) > 3 else "")
            raise VrnError(
                f"{p}: holds {len(foreign)} file(s) vrneural did not write there ({shown}); "
                "--force never deletes them: move them away or choose another --out"
            )

    def open(self) -> Path:
        """Create, lock, empty and mark the directory, once the inputs are validated (a run
        that fails early leaves the old output as it was)."""
        p = self.check()  # (again where the caller checked: the folder may have changed since)
        self._created += make_dirs(p)
        if self._lock is None:  # before emptying it: another process may be about to do so
            self._lock = _take_lock(p, "--out")
        if not (self.resume or self.keep is True):  # else nothing is deleted: the caller goes on
            self.check()  # again, under the lock
            for child in (c for c in p.iterdir() if c.name not in (*self.keep, OUTPUT_MARK)):
                try:  # (keep: a tuple here)
                    if child.is_dir() and not child.is_symlink():
                        shutil.rmtree(child)
                    else:
                        child.unlink()
                except OSError as e:  # read-only, or permissions: what is left stays whole
                    raise VrnError(
                        f"{child}: cannot remove the old output to replace it ({e.strerror or e})"
                    ) from None
        mark_output(p, self.command, sealed=False)
        self.opened = True
        return p

    def close(self, failed: bool = False) -> None:
        """Seal the output; a ``failed`` block's directory made here that holds only the marker
        is removed instead, with the folders made for it."""
        p, held = self.path, hold_signals()  # a second Ctrl-C or SIGTERM waits for this
        try:
            lone = p in self._created and p.is_dir() and os.listdir(p) == [OUTPUT_MARK]
            if self.opened and failed and lone:
                with contextlib.suppress(OSError):
                    (p / OUTPUT_MARK).unlink()
            elif self.opened:  # unless sealed already, or taken over meanwhile
                mark = read_mark(p) if p.is_dir() else None
                if mark and mark.get("command") == self.command and mark["entries"] is None:
                    with contextlib.suppress(VrnError, OSError):
                        mark_output(p, self.command)
        finally:
            self.opened, lock, self._lock = False, self._lock, None
            _release(lock)
            for d in self._created:  # deepest first; one that holds anything is kept
                with contextlib.suppress(OSError):
                    d.rmdir()
            self._created = []
            put_back(held)

    seal = close  # (before the block's end: the output is complete)


def write_json(path: str | os.PathLike, obj: object) -> Path:
    """Write ``obj`` as indented JSON, atomically (NaN and infinities as ``null``)."""
    text = json.dumps(json_safe(obj), indent=2, allow_nan=False)
    with atomic_path(path) as tmp:
        tmp.write_text(text + "\n")
    return Path(path)


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
    if type(o).__module__ == "numpy":  # numpy scalars and arrays
        return json_safe(o.tolist())  # type: ignore[attr-defined]
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 of a file's bytes (hex), read in 1 MiB chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()
