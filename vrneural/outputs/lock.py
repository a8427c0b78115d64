"""A lock per output (a file or an ``--out`` directory), so two commands cannot write one
output at once: a :mod:`filelock` ``flock`` on a file in ``$TMPDIR/vrneural-locks`` named by
the output's absolute path, released by the kernel however its holder ends. A second process
is a one-line error, never a wait; where there are no locks, outputs go without one."""

from __future__ import annotations

import contextlib
import hashlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

import filelock

from vrneural.errors import VrnError


def lock_path(output: str | os.PathLike) -> Path:
    """The lock file of ``output`` (which need not exist)."""
    key = str(Path(output).resolve())
    name = hashlib.sha256(key.encode()).hexdigest()[:32] + ".lock"
    return Path(tempfile.gettempdir()) / "vrneural-locks" / name


class OutputLock:
    """The lock of one output; ``flag`` names the option in the busy message (``--out``)."""

    def __init__(self, output: str | os.PathLike, flag: str = "output"):
        self.output, self.flag = Path(output), flag
        self._lock: filelock.FileLock | None = None

    def acquire(self) -> bool:
        """True when taken, False where there are no locks; a one-line error when busy."""
        if self._lock is not None:
            return True
        path = lock_path(self.output)
        try:
            path.parent.mkdir(mode=0o777, exist_ok=True)
            lock = filelock.FileLock(path, thread_local=False, fallback_to_soft=False)
            lock.acquire(timeout=0)
        except filelock.Timeout:
            raise VrnError(
                f"{self.output}: another vrneural process is writing this output right now; "
                f"wait for it to finish or choose another {self.flag}"
            ) from None
        except OSError:
            return False  # no locks here (ENOLCK, a read-only /tmp, another user's file)
        self._lock = lock
        return True

    def held_elsewhere(self) -> bool:
        """Whether another process holds this output's lock."""
        if self._lock is not None:
            return False
        try:
            if self.acquire():
                self.release()
        except VrnError:
            return True
        return False

    def release(self) -> None:
        """Release the lock, removing its file while still held (filelock then sees a file
        removed under it and takes a new one)."""
        lock, self._lock = self._lock, None
        if lock is not None:
            with contextlib.suppress(OSError):
                Path(lock.lock_file).unlink()
            lock.release()


@contextlib.contextmanager
def output_lock(*outputs: str | os.PathLike) -> Iterator[None]:
    """Hold the lock of each output file for the block (a checkpoint or BTF being written);
    under ``torchrun`` only rank 0, which alone writes."""
    locks = [] if int(os.environ.get("RANK", "0") or 0) else [OutputLock(o) for o in outputs]
    try:
        for lk in locks:
            lk.acquire()
        yield
    finally:
        for lk in reversed(locks):
            lk.release()
