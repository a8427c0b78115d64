"""`vrneural bench frame`: where a frame's time goes, against the adapter's floors, in one run.

The benchmark scene (:func:`vrneural.bench.timing.bench_scene`: two neural objects and a plain
floor) rendered by one renderer per colour target. Measured in interleaved rounds, so a slow
spell of a shared machine hits every condition:

- the frame loop with 1, 2 and 3 frames in flight: wall time per frame (frames back to back),
  host CPU per frame (main thread: ``frame()`` and reading its statistics) and frames queued;
- each pass on its own (submitted alone, from submit to completion: wall clock, the CPU time of
  all of this process's threads, and GPU timestamps where this adapter's cover the pass,
  runtime/timecheck.py; a CPU adapter's passes are compared by their CPU time, others by
  timestamps or the wall clock): a full texture-space update,
  a staggered frame's update, the forward pass of both eyes (HDR and the 8-bit display target);
- the floors over the same geometry, targets and candidates: a constant-colour forward pass, a
  forward pass doing one bilinear sample per fragment and nothing else, the raster floor (one
  constant-colour triangle over each eye's viewport, the same clears: every pixel covered once)
  against a compute pass storing the same texels (``colour_store``: the adapter's render
  back end against the whole chip; on an NVIDIA H200 the one was 30x the other by timestamps,
  docs/results/h200/raster_floor.py), and the bare
  texture-space kernel (the same facing test, geometry records read and texels stored; no
  shading), alone and with the neural-texture lookups at the blocks' texels (``texture_loads``:
  the traffic any shading of them needs);
- the runtime's neural-texture filtering ("hardware": the sampler's) against the exact
  float32 filter in the shader (``*_exact``: the full and staggered updates and the loads floor).

With ``--parallax-steps S`` the same rounds also time the texture-space update of the same two
materials with height-field parallax of up to S steps, marched per texel, once per 2x2 block and
``auto`` (per block where a block spans at most one texel of the height field: the runtime's
default; the share of blocks that take that route is reported) (a renderer each; issue #44's
target: at most 1.5x the update without it); with ``--neural-offset`` those materials with
NeuMIP's neural offset module instead of a height field, with the same three marches.

Ratios: forward / one-sample floor (target <= 1.15), full update / bare kernel (<= 1.5),
wall per frame / max(host CPU, GPU) with frames in flight (<= 1.1; GPU = the passes' times
summed, amortised as the frame loop runs them).
"""

from __future__ import annotations

import time

import numpy as np

from vrneural.bench import report as rp
from vrneural.bench import timing
from vrneural.bench.configs import FrameConfig
from vrneural.bench.frame_report import markdown, plot, summarise
from vrneural.errors import check_range
from vrneural.gpu.device import poll_thread_cpu
from vrneural.runtime.config import LIGHTS_MAX, REUSE_MAX, parse_res
from vrneural.runtime.lights import light_arrays
from vrneural.runtime.profiles import get_profile

#: the texture-space pass's marches each parallax kind is timed with (``--parallax-march``)
MARCHES = ("texel", "block", "auto")
TARGETS = {
    "forward_vs_sample_floor": 1.15,
    "texture_vs_bare": 1.5,
    "wall_vs_bound": 1.1,
    "parallax_vs_texture": 1.5,
    "parallax_block_vs_texture": 1.5,
    "parallax_auto_vs_texture": 1.5,
}


def time_passes(r, encode, repeats: int) -> dict:
    """``encode(enc, timer)`` records one pass (or a set of passes timed together) into a
    fresh encoder; submitted alone ``repeats`` times: ``{"wall_ms", "cpu_ms",
    "timestamp_ms"}`` (medians; ``cpu_ms``: the CPU time of every thread of this process from
    submit to completion, on a CPU adapter the pass's work; the timestamps summed over the
    passes it timed, None without them)."""
    from vrneural.gpu.timing import GpuTimer

    walls, cpus, stamps = [], [], []
    timer = GpuTimer(8)
    for i in range(repeats + 1):  # the first: warm-up (pipelines compiled at first use)
        enc = r.dev.create_command_encoder()
        encode(enc, timer)
        timer.resolve(enc)
        r.arena.flush()
        t0, c0 = time.perf_counter(), time.process_time()
        r.dev.queue.submit([enc.finish()])
        r.dev.queue.read_buffer(r.counters.buf, 0, 16)  # a copy after everything: waits for it
        c1 = time.process_time()
        ts = timer.read()
        if i:
            walls.append((time.perf_counter() - t0) * 1e3)
            cpus.append((c1 - c0) * 1e3)
            stamps.append(sum(ts.values()) if ts else None)
    ok = [t for t in stamps if t is not None]
    return {
        "wall_ms": float(np.median(walls)),
        "cpu_ms": float(np.median(cpus)),
        "timestamp_ms": float(np.median(ok)) if ok else None,
    }


