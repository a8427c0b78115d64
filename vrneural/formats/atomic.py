"""Outputs that never lose data: refuse to overwrite without ``force``, write atomically."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import math
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from vrneural.errors import VrnError


def check_suffix(
    path: str, suffix: str, what: str, example: str, ignore_case: bool = False
) -> None:
    """A one-line error unless output ``path`` (``-o``) names a file ending in ``suffix``
    (exactly, or with ``ignore_case`` in any case): an empty ``-o``, a bare ``.pt`` (a hidden
    file without a suffix to Path) and another ending each get their own message.
    ``example``: a name to suggest."""
    if not str(path).strip():
        raise VrnError(f"-o is empty; name the output {what} (e.g. -o {example})")
    name = Path(path).name.lower() if ignore_case else Path(path).name
    if name == suffix:
        raise VrnError(f"{path}: the output {what} needs a name before {suffix} ({example})")
    if not name.endswith(suffix) or str(path).endswith(("/", os.sep)):
        raise VrnError(f"{path}: output {what} must end in {suffix}")


def check_output(path: str | os.PathLike, force: bool) -> Path:
    """Validate an output path before any work starts.

    Raises :class:`VrnError` when ``path`` exists and ``force`` is false, or when its parent
    directory cannot be created. Returns the path as :class:`Path`.
    """
    p = Path(path)
    # a file goes here: even --force does not replace a directory, and a name given with a
    # trailing slash ("out/new/") means a directory, which Path would silently make a file
    if p.is_dir() or str(path).endswith(("/", os.sep)):
        raise VrnError(
            f"{path}: output path is a directory (a file is written here); choose another"
        )
    if p.exists() and not force:
        raise VrnError(f"{p}: output exists; pass --force to overwrite")
    _make_parent(p)
    return p


def check_outputs(
    paths: list[str | os.PathLike],
    force: bool,
    inputs: list[str | os.PathLike] = (),  # type: ignore[assignment]
) -> list[Path]:
    """:func:`check_output` for every file a command will write, after refusing any output
    that is one of its ``inputs`` (:func:`check_not_input`)."""
    check_not_input(paths, inputs)
    return [check_output(o, force) for o in paths]


def check_not_input(paths: list, inputs: list) -> None:
    """Refuse an output that is one of the command's inputs, even with ``--force`` (the
    command would destroy what it reads). Empty inputs are skipped."""
    for o in paths:
        for i in inputs:
            if i and same_file(i, o):
                raise VrnError(f"{o}: output would overwrite the input {i}; choose another output")


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether ``a`` and ``b`` name the same file (``samefile`` when both exist, which also
    sees hard links; else the resolved paths)."""
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
    """Refuse to start writing ``nbytes`` into ``path``'s directory when the disk has less
    free space (``reclaimed``: bytes of a file the write replaces)."""
    p = Path(path)
    try:
        free = shutil.disk_usage(p.parent).free + reclaimed
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


_CREATED: list[Path] = []  # directories this process created for its outputs


def _mkdirs(d: Path) -> None:
    """``d.mkdir(parents=True, exist_ok=True)``, remembering each directory it creates so
    that :func:`remove_empty_created_dirs` can take back those a failed command left empty."""
    missing = []
    q = d
    while not (q.exists() or q.is_symlink()) and q != q.parent:
        missing.append(q)
        q = q.parent
    d.mkdir(parents=True, exist_ok=True)
    _CREATED.extend(missing)


def remove_empty_created_dirs() -> None:
    """Remove the directories :func:`_mkdirs` created that are still empty, deepest first:
    a command that fails after checking its outputs leaves no empty folders behind. A
    directory that holds anything (an output, a user's file) is kept."""
    for d in sorted(set(_CREATED), key=lambda q: len(q.parts), reverse=True):
        try:
            d.rmdir()
        except OSError:
            pass
    _CREATED.clear()


def _make_parent(p: Path) -> None:
    """Create the directory an output goes into and check that files can be created there;
    failure is a one-line :class:`VrnError`."""
    try:
        _mkdirs(p.parent)
    except OSError as e:
        raise VrnError(
            f"{p.parent}: cannot create output directory ({_why(p.parent, e)})"
        ) from None
    try:  # a real file, not os.access: root passes access() checks on read-only mounts too
        with tempfile.TemporaryFile(dir=p.parent, prefix=".vrneural-probe-"):
            pass
    except OSError as e:
        raise VrnError(f"{p.parent}: cannot write here ({e.strerror or e})") from None


OUTPUT_MARK = ".vrneural-output"


