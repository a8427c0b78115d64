"""Do this adapter's timestamps cover the renderer's passes? Checked on the renderer itself.

Some adapters write a pass's timestamps at another moment than its work. On lavapipe a
timestamp lands in llvmpipe's current render scene and is written when that scene is flushed:
a compute pass that touches nothing the scene uses (a bare kernel of direct dispatches, say)
reads ~0.1 ms for 100 ms of work, while one that reads a texture (which flushes the scene)
is timed right. Whether a pass is covered thus depends on what it binds, so it is checked on
the renderer's own passes, once, right after its first frame: each pass timed by timestamps
inside one frame-like submit, and submitted alone by the wall clock (minus the cost of an empty
submit). A pass whose timestamps read less than a third, or more than three times, of its
wall time is *untimed*: left out of ``FrameStats.gpu_ms`` and named in ``FrameStats.untimed``
(its time is in the frame's wall time; ``Renderer.pass_clock = "wall"`` times it alone).
"""

from __future__ import annotations

import numpy as np

from vrneural.gpu.timing import GpuTimer

LOW, HIGH = 1 / 3, 3.0  # agreement band of timestamps / wall time
#: a pass shorter than this (ms, wall minus an empty submit) cannot be judged on a busy machine:
#: taken as covered
MIN_MS = 2.0


def _wall(r, encode) -> float:
    enc = r.dev.create_command_encoder()
    encode(enc, None)
    return r._submit_and_wait(enc)


def _passes(r) -> dict:
    """name -> encode(enc, timer): the renderer's passes with its last frame's uniforms (the
    texture pass as a full update)."""
    eyes, lp, lc = r._last
    out = {}
    if r.s.mode == "texture" and r.neural:
        # the objects the frame updated in full (one out of view is left as it is)
        todo = [(k, n, 0, 1) for k, n in enumerate(r.neural) if n.fresh]

        def texture(enc, timer):
            cp = enc.begin_compute_pass(timestamp_writes=timer and timer.writes("texture"))
            r._dispatch_updates(cp, todo, eyes, lp, lc)
            cp.end()

        out["texture"] = texture

    def forward(enc, timer):
        r.encode_forward(enc, None, None, "forward", timer or _NoTimer())

    out["forward"] = forward
    if r.s.mode != "texture":

        def screen(enc, timer):
            for e in range(r.s.eyes):
                cp = enc.begin_compute_pass(timestamp_writes=timer and timer.writes("screen"))
                for n in r.neural:
                    n.targets[e].dispatch(cp)
                cp.end()

        out["screen"] = screen
    return out


class _NoTimer:
    def writes(self, name):
        return None


def check_timestamps(r, repeats: int = 3) -> dict:
    """Per pass of renderer ``r`` (after its first frame): ``{timestamp_ms, wall_ms,
    overhead_ms, covered}`` (medians over ``repeats``); ``{}`` without timestamps. Judged in
    favour of the timestamps (the largest against the smallest wall time and the other way
    round): timestamps that miss a pass are off by 10-100x, the noise of a busy machine by
    less."""
    if not r.timer.enabled:
        return {}
    r.wait()
    passes = _passes(r)
    empty = float(np.median([_wall(r, lambda enc, t: None) for _ in range(3)]))
    walls: dict = {k: [] for k in passes}
    stamps: dict = {k: [] for k in passes}
    timer = GpuTimer(4 * r.s.eyes + 4)
    for _ in range(repeats):
        enc = r.dev.create_command_encoder()
        r.counters.clear(enc)
        for enc_pass in passes.values():  # as in a frame: one submit, in the frame's order
            enc_pass(enc, timer)
        timer.resolve(enc)
        r.arena.flush()
        r.dev.queue.submit([enc.finish()])
        ts = timer.read()
        for k, fn in passes.items():
            stamps[k].append(ts.get(k, 0.0))
            walls[k].append(_wall(r, fn))
    out = {}
    for k in passes:
        ts, wall = float(np.median(stamps[k])), float(np.median(walls[k]))
        work = max(min(walls[k]) - empty, 0.0)
        covered = work < MIN_MS or (
            LOW * work <= max(stamps[k]) and min(stamps[k]) <= HIGH * max(walls[k])
        )
        out[k] = {"timestamp_ms": ts, "wall_ms": wall, "overhead_ms": empty, "covered": covered}
    return out
