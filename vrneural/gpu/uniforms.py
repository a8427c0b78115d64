"""One uniform buffer for many bindings, written once per frame.

Every per-frame uniform of the renderer (each texture target's ``Params`` and lights, each
eye's frame and lights, each screen target's) lives in one :class:`UniformArena`: a region per
binding at a fixed, aligned offset of one GPU buffer, mirrored by a host byte array. Writers
fill their regions on the host; :meth:`UniformArena.flush` sends the changed span with one
``queue.write_buffer`` before the frame's submit. ``write_buffer`` is ordered on the queue, so
frames still in flight read the values they were submitted with.
"""

from __future__ import annotations

import numpy as np

from vrneural.gpu.device import get_device


class UniformArena:
    """Regions of one uniform buffer. :meth:`alloc` hands out offsets until the first
    :meth:`binding` creates the buffer (no allocation after that); ``auto_flush``: writers'
    :meth:`written` sends their values at once (a target used on its own, outside a frame)."""

    def __init__(self, label: str = "uniforms", auto_flush: bool = False):
        self.label = label
        self.auto_flush = auto_flush
        self.align = int(get_device().limits.get("min-uniform-buffer-offset-alignment", 256))
        self.size = 0
        self.buf = None
        self.host: np.ndarray | None = None  # [size] uint8, the buffer's contents
        self.lo, self.hi = None, 0  # the span written since the last flush (bytes)

    def alloc(self, nbytes: int) -> int:
        """A region of ``nbytes`` (offset aligned for a uniform binding); returns its offset."""
        if self.buf is not None:
            raise RuntimeError(f"{self.label}: alloc after the buffer was created")
        off = -(-self.size // self.align) * self.align
        self.size = off + max(16, -(-nbytes // 16) * 16)
        return off

    def _create(self) -> None:
        import wgpu

        u = wgpu.BufferUsage.UNIFORM | wgpu.BufferUsage.COPY_DST | wgpu.BufferUsage.COPY_SRC
        self.buf = get_device().create_buffer(size=max(self.size, 16), usage=u, label=self.label)
        self.host = np.zeros(max(self.size, 16), np.uint8)

    def binding(self, offset: int, nbytes: int) -> dict:
        """A bind-group resource for the region at ``offset`` (creates the buffer on first
        use)."""
        if self.buf is None:
            self._create()
        return {"buffer": self.buf, "offset": offset, "size": -(-nbytes // 16) * 16}

    def view(self, offset: int, nbytes: int, dtype=np.float32) -> np.ndarray:
        """The host copy of a region as a writable ``dtype`` array (marks it written)."""
        if self.buf is None:
            self._create()
        self._mark(offset, nbytes)
        return self.host[offset : offset + nbytes].view(dtype)

    def words(self, offset: int, nbytes: int) -> np.ndarray:
        """The host copy of a region as float32 words, for a writer that keeps the view and
        fills it each frame (a view of :attr:`host`, which is never replaced); the writer
        calls :meth:`mark` after writing."""
        if self.buf is None:
            self._create()
        return self.host[offset : offset + nbytes].view(np.float32)

    def mark(self, offset: int, nbytes: int) -> None:
        """A region of :meth:`words` was written: it goes with the next :meth:`flush`."""
        self._mark(offset, nbytes)

    def _mark(self, offset: int, nbytes: int) -> None:
        self.lo = offset if self.lo is None else min(self.lo, offset)
        self.hi = max(self.hi, offset + nbytes)

    def written(self) -> None:
        """A writer has filled its regions: sent now when ``auto_flush``, else with the
        frame's :meth:`flush`."""
        if self.auto_flush:
            self.flush()

    def flush(self) -> None:
        """Send what was written since the last flush (one ``write_buffer``)."""
        if self.lo is None:
            return
        lo, hi = self.lo & ~3, -(-self.hi // 4) * 4
        get_device().queue.write_buffer(self.buf, lo, self.host, lo, hi - lo)
        self.lo, self.hi = None, 0
