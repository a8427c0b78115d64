"""Do this adapter's timestamps cover a pass? Checked once per process on a controlled workload.

Some adapters write a pass's timestamps at another moment than its work: on lavapipe, once a
render pass has run, the two timestamps of a compute pass are both written when the next
render pass is rasterized, so a compute pass of 100 ms reads 0.1 ms (README, "Timings").
:func:`timestamp_coverage` renders one pass of each kind after a render pass (the order of a
frame), each with a loop long enough to take a few milliseconds, and compares its timestamps with
the wall clock of the same pass submitted alone. A kind whose timestamps read less than a
third, or more than three times, of its wall time is not covered: the renderer leaves it out of
``FrameStats.gpu_ms`` and names it in ``FrameStats.untimed`` (its time is in the frame's wall
time).
"""

from __future__ import annotations

import functools
import time

import numpy as np

from vrneural.gpu.device import get_device
from vrneural.gpu.timing import GpuTimer

KINDS = ("compute", "render")
#: calibrate the workload until one pass takes at least this long (ms of wall time)
TARGET_MS = 8.0
#: agreement band of timestamps / wall time
LOW, HIGH = 1 / 3, 3.0


class _Probe:
    def __init__(self):
        import wgpu

        from vrneural.gpu.shaders import load_wgsl

        dev = self.dev = get_device()
        mod = dev.create_shader_module(code=load_wgsl("timing_probe"), label="timing_probe")
        self.cpipe = dev.create_compute_pipeline(
            layout="auto", compute={"module": mod, "entry_point": "cs_main"}
        )
        self.rpipe = dev.create_render_pipeline(
            layout="auto",
            vertex={"module": mod, "entry_point": "vs_main"},
            primitive={"topology": "triangle-list"},
            fragment={
                "module": mod,
                "entry_point": "fs_main",
                "targets": [{"format": "rgba8unorm"}],
            },
        )
        bu = wgpu.BufferUsage
        self.n = 64 * 256
        self.work = dev.create_buffer(size=16, usage=bu.UNIFORM | bu.COPY_DST)
        sink = dev.create_buffer(size=4 * self.n, usage=bu.STORAGE | bu.COPY_SRC)
        self.cbind = dev.create_bind_group(
            layout=self.cpipe.get_bind_group_layout(0),
            entries=[{"binding": 0, "resource": {"buffer": self.work}},
                     {"binding": 1, "resource": {"buffer": sink}}],
        )  # fmt: skip
        self.rbind = dev.create_bind_group(
            layout=self.rpipe.get_bind_group_layout(0),
            entries=[{"binding": 0, "resource": {"buffer": self.work}}],
        )
        tu = wgpu.TextureUsage
        tex = dev.create_texture(
            size=(128, 128, 1), format="rgba8unorm", usage=tu.RENDER_ATTACHMENT
        )
        self.view = tex.create_view()
        self.sink = sink

    def encode(self, enc, kind: str, ts=None) -> None:
        if kind == "compute":
            cp = enc.begin_compute_pass(timestamp_writes=ts)
            cp.set_pipeline(self.cpipe)
            cp.set_bind_group(0, self.cbind)
            cp.dispatch_workgroups(self.n // 64)
            cp.end()
        else:
            att = {"view": self.view, "load_op": "clear", "store_op": "store",
                   "clear_value": (0, 0, 0, 0)}  # fmt: skip
            rp = enc.begin_render_pass(color_attachments=[att], timestamp_writes=ts)
            rp.set_pipeline(self.rpipe)
            rp.set_bind_group(0, self.rbind)
            rp.draw(3)
            rp.end()

    def wall_ms(self, kind: str) -> float:
        """One pass submitted alone, from submit to the GPU's completion (ms)."""
        enc = self.dev.create_command_encoder()
        self.encode(enc, kind)
        t0 = time.perf_counter()
        self.dev.queue.submit([enc.finish()])
        self.dev.queue.read_buffer(self.sink, 0, 16)  # waits for the queue
        return (time.perf_counter() - t0) * 1e3

    def set_iterations(self, n: int) -> None:
        self.dev.queue.write_buffer(self.work, 0, np.array([n, 0, 0, 0], np.uint32))

    def measure(self, kind: str) -> dict:
        it = 16
        self.set_iterations(it)
        self.wall_ms(kind)  # compile, warm up
        while True:
            self.set_iterations(it)
            wall = self.wall_ms(kind)
            if wall >= TARGET_MS or it >= 1 << 22:
                break
            it *= 2 if wall > TARGET_MS / 8 else 8
        timer = GpuTimer(2)
        enc = self.dev.create_command_encoder()
        self.encode(enc, "render")  # as in a frame: a render pass has run before
        enc2 = self.dev.create_command_encoder()
        self.encode(enc2, kind, timer.writes(kind))
        timer.resolve(enc2)
        self.dev.queue.submit([enc.finish(), enc2.finish()])
        ts = timer.read().get(kind, 0.0)
        wall = min(wall, self.wall_ms(kind))
        return {"timestamp_ms": ts, "wall_ms": wall, "iterations": it,
                "covered": bool(LOW <= ts / max(wall, 1e-9) <= HIGH)}  # fmt: skip


@functools.cache
def coverage_report() -> dict:
    """Per pass kind (``compute``, ``render``): its timestamps and wall time on the controlled
    workload and whether they agree (``covered``); ``{}`` without the timestamp-query
    feature."""
    if "timestamp-query" not in get_device().features:
        return {}
    p = _Probe()
    p.wall_ms("render")  # the state of the adapter in a frame: a render pass has run
    return {k: p.measure(k) for k in KINDS}


def timestamp_coverage() -> dict[str, bool]:
    """``{"compute": bool, "render": bool}``: whether timestamps cover each kind of pass
    (False for both without timestamps)."""
    rep = coverage_report()
    return {k: bool(rep.get(k, {}).get("covered", False)) for k in KINDS}