def check_output_dir(
    path: str | os.PathLike,
    force: bool,
    command: str,
    remedy: str = "pass --force to overwrite",
    deletes: bool = True,
) -> Path:
    """Validate an output *directory* of ``vrneural <command>`` before any work starts.

    An existing path must be an empty directory or one that the same command wrote (its
    :data:`OUTPUT_MARK` names the command), and it needs ``force`` (else the error says
    ``remedy``). ``--force`` replaces only that command's own output: never a folder of the
    user's files, never another command's output (a ``bench quality`` directory of trained
    checkpoints is not a ``run`` directory), and never files added to it after the command
    sealed it (:func:`seal_output_dir`). An unsealed output (its command was killed, or is
    still running in another process) is refused too, since nobody knows what in it is ours.
    ``deletes=False``: the caller keeps what is there (``bench quality``), so neither applies.
    """
    if not str(path).strip():  # Path("") is ".": the current directory, never meant
        raise VrnError("--out is empty; name the output directory")
    p = Path(path)
    if p.exists() or p.is_symlink():
        if not p.is_dir():
            raise VrnError(f"{p}: output exists and is not a directory; choose another --out")
        if any(p.iterdir()):
            mark = read_mark(p)
            if mark is None:  # checked first: no flag helps here, so none is suggested
                raise VrnError(
                    f"{p}: not a vrneural output directory (no {OUTPUT_MARK}); vrneural only "
                    "replaces or reuses its own output, so choose another --out"
                )
            if mark.get("command") != command:
                by = mark.get("command")
                by = f"`vrneural {by}`" if by else "an older vrneural release"
                raise VrnError(
                    f"{p}: holds the output of {by}, not of `vrneural {command}`; choose "
                    "another --out"
                )
            if mark.get("entries") is None and _held_elsewhere(p):  # --force would not help
                raise VrnError(
                    f"{p}: another vrneural process is writing this output right now; wait "
                    "for it to finish or choose another --out"
                )
            if not force:
                raise VrnError(f"{p}: output exists; {remedy}")
            if deletes:
                _check_replaceable(p, mark, command)
    _make_parent(p)
    return p


def _check_replaceable(p: Path, mark: dict, command: str) -> None:
    """``--force`` may empty ``p`` only when its command sealed it and nothing was added."""
    if not isinstance(mark.get("entries"), list):  # (a running writer: refused before)
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


def _held_elsewhere(p: Path) -> bool:
    """Whether another process holds the lock of output directory ``p`` (see
    :func:`lock_output_dir`); False where there are no locks."""
    fcntl = _fcntl()
    if fcntl is None or p.resolve() in _LOCKS:
        return False
    try:
        fd = os.open(p, os.O_RDONLY)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    except OSError:
        return False
    finally:
        os.close(fd)  # closing it releases a lock taken here
    return False


def read_mark(p: Path) -> dict | None:
    """The marker of output directory ``p`` (``{"command", "entries"}``), ``{}`` for a marker
    this release cannot read (an older one), None when there is none."""
    f = p / OUTPUT_MARK
    if not f.is_file():
        return None
    try:
        doc = json.loads(f.read_text())
    except (OSError, ValueError):  # UnicodeDecodeError is a ValueError
        return {}
    return doc if isinstance(doc, dict) else {}


def _write_mark(p: Path, command: str, entries: list[str] | None) -> None:
    doc = {"written_by": f"vrneural {command}", "command": command, "entries": entries}
    doc["note"] = "--force of the same command may replace the entries listed here"
    with atomic_path(p / OUTPUT_MARK) as tmp:  # a killed write never leaves half a marker
        tmp.write_text(json.dumps(doc, indent=1) + "\n")


def mark_output_dir(path: str | os.PathLike, command: str) -> Path:
    """Create ``path`` (and parents) and mark it as ``vrneural <command>``'s output, keeping
    its contents; the mark lists no entries until :func:`seal_output_dir` (a run in progress)."""
    p = Path(path)
    try:
        _mkdirs(p)
    except OSError as e:
        raise VrnError(f"{p}: cannot create output directory ({_why(p, e)})") from None
    lock_output_dir(p)
    _write_mark(p, command, None)
    _MARKED[p.resolve()] = command
    return p


#: output directories this process marked and has not sealed yet (see :func:`seal_marked`)
_MARKED: dict[Path, str] = {}

#: output directories this process holds the lock of -> the open descriptor holding it
_LOCKS: dict[Path, int] = {}