def texture_update(r, entry: str, phase: int, period: int, f: int):
    """An encoder callback: every neural object's update of rows ``phase::period`` for every
    radiance texture, at frame ``f``'s eyes and lights, in one compute pass (``entry``:
    ``main``, the pass; ``bare``, its floor)."""
    eyes = r.eyes_at(f)
    lp, lc = light_arrays(r.lights, f / r.s.fps)

    def encode(enc, timer) -> None:
        cp = enc.begin_compute_pass(timestamp_writes=timer.writes("texture"))
        bound = None
        for k, n in enumerate(r.neural):
            tiling = (n.desc.material.tiling,) * 2 + (0.0, 0.0)
            for e, ((pos, margin), tgt) in enumerate(
                zip(r._shading_eyes(eyes), n.targets, strict=True)
            ):
                tgt.update(n.desc.model, pos, tiling, lp, lc, phase, period, k * r.s.eyes + e,
                           margin, n.lod_scale)  # fmt: skip
                bound = tgt.dispatch(cp, phase, period, entry, bound)
        cp.end()

    return encode


def forward(r, bundles=None):
    """An encoder callback: the eyes' forward passes (in mode texture one pass, the eyes side
    by side; ``bundles``: a floor's draws)."""

    def encode(enc, timer) -> None:
        r.encode_forward(enc, None, bundles, "forward", timer)

    return encode


def screen_floor_bundles(r) -> list:
    """Per eye, a render bundle drawing one triangle over its viewport in a constant colour
    (forward.screen_floor_pipeline): every pixel covered once, the raster floor of the
    adapter over these targets."""
    from vrneural.runtime import forward as fw

    out = []
    for et in r.eye_t:
        enc = fw.bundle_encoder(et)
        enc.set_pipeline(fw.screen_floor_pipeline(et.n_lights, et.format, et.samples))
        enc.draw(3)
        out.append(enc.finish())
    return out


def colour_store(r):
    """An encoder callback: the compute pass that stores black in every texel of the eyes'
    colour target (forward.clear_colour): the same texels written by the whole chip."""
    from vrneural.runtime import forward as fw

    def encode(enc, timer) -> None:
        fw.clear_colour(enc, r.eye_t[0], timer.writes("colour_store"))

    return encode


def floor_bundles(r, fragment: str) -> list:
    """Per eye, a render bundle of the renderer's draws with every fragment entry point
    replaced by ``fragment`` (``fs_floor_constant``, ``fs_floor_sample``)."""
    from vrneural.runtime import forward as fw

    return [fw.record_bundle(et, r.draw_list(e, et, fragment)) for e, et in enumerate(r.eye_t)]


def loop(r, frames: int, f0: int) -> dict:
    """``frames`` frames back to back from ``f0`` (reading each one's statistics as they come
    back, as `run` does); per frame: wall, host CPU (main thread; and wgpu-py's device-poll
    thread, :func:`~vrneural.gpu.device.poll_thread_cpu`), frames queued."""
    sts = []
    c0, t0, p0 = time.thread_time(), time.perf_counter(), poll_thread_cpu()
    for f in range(f0, f0 + frames):
        sts.append(r.frame(f))
        latest = r.latest_stats()
        if latest is not None:
            latest.blocks_shaded  # noqa: B018 (decoded here: its cost counts as host work)
    r.wait()
    for st in sts:
        st.mlp_fine  # noqa: B018
    wall = (time.perf_counter() - t0) * 1e3 / frames
    cpu = (time.thread_time() - c0) * 1e3 / frames
    p1 = poll_thread_cpu()
    return {
        "wall_ms": wall,
        "host_cpu_ms": cpu,
        **({"poll_cpu_ms": (p1 - p0) * 1e3 / frames} if p1 is not None else {}),
        "host_ms": float(np.mean([st.host_ms for st in sts])),
        "in_flight": float(np.mean([st.in_flight for st in sts])),
        "blocks_per_frame": float(np.mean([st.blocks_shaded for st in sts])),
    }


def _renderer(scene, c, eye_res, target: str, depth: int = 2, march: str = "pack",
              neural_filter: str = "hardware"):  # fmt: skip
    prof = get_profile("quest3")
    r = timing.make_renderer(scene, eyes=2, reuse=c.reuse, texture_res=c.texture_res,
                             eye_res=eye_res, fps=prof.fps, fov_y=prof.fov_y, n_lights=c.lights,
                             schedule="staggered", frames_in_flight=depth, target=target,
                             parallax_march=march, neural_filter=neural_filter)  # fmt: skip
    r.wait()
    return r


