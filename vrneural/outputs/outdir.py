"""An output directory for the length of a ``with`` block: checked, emptied, marked, locked,
and sealed however the block ends, whoever the caller is (the CLI or the Python API).

Its marker (:data:`OUTPUT_MARK`) is the directory's manifest: the command that wrote it and,
once sealed, the names it wrote (``entries``; ``None`` while it is being written). A later
``--force`` of the same command replaces only those; files added after the seal, another
command's output and a folder of the user's files are never deleted.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
from pathlib import Path

from vrneural.errors import VrnError
from vrneural.interrupt import hold_signals, put_back
from vrneural.outputs.files import atomic_path, check_writable, make_dirs, why
from vrneural.outputs.lock import OutputLock

OUTPUT_MARK = ".vrneural-output"


def read_mark(p: Path) -> dict | None:
    """The marker of output directory ``p`` (``{"command", "entries"}``), ``{}`` for a marker
    this release cannot read (an older one), None when there is none."""
    f = Path(p) / OUTPUT_MARK
    if not f.is_file():
        return None
    try:
        doc = json.loads(f.read_text())
    except (OSError, ValueError):  # UnicodeDecodeError is a ValueError
        return {}
    return doc if isinstance(doc, dict) else {}


def write_mark(p: str | os.PathLike, command: str, entries: list[str] | None) -> None:
    """Mark ``p`` as ``vrneural <command>``'s output that wrote ``entries`` (None: in progress)."""
    doc = {"written_by": f"vrneural {command}", "command": command, "entries": entries}
    doc["note"] = "--force of the same command may replace the entries listed here"
    with atomic_path(Path(p) / OUTPUT_MARK) as tmp:  # a killed write never leaves half a marker
        tmp.write_text(json.dumps(doc, indent=1) + "\n")


def seal_output_dir(path: str | os.PathLike, command: str) -> Path:
    """Record what ``vrneural <command>`` wrote in ``path`` (the names now in it), so a later
    ``--force`` deletes only those and refuses when anything else was added."""
    p = Path(path)
    write_mark(p, command, sorted(c.name for c in p.iterdir() if c.name != OUTPUT_MARK))
    return p


class OutputDir:
    """The output directory ``path`` of ``vrneural <command>``.

    In ``with OutputDir(path, command, force=..., resume=...) as out:``, :meth:`check` refuses
    before any work what may not be replaced; :meth:`open` (which checks too) then takes its
    lock, empties it (keeping the names in ``keep``) and marks it; when the block ends, however
    it ends, it is sealed (:meth:`close`).
    An existing directory must be empty or this command's output; it needs ``force`` or
    ``resume`` (else the error says ``remedy``). With ``resume`` what is there is kept (the
    caller continues or overwrites it), so neither an unsealed output nor added files are
    refused; ``keep=True`` keeps everything too, but is as strict as ``force``.
    """

    def __init__(
        self,
        path: str | os.PathLike,
        command: str,
        *,
        force: bool = False,
        resume: bool = False,
        keep: tuple[str, ...] | bool = (),
        remedy: str = "pass --force to overwrite",
    ):
        if not str(path).strip():  # Path("") is ".": the current directory, never meant
            raise VrnError("--out is empty; name the output directory")
        self.path, self.command, self.keep, self.remedy = Path(path), command, keep, remedy
        self.force, self.resume = force, resume
        self.keeps_all = resume or keep is True  # nothing is deleted: the caller continues
        self._lock = OutputLock(self.path, "--out")
        self._created: list[Path] = []  # directories made here, deepest first
        self.opened = self.checked = False

    def __enter__(self) -> OutputDir:
        return self

    def __exit__(self, typ, value, tb) -> None:
        self.close(failed=typ is not None)

    def __truediv__(self, name: str) -> Path:
        return self.path / name

    def check(self, force: bool | None = None) -> Path:
        """Refuse, before any work, what this output may not replace (one-line errors)."""
        p = self.path
        force = self.force or self.resume if force is None else force
        if p.exists() or p.is_symlink():
            if not p.is_dir():
                raise VrnError(f"{p}: output exists and is not a directory; choose another --out")
            if any(p.iterdir()):
                self._check_mark(read_mark(p), force)
        check_writable(p.parent)
        self.checked = True
        return p

    def _check_mark(self, mark: dict | None, force: bool) -> None:
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
        if mark.get("entries") is None and self._lock.held_elsewhere():  # --force won't help
            raise VrnError(
                f"{p}: another vrneural process is writing this output right now; wait for it "
                "to finish or choose another --out"
            )
        if not force:
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
        """Create, lock, empty (unless ``resume``) and mark the directory: call it once the
        inputs are validated, so a run that fails early leaves the old output as it was."""
        p = self.path
        if not self.checked:
            self.check()
        self._created += make_dirs(p)
        self._lock.acquire()  # before emptying it: another process may be about to do the same
        if not self.keeps_all:
            self.check(force=True)  # again: the folder may have changed since
            for child in p.iterdir():
                if child.name not in (*self.keep, OUTPUT_MARK):  # (keep: a tuple here)
                    _remove(child)
        write_mark(p, self.command, None)
        self.opened = True
        return p

    def seal(self) -> Path:
        """Record what was written (see :func:`seal_output_dir`) and release the lock."""
        if self.opened:
            seal_output_dir(self.path, self.command)
            self.opened = False
        self._lock.release()
        return self.path

    def close(self, failed: bool = False) -> None:
        """Seal the output. A ``failed`` block's directory that was made here and holds nothing
        but the marker is removed instead, with the folders made for it that stay empty."""
        p, held = self.path, hold_signals()  # a second Ctrl-C or SIGTERM waits for this
        try:
            if self.opened and failed and p in self._created and _only_mark(p):
                with contextlib.suppress(OSError):
                    (p / OUTPUT_MARK).unlink()
            elif self.opened:  # unless sealed already, or taken over meanwhile
                mark = read_mark(p) if p.is_dir() else None
                if mark and mark.get("command") == self.command and mark["entries"] is None:
                    with contextlib.suppress(VrnError, OSError):
                        seal_output_dir(p, self.command)
        finally:
            self.opened = False
            self._lock.release()
            for d in self._created:  # deepest first; one that holds anything is kept
                with contextlib.suppress(OSError):
                    d.rmdir()
            self._created = []
            put_back(held)


def _remove(child: Path) -> None:
    try:
        if child.is_dir() and not child.is_symlink():
            shutil.rmtree(child)
        else:
            child.unlink()
    except OSError as e:  # read-only, or permissions: what is left stays whole
        raise VrnError(
            f"{child}: cannot remove the old output to replace it ({e.strerror or e})"
        ) from None


def _only_mark(p: Path) -> bool:
    try:
        return [c.name for c in p.iterdir()] == [OUTPUT_MARK]
    except OSError:
        return False


def new_output_dir(base: str) -> Path:
    """Create a fresh directory ``base`` (``base-2``, ``base-3``... if taken): the name is
    claimed with an exclusive ``mkdir``, so two runs started in the same second never share
    it."""
    k = 1
    while True:
        p = Path(base if k == 1 else f"{base}-{k}")
        try:
            make_dirs(p.parent)
            p.mkdir()
            return p
        except FileExistsError as e:
            if p.parent.is_dir():  # the name is taken: the next one
                k += 1
                continue
            raise VrnError(f"{p}: cannot create output directory ({why(p, e)})") from None
        except OSError as e:
            raise VrnError(f"{p}: cannot create output directory ({why(p, e)})") from None