def lock_output_dir(p: Path) -> None:
    """Take an exclusive ``flock`` on output directory ``p`` for as long as this process writes
    it (released by :func:`seal_output_dir`, or by the kernel however the process ends), so two
    commands given the same ``--out`` cannot empty and fill it at the same time: the second is
    a one-line error. A no-op where ``flock`` does not exist, or for a directory this process
    already holds."""
    key = p.resolve()
    if _fcntl() is None or key in _LOCKS:
        return
    try:
        fd = os.open(p, os.O_RDONLY)
    except OSError:
        return  # unreadable: the write itself will say so
    if _flock(fd, p, "--out"):
        _LOCKS[key] = fd


def _fcntl():
    """The ``fcntl`` module, or None where it does not exist (not POSIX: no output locks)."""
    try:
        import fcntl
    except ImportError:
        return None
    return fcntl


def _flock(fd: int, p, flag: str) -> bool:
    """Lock ``fd`` (exclusive, not waiting) for output ``p``: True when held; False, with
    ``fd`` closed, where the file system has no locks (some network mounts: go on without);
    a one-line error, naming ``flag``, where another process holds it."""
    import fcntl  # callers checked :func:`_fcntl`

    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:  # EWOULDBLOCK: another process holds it
        os.close(fd)
        raise VrnError(
            f"{p}: another vrneural process is writing this output right now; wait for it to "
            f"finish or choose another {flag}"
        ) from None
    except OSError:
        os.close(fd)
        return False
    return True


#: output files this process holds the lock of -> (descriptor, lock file)
_FILE_LOCKS: dict[str, tuple[int, Path]] = {}


def lock_output_file(p) -> None:
    """Take an exclusive ``flock`` for output file ``p`` (a checkpoint, a BTF) for as long as
    this process trains it, so a second command given the same ``-o`` while the first runs is
    a one-line error instead of two runs overwriting each other's checkpoints. The lock is on
    a file in ``$TMPDIR/vrneural-locks`` named by the output's absolute path (the output itself
    is replaced by renames, so it cannot carry the lock); :func:`output_locks` removes it when
    it releases the lock, and the kernel releases it however the process ends. A no-op where
    this process holds it already, under ``torchrun`` on ranks other than 0 (rank 0 writes),
    or where locks are unavailable."""
    key = str(Path(p).resolve())
    if _fcntl() is None or int(os.environ.get("RANK", "0") or 0) != 0 or key in _FILE_LOCKS:
        return
    path = Path(tempfile.gettempdir()) / "vrneural-locks"
    path = path / (hashlib.sha256(key.encode()).hexdigest()[:32] + ".lock")
    for _ in range(100):  # a holder may remove the file between our open and our lock
        try:
            path.parent.mkdir(mode=0o777, exist_ok=True)
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        except OSError:
            return  # no lock directory (read-only /tmp, another user's file): go on without
        if not _flock(fd, p, "output"):
            return
        try:
            same = os.path.samestat(os.fstat(fd), os.stat(path))
        except OSError:  # removed by the holder that just released it
            same = False
        if same:
            _FILE_LOCKS[key] = (fd, path)
            return
        os.close(fd)  # a file its holder removed: lock the new one


def _release_output_file(key: str) -> None:
    fd, path = _FILE_LOCKS.pop(key)
    with contextlib.suppress(OSError):
        path.unlink()  # while still holding it: a waiting process then sees another file
    os.close(fd)


@contextlib.contextmanager
def output_locks() -> Iterator[None]:
    """Release the output-file locks taken inside the block (not those held before it), so a
    process that trains many outputs (a benchmark) does not keep them all."""
    before = set(_FILE_LOCKS)
    try:
        yield
    finally:
        for k in set(_FILE_LOCKS) - before:
            _release_output_file(k)


def _unlock_output_dir(p: Path) -> None:
    fd = _LOCKS.pop(p.resolve(), None)
    if fd is not None:
        os.close(fd)  # closing the descriptor releases the flock


def _why(p: Path, e: OSError) -> str:
    """An OSError's reason, plainer where the usual one misleads: a path component that is a
    file gives ``File exists``/``Not a directory``."""
    for q in (p, *p.parents):
        if q.exists() and not q.is_dir():
            return f"{q} is a file, not a directory"
    return e.strerror or str(e)


