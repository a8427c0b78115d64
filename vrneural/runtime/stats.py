"""Frame statistics that arrive after the frame: :class:`FrameStats` and the read-back ring
that fills them in (:class:`FrameResults`).

:meth:`Renderer.frame <vrneural.runtime.renderer.Renderer.frame>` returns as soon as the frame
is submitted. Its counters and timestamps travel back in the frame's own command buffer into a
persistent ``MAP_READ`` buffer (:class:`~vrneural.gpu.inflight.ReadbackRing`) and are decoded
when the renderer next finds the frame finished (a later frame reusing its slot, or
:meth:`FrameResults.wait`); reading one of them earlier waits for that frame.
"""

from __future__ import annotations

import time

import numpy as np

from vrneural.gpu.inflight import ReadbackRing
from vrneural.gpu.timing import GpuTimer

#: the fields known once the GPU has finished the frame
GPU_FIELDS = (
    "wall_ms",
    "gpu_ms",
    "blocks_shaded",
    "blocks_backfacing",
    "mlp_coarse",
    "mlp_fine",
    "pixels_shaded",
    "object_blocks",
)


class FrameStats:
    """What one :meth:`Renderer.frame` did. Frame 0 includes shader compilation: leave it out
    of timings.

    Known at once: ``frame``, ``updated_objects``, ``culled_objects``, ``host_ms``, ``cpu_ms``,
    ``in_flight``, ``untimed``. Known when the GPU has finished the frame (:attr:`ready`; reading
    one before waits for it): ``wall_ms``, ``gpu_ms`` and the counters."""

    frame: int  #: the frame index
    #: wall time of the frame in a loop rendering frames back to back: from the start of its
    #: ``frame()`` to the start of the next (1000 / FPS), or to the end of a wait for its
    #: results when that came first; the caller's own work between frames counts
    wall_ms: float
    #: GPU ms per pass name (texture, forward; screen in the screen modes), both eyes summed,
    #: from timestamps; only the passes this adapter's timestamps cover (see ``untimed``)
    gpu_ms: dict
    updated_objects: int  #: neural objects whose radiance textures were updated (texture mode)
    culled_objects: int  #: neural objects outside every eye's view, not updated
    blocks_shaded: int  #: 2x2 texel blocks shaded (texture mode)
    blocks_backfacing: int  #: blocks skipped as facing away from the eye (texture mode)
    mlp_coarse: int  #: coarse-network evaluations (per block; per pixel in screen modes)
    mlp_fine: int  #: fine-network evaluations (per texel; per pixel in screen modes)
    pixels_shaded: int  #: pixels shaded per pixel (screen and reference modes)
    host_ms: float  #: main-thread wall time inside ``frame()`` (encoding, submit, ring waits)
    cpu_ms: float  #: main-thread CPU time inside ``frame()``
    in_flight: int  #: frames submitted before this one and not yet finished on the GPU
    #: passes run but left out of ``gpu_ms``: this adapter's timestamps do not cover them
    #: (runtime/timecheck.py); their time is in ``wall_ms``
    untimed: tuple
    #: what ``gpu_ms`` was measured with: "timestamps", or "wall" (``Renderer.pass_clock``:
    #: each pass submitted alone and waited for, from submit to completion)
    clock: str

    def __init__(self, frame: int, updated: int, culled: int, untimed: tuple, waiter=None):
        self.frame = frame
        #: per neural object (texture mode; known at once): its radiance texture side and the
        #: texels allocated for it (all eyes); the footprint scale of its neural-texture lookups
        #: at its last update (Settings.lod_footprint); ``object_blocks`` (a GPU field): the 2x2
        #: blocks shaded for it this frame
        self.object_res: list = []
        self.object_texels: list = []
        self.object_lod_scale: list = []
        self.updated_objects = updated
        self.culled_objects = culled
        self.untimed = untimed
        self.host_ms = self.cpu_ms = 0.0
        self.in_flight = 0
        self.clock = "timestamps"
        self._waiter = waiter
        self._start = 0.0
        self._end: float | None = None
        #: the read-back bytes (timestamps, then ``slots x 4`` u32 counters), the timed pass
        #: names, the timestamps' bytes, screen counters?, per-pass wall ms (``pass_clock``
        #: "wall") or None: decoded when a GPU field is first read
        self._raw = None

    def __getattr__(self, name: str):
        if name in GPU_FIELDS:
            d = self.__dict__
            if d.get("_waiter") is not None:
                d["_waiter"](self)
            if d.get("_raw") is not None:
                self._decode()
            if name in d:
                return d[name]
        raise AttributeError(f"{type(self).__name__} has no attribute {name!r}")

    @property
    def ready(self) -> bool:
        """Whether the GPU fields are in (reading them does not wait)."""
        return self.__dict__.get("_waiter") is None

    def _decode(self) -> None:
        raw, names, ts_bytes, screen, wall = self._raw
        slots = np.frombuffer(raw, np.uint32, offset=ts_bytes).reshape(-1, 4)
        c = [int(x) for x in slots.sum(0, dtype=np.int64)]
        gpu = dict(wall) if wall is not None else GpuTimer.decode(raw[:ts_bytes], names)
        for k in self.untimed:
            gpu.pop(k, None)
        d = self.__dict__
        d["gpu_ms"] = gpu
        d["wall_ms"] = (self._end - self._start) * 1e3
        # the screen kernels count (pixels, backfacing, coarse, fine)
        d["pixels_shaded"], d["blocks_shaded"] = (c[0], 0) if screen else (0, c[0])
        d["blocks_backfacing"], d["mlp_coarse"], d["mlp_fine"] = c[1:]
        # per neural object (texture mode): the blocks shaded for it, its eyes' slots summed
        n, eyes = d.get("_objects", (0, 1))
        d["object_blocks"] = [int(b) for b in slots[: n * eyes, 0].reshape(n, eyes).sum(1)]
        self._raw = None

    def __repr__(self) -> str:
        gpu = {k: self.__dict__[k] for k in GPU_FIELDS if k in self.__dict__}
        return (
            f"FrameStats(frame={self.frame}, updated_objects={self.updated_objects}, "
            f"culled_objects={self.culled_objects}, host_ms={self.host_ms:.3f}, "
            f"in_flight={self.in_flight}, "
            + (", ".join(f"{k}={v!r}" for k, v in gpu.items()) if gpu else "pending")
            + ")"
        )


