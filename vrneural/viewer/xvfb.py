"""A virtual X display (Xvfb) for the window tests, the viewer benchmark and the docs'
screenshot: a real X server, so glfw opens a real window and lavapipe presents to a real X11
surface; only the monitor is missing."""

from __future__ import annotations

import contextlib
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator

from vrneural.errors import VrnError

INSTALL = "apt-get install -y xvfb"


def on_a_display(fn, width: int = 2200, height: int = 1400):
    """``fn()`` on the display there is, or on a virtual one of ``width x height`` (Xvfb)
    while there is none."""
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return fn()
    with virtual_display(width, height):
        return fn()


@contextlib.contextmanager
def virtual_display(width: int = 2200, height: int = 1400) -> Iterator[str]:
    """Start ``Xvfb`` on a free display number (it picks one: ``-displayfd``), set
    ``DISPLAY`` to it for the block, stop it after; yields the display name (``":99"``)."""
    exe = shutil.which("Xvfb")
    if exe is None:
        raise VrnError(f"Xvfb is not installed ({INSTALL})")

    r, w = os.pipe()
    log = tempfile.TemporaryFile()  # Xvfb's messages (read only when it fails to start)
    proc = subprocess.Popen(
        [exe, "-displayfd", str(w), "-screen", "0", f"{width}x{height}x24", "-nolisten", "tcp"],
        pass_fds=(w,),
        stdout=subprocess.DEVNULL,
        stderr=log,
    )
    os.close(w)
    try:
        number = _read_display(r, proc, log)
        old = os.environ.get("DISPLAY")
        os.environ["DISPLAY"] = f":{number}"
        try:
            yield f":{number}"
        finally:
            # glfw's X connection goes before its server (else Xlib's fatal-error handler ends
            # the process at exit); rendercanvas initialises glfw again for its next window
            glfw = sys.modules.get("glfw")
            if glfw is not None:
                glfw.terminate()
                glfw._rc_alive = False  # rendercanvas's flag: no polling of a terminated glfw
            if old is None:
                os.environ.pop("DISPLAY", None)
            else:
                os.environ["DISPLAY"] = old
    finally:
        os.close(r)
        log.close()
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _read_display(fd: int, proc, log, timeout: float = 30.0) -> int:
    """The display number Xvfb writes to ``fd`` once it accepts connections."""
    buf = b""
    end = time.monotonic() + timeout
    while not buf.endswith(b"\n"):
        left = end - time.monotonic()
        if left <= 0 or proc.poll() is not None:
            log.seek(0)
            err = log.read().decode(errors="replace").strip().splitlines()
            raise VrnError(f"Xvfb did not start ({err[-1] if err else 'timed out'})")
        ready, _, _ = select.select([fd], [], [], min(left, 0.5))
        if ready:
            chunk = os.read(fd, 64)
            if not chunk:
                continue
            buf += chunk
    return int(buf.strip())
