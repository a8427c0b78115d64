"""A lock per output, so two commands given the same output cannot write it at once.

Each output (a file, or a whole ``--out`` directory) is locked through a lock file in
``$TMPDIR/vrneural-locks`` named by the output's absolute path (the output itself is replaced
by renames, or is a directory, so it cannot carry the lock), with :mod:`filelock`'s ``flock``
lock: the kernel releases it however the holder ends. A second process is a one-line error,
never a wait. Where there are no locks (``flock`` missing or failing, a lock directory of
another user), the output is written without one.
"""

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
    """The lock file of ``output`` (which need not exist yet)."""
    key = str(Path(output).resolve())
    name = hashlib.sha256(key.encode()).hexdigest()[:32] + ".lock"
    return Path(tempfile.gettempdir()) / "vrneural-locks" / name


class OutputLock:
    """The lock of one output; ``flag`` names the option in the busy message (``--out``)."""

    def __init__(self, output: str | os.PathLike, flag: str = "output"):
        self.output, self.flag = Path(output), flag
        self._lock: filelock.FileLock | None = None

    def acquire(self) -> bool:
        """Take the lock: True when held, False where locks are unavailable (go on without);
        a one-line :class:`VrnError` where another process holds it."""
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
        """Whether another process holds this output's lock (False where there are none)."""
        if self._lock is not None:
            return False
        try:
            if self.acquire():
                self.release()
        except VrnError:
            return True
        return False

    def release(self) -> None:
        """Release the lock, removing its file first (while still held: a process waiting on
        it then finds the file gone and takes a new one)."""
        lock, self._lock = self._lock, None
        if lock is not None:
            with contextlib.suppress(OSError):
                Path(lock.lock_file).unlink()
            lock.release()


@contextlib.contextmanager
def output_lock(*outputs: str | os.PathLike) -> Iterator[None]:
    """Hold the lock of every output file in ``outputs`` for the block (a checkpoint, a BTF
    being trained or written). Under ``torchrun`` only rank 0 locks (it alone writes)."""
    locks = [] if int(os.environ.get("RANK", "0") or 0) else [OutputLock(o) for o in outputs]
    try:
        for lk in locks:
            lk.acquire()
        yield
    finally:
        for lk in reversed(locks):
            lk.release()