class FrameResults:
    """The read-back of a renderer's frames: ``depth`` slots, each carrying one frame's
    resolved timestamps and counters (``slots x 4`` u32) and its :class:`FrameStats`."""

    def __init__(self, timer: GpuTimer, counters, depth: int, screen: bool):
        self.timer = timer
        self.counters = counters
        self.screen = screen  # counters mean (pixels, backfacing, coarse, fine) there
        self.ts_bytes = timer.nbytes
        self.cnt_bytes = 16 * counters.slots
        self.ring = ReadbackRing(self.ts_bytes + self.cnt_bytes, depth, "frame results")
        self.next_slot = 0
        self.last: FrameStats | None = None  # the frame started last (its wall_ms is open)
        self.latest: FrameStats | None = None  # the newest frame whose results are in

    @property
    def depth(self) -> int:
        return self.ring.depth

    def begin(self) -> int:
        """At the start of a frame: close the previous frame's wall interval, take in every
        finished frame (waiting for the one in the slot this frame needs); returns the slot."""
        now = time.perf_counter()
        if self.last is not None and self.last._end is None:
            self.last._end = now
        slot = self.next_slot
        if self.ring.busy(slot):
            self._take(slot)
        self.poll()
        return slot

    def poll(self) -> None:
        """Take in the frames that have finished, oldest first, without waiting."""
        for k in range(1, self.depth + 1):
            s = (self.next_slot + k) % self.depth
            if self.ring.ready(s):
                self._take(s)

    def in_flight(self) -> int:
        return sum(self.ring.busy(s) for s in range(self.depth))

    def copy_into(self, encoder, slot: int) -> list[str]:
        """In the frame's encoder, after its passes: its timestamps and counters into
        ``slot``; returns the timed pass names."""
        names = self.timer.resolve_into(encoder, self.ring.bufs[slot], 0)
        encoder.copy_buffer_to_buffer(
            self.counters.buf, 0, self.ring.bufs[slot], self.ts_bytes, self.cnt_bytes
        )
        return names

    def submitted(self, slot: int, st: FrameStats, names: list[str], wall=None) -> None:
        st._waiter = self._wait_for
        self.ring.submitted(slot, (st, names, wall))
        self.last = st
        self.next_slot = (slot + 1) % self.depth

    def _wait_for(self, st: FrameStats | None) -> None:
        """Take in frames, oldest first, until ``st`` is in (None: every submitted one)."""
        for k in range(self.depth):
            s = (self.next_slot + k) % self.depth
            if self.ring.busy(s):
                self._take(s)
            if st is not None and st.ready:
                return

    def wait(self) -> None:
        """Take in every submitted frame (waits for the GPU to finish them)."""
        self._wait_for(None)

    def _take(self, slot: int) -> None:
        (st, names, wall), raw = self.ring.take(slot)
        if st._end is None:
            st._end = time.perf_counter()
        st._raw, st._waiter = (raw, names, self.ts_bytes, self.screen, wall), None
        self.latest = st  # frames are taken in the order they were submitted
