"""GPU timestamps per pass, converted to milliseconds on any adapter.

wgpu-native resolves raw ticks; ``wgpuQueueGetTimestampPeriod`` gives nanoseconds per tick
(1.0 on most Vulkan drivers, other values elsewhere). We multiply by it, so figures are ms.
"""

from __future__ import annotations

import functools

import numpy as np

from vrneural.gpu.device import get_device


@functools.cache
def timestamp_period_ns() -> float:
    """Nanoseconds per timestamp tick for the default device's queue."""
    dev = get_device()
    try:
        from wgpu.backends.wgpu_native._api import libf

        period = float(libf.wgpuQueueGetTimestampPeriod(dev.queue._internal))
    except Exception:  # another backend, or the symbol moved: WebGPU says ticks are ns
        period = 1.0
    return period if period > 0 else 1.0


class GpuTimer:
    """Collect begin/end timestamps of named passes within command encoders.

    Usage::

        timer = GpuTimer(max_passes=16)
        pass_ = encoder.begin_compute_pass(timestamp_writes=timer.writes("shade"))
        ...
        timer.resolve(encoder)   # once per submission, after the passes
        queue.submit([encoder.finish()])
        ms = timer.read()        # {"shade": 0.42, ...}; sums repeats of a name

    When the device lacks ``timestamp-query`` it is disabled: ``writes`` returns None and
    ``read`` returns an empty dict, so callers need no special cases.
    """

    def __init__(self, max_passes: int = 32):
        import wgpu

        self.dev = get_device()
        self.enabled = "timestamp-query" in self.dev.features
        self.max = max_passes
        self.names: list[str] = []
        if self.enabled:
            self.qs = self.dev.create_query_set(type="timestamp", count=2 * max_passes)
            self.resolve_buf = self.dev.create_buffer(
                size=16 * max_passes,
                usage=wgpu.BufferUsage.QUERY_RESOLVE | wgpu.BufferUsage.COPY_SRC,
            )

    def writes(self, name: str) -> dict | None:
        """``timestamp_writes`` for the next pass, or None when timing is off or full."""
        if not self.enabled or len(self.names) >= self.max:
            return None
        i = len(self.names)
        self.names.append(name)
        return {
            "query_set": self.qs,
            "beginning_of_pass_write_index": 2 * i,
            "end_of_pass_write_index": 2 * i + 1,
        }

    def resolve(self, encoder) -> None:
        if self.enabled and self.names:
            encoder.resolve_query_set(self.qs, 0, 2 * len(self.names), self.resolve_buf, 0)

    @property
    def nbytes(self) -> int:
        """Bytes of resolved timestamps :meth:`resolve_into` copies at most."""
        return 16 * self.max if self.enabled else 0

    def resolve_into(self, encoder, dst, offset: int = 0) -> list[str]:
        """Resolve this encoding's timestamps and copy them to ``dst`` at ``offset`` (a
        persistent read-back buffer, inside the frame's own submit); returns the pass names
        in order (for :meth:`decode`) and resets for the next encoding."""
        names, self.names = self.names, []
        if self.enabled and names:
            n = 2 * len(names)
            encoder.resolve_query_set(self.qs, 0, n, self.resolve_buf, 0)
            encoder.copy_buffer_to_buffer(self.resolve_buf, 0, dst, offset, 8 * n)
        return names

    @staticmethod
    def decode(raw, names: list[str]) -> dict[str, float]:
        """Milliseconds per pass name (summed over repeats) from resolved ticks ``raw`` (bytes
        or uint8 array, at least ``16 * len(names)`` long)."""
        if not names:
            return {}
        ticks = np.frombuffer(raw, np.uint64, 2 * len(names)).astype(np.int64)
        dt = (ticks[1::2] - ticks[0::2]).clip(min=0) * timestamp_period_ns() * 1e-6
        out: dict[str, float] = {}
        for n, t in zip(names, dt, strict=True):
            out[n] = out.get(n, 0.0) + float(t)
        return out

    def read(self) -> dict[str, float]:
        """Milliseconds per pass name (summed over repeats); resets for the next use."""
        names, self.names = self.names, []
        if not self.enabled or not names:
            return {}
        return self.decode(self.dev.queue.read_buffer(self.resolve_buf), names)
