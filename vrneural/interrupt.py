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
        if threading_main():
            self._old = {sig: signal.signal(sig, self._handle) for sig in SIGNALS}
        return self

    def _handle(self, *_):
        if self.flag and self.second_raises:
            raise KeyboardInterrupt
        self.flag = True

    def __exit__(self, *exc):
        for sig, old in self._old.items():
            signal.signal(sig, old)
        self._old = {}


def threading_main() -> bool:
    return threading.current_thread() is threading.main_thread()