def run_frame(cfg: FrameConfig) -> dict:
    c = cfg.resolved()
    rp.check_texture_res(c.texture_res)
    check_range("--reuse", c.reuse, 0, REUSE_MAX)
    check_range("--lights", c.lights, 1, LIGHTS_MAX)
    check_range("--frames", c.frames, 2, 10000)
    check_range("--repeats", c.repeats, 1, 100)
    check_range("--rounds", c.rounds, 1, 100)
    check_range("--parallax-steps", c.parallax_steps, 0, 64)
    eye_res = parse_res(c.eye_res)
    with rp.prepare_out(cfg.out, cfg.force, "frame") as root:
        t0 = time.perf_counter()
        doc = rp.header("frame", c)
        scene = timing.bench_scene(c.lights)
        hdr = _renderer(scene, c, eye_res, "hdr")
        disp = _renderer(scene, c, eye_res, "display")
        exact = _renderer(scene, c, eye_res, "hdr", neural_filter="exact")  # the other filter
        doc["timestamp_check"] = hdr.timestamp_check
        par = {}  # (kind, march) -> renderer of the materials with parallax of that kind
        kinds = {"parallax": c.parallax_steps, "offset": c.neural_offset}
        for kind in (k for k, on in kinds.items() if on):
            mats = timing.parallax_materials(
                "height" if kind == "parallax" else "neural", c.parallax_steps
            )
            for march in MARCHES:  # the render's march (--parallax-march)
                rr = _renderer(timing.bench_scene(c.lights, mats), c, eye_res, "hdr", march=march)
                par[kind, march] = rr
            own, by_side = timing.auto_block_shares(rr, (16, 32, 64, 128, 256))
            doc.setdefault("auto_block_share", {})[kind] = own
            doc["auto_block_share_by_side"] = by_side  # the same scene with larger materials
        floors = {k: floor_bundles(hdr, k) for k in ("fs_floor_sample", "fs_floor_constant")}
        floors["fs_floor_screen"] = screen_floor_bundles(hdr)
        n1 = c.reuse + 1
        bar = timing.progress(c.rounds, "bench frame", c.progress, unit="round")
        f = n1 * 2  # after a cycle of warm-up
        for rnd in range(c.rounds):
            rec = {"round": rnd, "loop": {}, "passes": {}}
            for depth in (1, 2, 3):
                hdr.set_frames_in_flight(depth)
                hdr.frame(f)  # warm the new ring
                hdr.wait()
                f += 1
                f += (-f) % n1
                rec["loop"][depth] = loop(hdr, c.frames, f)
                f += c.frames
            p, rep = rec["passes"], c.repeats
            rec["empty_submit_ms"] = time_passes(hdr, lambda enc, timer: None, rep)["wall_ms"]
            updates = {"texture_full": (hdr, "main", 1), "texture_bare": (hdr, "bare", 1),
                       "texture_loads": (hdr, "bare_loads", 1),
                       "texture_slice": (hdr, "main", n1),
                       "texture_slice_bare": (hdr, "bare", n1),
                       "texture_full_exact": (exact, "main", 1),
                       "texture_loads_exact": (exact, "bare_loads", 1),
                       "texture_slice_exact": (exact, "main", n1)}  # fmt: skip
            for (kind, march), rr in par.items():  # the same update, with parallax
                sfx = kind + ("" if march == "texel" else f"_{march}")
                updates[f"texture_full_{sfx}"] = (rr, "main", 1)
                updates[f"texture_slice_{sfx}"] = (rr, "main", n1)
            for key, (rr, entry, period) in updates.items():
                p[key] = time_passes(rr, texture_update(rr, entry, 0, period, f), rep)
            hdr.frame(f)  # the eyes' uniforms and radiance textures of a real frame
            hdr.wait()
            f += 1
            p["forward"] = time_passes(hdr, forward(hdr), rep)
            for k, bundles in floors.items():  # forward_floor_constant, _sample, _screen
                p[k.replace("fs_", "forward_")] = time_passes(hdr, forward(hdr, bundles), rep)
            p["colour_store"] = time_passes(hdr, colour_store(hdr), rep)
            disp.frame(f)
            disp.wait()
            p["forward_display"] = time_passes(disp, forward(disp), rep)
            doc["records"].append(rec)
            bar.update()
        bar.close()
        doc["summary"] = summarise(doc, c.reuse)
        doc["targets"] = TARGETS
        return rp.finish(root, doc, markdown(doc), t0, [("frame.png", "frame breakdown", plot)])
