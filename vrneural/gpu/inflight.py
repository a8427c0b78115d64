"""Frames in flight: per-frame results read back without waiting for the GPU.

A :class:`ReadbackRing` holds one persistent ``MAP_READ`` buffer per frame in flight. A frame's
own command buffer copies what it wants back (resolved timestamps, counters) into its slot; the
slot is mapped right after the submit and read when the slot comes round again (``depth``
frames later) or when a caller waits. Nothing is allocated per frame, and the host waits only
when it is ``depth`` frames ahead of the GPU.
"""

from __future__ import annotations

from vrneural.gpu.device import get_device


def _map_read(buf):
    """Start mapping ``buf`` for reading. wgpu-py's plain "READ" submits an empty command
    buffer first (a wgpu-native workaround for buffers never written by the GPU); ours always
    were, in the submit before, so its internal "READ_NOSYNC" mode is used where it exists."""
    try:
        return buf.map_async("READ_NOSYNC")
    except (ValueError, KeyError, TypeError):  # a wgpu-py without that mode
        return buf.map_async("READ")


class ReadbackRing:
    """``depth`` buffers (``frames_in_flight``, checked by the renderer) of ``nbytes`` each;
    slot ``i`` carries the payload it was submitted with until :meth:`take` hands both back."""

    def __init__(self, nbytes: int, depth: int, label: str = "readback"):
        import wgpu

        dev = get_device()
        u = wgpu.BufferUsage.MAP_READ | wgpu.BufferUsage.COPY_DST
        self.nbytes = max(16, -(-nbytes // 16) * 16)
        self.depth = depth
        self.bufs = [
            dev.create_buffer(size=self.nbytes, usage=u, label=f"{label}/{i}") for i in range(depth)
        ]
        self.promises: list = [None] * depth
        self.payloads: list = [None] * depth

    def busy(self, slot: int) -> bool:
        """Whether slot ``slot`` holds a submitted frame not yet taken."""
        return self.promises[slot] is not None

    def ready(self, slot: int) -> bool:
        """Whether slot ``slot``'s frame has finished on the GPU (its map completed)."""
        p = self.promises[slot]
        return p is not None and getattr(p, "_state", "pending") != "pending"

    def submitted(self, slot: int, payload) -> None:
        """Call right after the submit whose commands copy into ``self.bufs[slot]``."""
        self.promises[slot] = _map_read(self.bufs[slot])
        self.payloads[slot] = payload

    def take(self, slot: int) -> tuple[object, bytes]:
        """Wait for slot ``slot``'s frame, copy its bytes out and free the slot: returns
        ``(payload, bytes [nbytes])``."""
        self.promises[slot].sync_wait()
        buf = self.bufs[slot]
        out = bytes(buf.read_mapped(copy=False))
        buf.unmap()
        payload = self.payloads[slot]
        self.promises[slot] = self.payloads[slot] = None
        return payload, out