def seal_marked(failed: bool = False) -> None:
    """Seal every output this process marked and did not seal: called when a command ends in
    any way (an error, Ctrl-C), so what it wrote is recorded and a later ``--force`` can still
    tell it from files added afterwards. Only a killed process leaves an output unsealed.
    A ``failed`` command's output directory that this process created and that holds nothing
    but the marker is removed instead: a run that fails in its set-up leaves nothing behind."""
    created = {d.resolve() for d in _CREATED} if failed else set()
    # deepest first: `bench all`'s sub-folders go before the folder that holds them is judged
    for p, command in sorted(_MARKED.items(), key=lambda kv: len(kv[0].parts), reverse=True):
        if p in created and _only_mark(p) and _remove_marked(p):
            _MARKED.pop(p, None)
            continue
        mark = read_mark(p) if p.is_dir() else None
        if mark is not None and mark.get("command") == command and mark.get("entries") is None:
            with contextlib.suppress(VrnError, OSError):
                seal_output_dir(p, command)
        _MARKED.pop(p, None)


def _remove_marked(p: Path) -> bool:
    """Remove output directory ``p`` that holds only its marker; False (it is then sealed
    as usual) where it cannot be."""
    _unlock_output_dir(p)
    try:
        (p / OUTPUT_MARK).unlink()
        p.rmdir()
    except OSError:
        return False
    return True


def _only_mark(p: Path) -> bool:
    try:
        return [c.name for c in p.iterdir()] == [OUTPUT_MARK]
    except OSError:
        return False


def seal_output_dir(path: str | os.PathLike, command: str) -> Path:
    """Record what ``vrneural <command>`` wrote in ``path`` (the names now in it), so a later
    ``--force`` deletes only those and refuses when anything else was added."""
    p = Path(path)
    _write_mark(p, command, sorted(c.name for c in p.iterdir() if c.name != OUTPUT_MARK))
    _MARKED.pop(p.resolve(), None)
    _unlock_output_dir(p)
    return p


def make_output_dir(path: str | os.PathLike, command: str, keep: tuple[str, ...] = ()) -> Path:
    """Empty a directory passed by :func:`check_output_dir` (except the names in ``keep``),
    create it and mark it as ``vrneural <command>``'s output. Call it once the inputs are
    validated, so a run that fails early leaves the old output as it was."""
    p = Path(path)
    if p.is_dir():
        lock_output_dir(p)  # before emptying it: another process may be about to do the same
        check_output_dir(p, True, command)  # again: the folder may have changed since
        for child in p.iterdir():
            if child.name in keep or child.name == OUTPUT_MARK:
                continue
            try:
                if child.is_dir() and not child.is_symlink():
                    shutil.rmtree(child)
                else:
                    child.unlink()
            except OSError as e:  # read-only, or permissions: what is left stays whole
                raise VrnError(
                    f"{child}: cannot remove the old output to replace it ({e.strerror or e})"
                ) from None
    return mark_output_dir(p, command)


def new_output_dir(base: str) -> Path:
    """Create and mark a fresh directory ``base`` (``base-2``, ``base-3``... if taken): the
    name is claimed with an exclusive ``mkdir``, so two runs started in the same second never
    share it."""
    k = 1
    while True:
        p = Path(base if k == 1 else f"{base}-{k}")
        try:
            _mkdirs(p.parent)
            p.mkdir()
            return p
        except FileExistsError as e:
            if p.parent.is_dir():  # the name is taken: the next one
                k += 1
                continue
            raise VrnError(f"{p}: cannot create output directory ({_why(p, e)})") from None
        except OSError as e:
            raise VrnError(f"{p}: cannot create output directory ({_why(p, e)})") from None


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
    except OSError as e:  # a full disk, a directory made read-only meanwhile: one line
        raise VrnError(f"{p}: cannot write ({e.strerror or e})") from None
    finally:
        if tmp.exists():
            tmp.unlink()


def write_json(path: str | os.PathLike, obj: object) -> Path:
    """Write ``obj`` as indented JSON, atomically. NaN and infinities become ``null``: bare
    ``NaN``/``Infinity`` are not JSON, and strict readers refuse the whole file."""
    p = Path(path)
    text = json.dumps(json_safe(obj), indent=2, sort_keys=False, allow_nan=False)
    with atomic_path(p) as tmp:
        tmp.write_text(text + "\n")
    return p


def json_safe(o: object) -> object:
    """``o`` with numpy values and paths converted and non-finite floats replaced by None."""
    if isinstance(o, dict):
        return {k: json_safe(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [json_safe(v) for v in o]
    if isinstance(o, float):
        return o if math.isfinite(o) else None
    if isinstance(o, (str, int, bool)) or o is None:
        return o
    return json_safe(_json_default(o))


def _json_default(o: object) -> object:
    import numpy as np

    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 of a file's bytes (hex), read in 1 MiB chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()
