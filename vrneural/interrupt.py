"""Ctrl-C at a safe point: :class:`Stop` turns SIGINT (and SIGTERM, what ``kill``, ``timeout``
and batch schedulers send) into a flag that a loop checks between units of work (a training
step, a rendered frame), so what is finished is always whole."""

from __future__ import annotations

import signal
import threading

#: the signals :class:`Stop` turns into its flag
SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Stop:
    """Within ``with Stop() as stop``, Ctrl-C (or SIGTERM) sets ``stop.flag`` instead of
    raising; the loop finishes its current unit and stops. While the loop sets
    ``stop.second_raises``, a second one raises :class:`KeyboardInterrupt` at once (for units
    that can take long, such as a frame of the per-pixel reference). Outside the main thread
    it does nothing (signals go to the main one)."""

    def __init__(self):
        self.flag = False
        self.second_raises = False
        self._old = {}

    def __enter__(self):
        if threading_main():  # a SIGTERM ignored on purpose (trap '' TERM) stays ignored;
            # SIGINT is taken even when ignored: shells start background jobs that way
            sigs = [s for s in SIGNALS if not _ignored(s) or s == signal.SIGINT]
            self._old = {sig: signal.signal(sig, self._handle) for sig in sigs}
        return self

    def _handle(self, *_):
        if self.flag and self.second_raises:
            raise KeyboardInterrupt
        self.flag = True

    def __exit__(self, *exc):
        for sig, old in self._old.items():
            signal.signal(sig, old)
        self._old = {}


def interrupt_saying(what: str, inner: BaseException | None = None) -> KeyboardInterrupt:
    """The KeyboardInterrupt to raise after a Ctrl-C was handled: ``what`` (what was kept, how
    to continue) rides on it to the command line, which prints it on its one ``interrupted``
    line (``vrneural btf render: interrupted after 3/7 views; ...``). ``what`` starts with a
    word that follows "interrupted" ("after ...", "before ...", "(...)"). An ``inner``
    interrupt's own words are kept in front."""
    said = str(inner) if inner is not None and inner.args else ""
    return KeyboardInterrupt(f"{said}; {what}" if said else what)


def threading_main() -> bool:
    return threading.current_thread() is threading.main_thread()


def _ignored(sig) -> bool:
    return signal.getsignal(sig) is signal.SIG_IGN


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where Ctrl-C's KeyboardInterrupt would be (every ``except
    KeyboardInterrupt`` cleans up after it too). Its own type because CPython, having marked
    a KeyboardInterrupt as unhandled (it compares the exact type), can end the process by
    SIGINT after our handler returned 130 (docs/quality-research.md, "Notes moved out of the
    code")."""


def raise_terminated(*_) -> None:
    """SIGTERM handler: raise :class:`Terminated` once; later SIGTERMs are ignored while the
    command stops (a second one must not break its clean-up)."""
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    raise Terminated


def terminate_as_interrupt():
    """SIGTERM (``kill``, ``timeout``, batch schedulers) stops a command as Ctrl-C does: exit
    130, outputs sealed, nothing half-written. Commands with a safe stopping point
    (:class:`Stop`) handle both signals themselves; this covers the rest. A SIGTERM ignored by
    whoever started us stays ignored. Returns the previous handler (to put back), or None
    where nothing was installed."""
    if not threading_main() or signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
        return None
    return signal.signal(signal.SIGTERM, raise_terminated)


def hold_signals() -> dict:
    """Ignore SIGINT and SIGTERM (a command's clean-up: sealing its outputs must not be cut
    short); returns the handlers to put back with :func:`put_back`."""
    if not threading_main():
        return {}
    return {s: signal.signal(s, signal.SIG_IGN) for s in SIGNALS}


def put_back(old: dict) -> None:
    for sig, h in old.items():
        if h is not None:  # None: a handler not set from Python, not restorable
            signal.signal(sig, h)
