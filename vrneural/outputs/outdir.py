"""An output directory for a ``with`` block: checked, locked, emptied, marked and sealed
however the block ends, whoever the caller is. Its marker (:data:`OUTPUT_MARK`) is its
manifest: the command and, once sealed, the names it wrote (``entries``; None while being
written). ``--force`` of that command replaces only those: never files added after the seal,
another command's output or a folder of the user's files."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
from pathlib import Path

from vrneural.errors import VrnError
from vrneural.interrupt import hold_signals, put_back
from vrneural.outputs.files import atomic_path, check_writable, make_dirs
from vrneural.outputs.lock import OutputLock

OUTPUT_MARK = ".vrneural-output"


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


def write_mark(p: str | os.PathLike, command: str, entries: list[str] | None) -> None:
    """Mark ``p`` as ``vrneural <command>``'s output of ``entries`` (None: in progress)."""
    doc = {"written_by": f"vrneural {command}", "command": command, "entries": entries}
    doc["note"] = "--force of the same command may replace the entries listed here"
    with atomic_path(Path(p) / OUTPUT_MARK) as tmp:  # a killed write never leaves half a marker
        tmp.write_text(json.dumps(doc, indent=1) + "\n")


def seal_output_dir(path: str | os.PathLike, command: str) -> Path:
    """Record the names now in ``path`` as what ``vrneural <command>`` wrote there."""
    p = Path(path)
    write_mark(p, command, sorted(c.name for c in p.iterdir() if c.name != OUTPUT_MARK))
    return p


class OutputDir:
    """``with OutputDir(path, command, force=..., resume=...) as out:`` the output directory of
    ``vrneural <command>``. :meth:`check` refuses, before any work, what may not be replaced;
    :meth:`open` (checking too) locks, empties (but the names in ``keep``) and marks it; the
    block's end seals it (:meth:`close`). An existing non-empty one must be this command's and
    needs ``force`` or ``resume`` (else the error says ``remedy``). ``resume`` keeps what is
    there (so neither an unsealed output nor added files are refused); ``keep=True`` keeps
    everything too, as strict as ``force``."""

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
        """Refuse what this output may not replace (one-line errors)."""
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
        """Create, lock, empty and mark the directory, once the inputs are validated (a run
        that fails early leaves the old output as it was)."""
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
        """Record what was written (:func:`seal_output_dir`) and release the lock."""
        if self.opened:
            seal_output_dir(self.path, self.command)
            self.opened = False
        self._lock.release()
        return self.path

    def close(self, failed: bool = False) -> None:
        """Seal the output; a ``failed`` block's directory made here that holds only the marker
        is removed instead, with the folders made for it."""
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
