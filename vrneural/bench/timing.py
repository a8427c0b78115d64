"""The frame-timing loop shared by `bench frames`, `bench lights` and `bench materials`, and
the run of the last two (:func:`count_bench`).

One :class:`~vrneural.runtime.renderer.Renderer` per (scene, texture resolution, lights) is
reused across update intervals and schedules (``reuse`` and ``schedule`` are read from its
settings every frame), so pipelines and atlases are built once. Frame 0 of a renderer (shader
compilation and every object's first full update) is never measured. A configuration is measured
over ``cycles * (N + 1)`` frames (at least ``min_frames``), so every radiance-texture block is
updated exactly ``cycles`` times in it under either schedule. Before it, unmeasured frames are
rendered for ``warmup`` seconds (at least one): a GPU lowers its clocks while the host builds
the next configuration and needs tens of frames to raise them again (docs/benchmarks.md, the
H100 section); a CPU adapter spends one frame.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from vrneural.bench import report as rp
from vrneural.btf.heightfield import spectral_noise
from vrneural.errors import check_range
from vrneural.material import random_material
from vrneural.mlp import random_mlp
from vrneural.neural_offset import OFFSET_SIZES, VIEW_INPUTS
from vrneural.parallax import auto_blocks
from vrneural.runtime.config import REUSE_MAX
from vrneural.runtime.lights import default_lights
from vrneural.runtime.profiles import get_profile
from vrneural.runtime.scene import MaterialDesc, ObjectDesc, Scene, model_matrix


def make_renderer(scene, **settings):
    """A renderer for ``scene`` with these :class:`~vrneural.runtime.renderer.Settings` (one
    light unless ``n_lights`` is given), its frame 0 already rendered."""
    from vrneural.runtime.renderer import Renderer, Settings

    r = Renderer(scene, Settings(**{"n_lights": 1, **settings, "frames": 1}))
    r.frame(0)  # compile + first full update: not measured
    r.next_frame = 1
    return r


def frames_for(reuse: int, cycles: int, min_frames: int) -> int:
    n1 = reuse + 1
    return n1 * max(cycles, -(-min_frames // n1))


def measure(
    r, reuse: int, schedule: str, cycles: int, min_frames: int, tick=None, warmup: float = 0.0
) -> dict:
    """Render one configuration's frames on renderer ``r``; returns the record's timing fields.

    ``frame_ms``: wall time per displayed frame, frames rendered back to back with
    ``Settings.frames_in_flight`` queued (on a CPU adapter this is all the work). ``gpu_ms``: sum
    of the timestamped passes per frame. ``shading_ms_per_frame``: mean neural-shading GPU ms per
    displayed frame (texture-space updates, or the screen-space pass), i.e. amortised over the
    N + 1 frames that share one update. ``forward_ms``: median GPU ms of the forward (raster)
    passes of both eyes. Where this adapter's timestamps do not cover a pass (``gpu_untimed``),
    those two come from one more update cycle rendered with each pass submitted alone and timed
    by the wall clock (``pass_clock`` "wall").
    """
    r.s.reuse, r.s.schedule = reuse, schedule
    n = frames_for(reuse, cycles, min_frames)
    warm, t0 = 0, time.perf_counter()
    while warmup > 0 and (warm == 0 or time.perf_counter() - t0 < warmup):
        r.frame(r.next_frame)
        r.next_frame += 1
        warm += 1
    f0 = r.next_frame
    f0 += (-f0) % (reuse + 1)  # start on a cycle boundary: same phases for every run
    sts = []
    for f in range(f0, f0 + n):  # back to back, frames in flight: the stats are read after
        sts.append(r.frame(f))
        if tick:
            tick()
    r.wait()
    untimed = set(sts[0].untimed)
    walls = [st.wall_ms for st in sts]
    gpu = [sum(st.gpu_ms.values()) for st in sts]
    evals = [st.mlp_coarse + st.mlp_fine for st in sts]
    blocks = [st.blocks_shaded if r.s.mode == "texture" else st.pixels_shaded for st in sts]
    clock, m, timed = "timestamps", 0, sts
    if untimed:  # this adapter's timestamps miss a pass: one more cycle, each pass timed alone
        r.pass_clock, clock = "wall", "wall"
        m = frames_for(reuse, 1, 1)
        timed = [r.frame(f) for f in range(f0 + n, f0 + n + m)]
        r.pass_clock = "timestamps"
        r.wait()
    shade = [st.gpu_ms.get("texture", 0.0) + st.gpu_ms.get("screen", 0.0) for st in timed]
    fwd = [st.gpu_ms.get("forward", 0.0) for st in timed]
    r.next_frame = f0 + n + m
    fs = rp.stats(walls)
    return {
        "frames": n,
        "first_frame": f0,
        "warmup_frames": warm,
        "frame_ms": fs,
        "fps": 1e3 / fs["mean"],
        "gpu_ms": rp.stats(gpu),  # the timed passes (gpu_untimed: those left out)
        "gpu_untimed": sorted(untimed),
        "host_cpu_ms": float(np.median([st.cpu_ms for st in sts])),
        # "wall": this adapter's timestamps miss a pass (runtime/timecheck.py), so the shading and
        # forward ms come from one more cycle with each pass submitted alone (submit to done)
        "pass_clock": clock,
        "wall_clock_frames": m,
        "shading_ms_per_frame": float(np.mean(shade)),
        "shading_ms_max": float(np.max(shade)),
        "forward_ms": float(np.median(fwd)),
        "mlp_evals_per_frame": float(np.mean(evals)),
        "mlp_evals_max": int(np.max(evals)),
        "shaded_per_frame": float(np.mean(blocks)),
    }


def measured_record(
    r, reuse: int, schedule: str, cycles: int, min_frames: int, tick=None, warmup: float = 0.0
) -> dict:
    """Renderer ``r``'s settings and scene sizes, with the timing fields of :func:`measure`."""
    timed = measure(r, reuse, schedule, cycles, min_frames, tick, warmup)  # sets reuse, schedule
    s, texture = r.s, r.s.mode == "texture"
    return {
        "mode": s.mode,
        "schedule": s.schedule if texture else "-",
        "texture_res": s.texture_res if texture else None,
        "reuse": s.reuse if texture else 0,
        "lights": len(r.lights),
        "materials": len({id(n.desc.material.neural) for n in r.neural}),
        "neural_objects": len(r.neural),
        "eyes": s.eyes,
        "eye_res": list(s.eye_res),
        "precision": s.precision,
        **timed,
    }


def count_bench(c, name: str, counts: list[int], setup, per: str, report) -> dict:
    """`bench lights` and `bench materials` (``name``), ``c`` resolved: its checks, its output
    folder, one renderer per count ``k`` of ``counts`` on ``setup(k) -> (scene, point lights)``
    with ``c``'s texture side, eyes, N and schedule at the quest3 frame rate and field of view,
    each measured over ``c.loop.cycles`` update cycles after ``c.loop.warmup`` s (the records in
    ``counts`` order), and results.md from ``report(records) -> (title, setting, columns,
    notes, plots)``: the title, the setting line (the scene; N, the frames measured per
    ``per`` and the warm-up follow), the table of ``columns``, the FPS note and ``notes``;
    ``plots`` as :func:`~vrneural.bench.report.finish` draws them."""
    rp.check_texture_res(c.texture_res)
    check_range("--reuse", c.reuse, 0, REUSE_MAX)
    loop, eye_res = c.loop, c.loop.check()
    with rp.prepare_out(c.out, c.force, name) as root:
        t0 = time.perf_counter()
        doc = rp.header(name, c)
        prof = get_profile("quest3")
        n = frames_for(c.reuse, loop.cycles, 1)
        bar = progress(n * len(counts), f"bench {name}", c.progress)
        recs = doc["records"] = []
        for k in counts:
            scene, n_lights = setup(k)
            r = make_renderer(scene, texture_res=c.texture_res, eye_res=eye_res, eyes=loop.eyes,
                              n_lights=n_lights, reuse=c.reuse, schedule=c.schedule, fps=prof.fps,
                              fov_y=prof.fov_y)  # fmt: skip
            recs.append(
                measured_record(r, c.reuse, c.schedule, loop.cycles, 1, bar.update, loop.warmup)
            )
            del r
        bar.close()
        title, setting, columns, notes, plots = report(recs)
        md = [
            title,
            "",
            rp.adapter_line(doc),
            f"{setting}, N = {c.reuse} ({c.schedule}), {n} frames per {per} after frame 0 "
            f"and {loop.warmup} s of unmeasured frames."
            + (" **Quick run: reduced grid.**" if c.quick else ""),
            "",
            *rp.record_table(recs, columns),
            "",
            rp.FPS_NOTE,
            *notes,
        ]
        return rp.finish(root, doc, md, t0, plots)


def progress(total: int, desc: str, enabled: bool, unit: str = "frame"):
    return tqdm(total=total, desc=desc, unit=unit, disable=not enabled)


def parallax_materials(kind: str, steps: int = 0, march: str = "texel"):
    """The benchmark scene's two random students (seeds 3 and 4, 16^2 textures) with parallax
    of ``kind``: ``height``, a height field of ``steps`` march steps on a rough random relief
    (spectral noise over 0.15 tile widths, pebbles' range; the march ends where it meets it, so
    the cost depends on the relief); ``neural``, NeuMIP's neural offset module of the student's
    size (:data:`vrneural.neural_offset.OFFSET_SIZES`: a random offset texture and a random
    dense offset MLP; the cost does not depend on the values)."""
    ch, hidden = OFFSET_SIZES["student"]
    out = []
    for s in (3, 4):
        rng = np.random.default_rng(s)
        if kind == "height":
            h = spectral_noise(rng, 16, 1, 8)
            h = 0.15 * (h - h.mean()) / max(float(np.ptp(h)), 1e-12)
            par = dict(height=h, parallax={"kind": "height", "steps": steps, "march": march})
        else:
            tex = rng.normal(0.0, 0.5, (16, 16, ch)).astype(np.float16)
            net = random_mlp([ch + VIEW_INPUTS, *hidden, 1], s)
            par = dict(offset_tex=tex, offset_net=net, parallax={"kind": "neural", "march": march})
        out.append(dataclasses.replace(random_material(s, tex_res=16), levels={}, **par))
    return out


def auto_block_shares(r, sides=()) -> tuple[float, dict]:
    """The share of renderer ``r``'s texture-space blocks (over its neural objects with
    parallax) that march ``"auto"`` runs once per block (:func:`vrneural.parallax.auto_blocks`
    at each object's atlas and tiling) for the materials' own march grids, and ``{side:
    share}`` for grids of ``side^2`` texels (what larger materials would get); each object's
    block footprints computed once."""
    from vrneural.runtime.reference import block_geometry

    feet = []  # (footprints [N], the material's march grid)
    for o in r.neural:
        mat = o.desc.material.neural
        if mat is not None and mat.parallax_kind != "off":
            foot = block_geometry(o.atlas)["foot"] * np.float32(o.desc.material.tiling)
            feet.append((foot, mat.march_grid))

    def share(side: int | None) -> float:
        hits = [auto_blocks(f, (side, side) if side else grid) for f, grid in feet]
        return float(np.concatenate(hits).mean()) if hits else 0.0

    return share(None), {side: share(side) for side in sides}


def bench_scene(n_lights: int, materials=None):
    """The benchmark scene, independent of the bundled packs: a neural sphere (0.8 m) and a
    neural tile (0.45 m) on a plain 6 m floor, ``n_lights`` circling point lights
    (:func:`vrneural.runtime.lights.default_lights`: the first k of them are the same for every
    count only through ``scene.lights[:k]``), the built-in head orbit. ``materials``: two
    NeuralMaterials (default: seeded random students, the runtime's coarse-to-fine 8-wide
    architecture; frame time does not depend on the weights' values)."""
    from vrneural.runtime.assets import get_mesh

    def fit(name: str, size: float) -> float:  # scale so the mesh's largest extent is ``size``
        p = get_mesh(name).positions
        return size / float((p.max(0) - p.min(0)).max())

    mats = materials or (random_material(3), random_material(4))
    hero = MaterialDesc("neural", mats[0], mats[0].meta.get("name", "hero"), 0.5)
    tile = MaterialDesc("neural", mats[1], mats[1].meta.get("name", "tile"), 1.0)
    floor = MaterialDesc("plain", albedo=(0.35, 0.35, 0.38), specular=0.02, shininess=16.0)
    objects = [
        ObjectDesc(
            "sphere", "sphere", model_matrix((0, 0.9, 0), (0, 0, 0), fit("sphere", 0.8)), hero
        ),
        ObjectDesc(
            "tile",
            "plane",
            model_matrix((0.55, 0.55, 0.15), (60, -30, 0), fit("plane", 0.45)),
            tile,
        ),
        ObjectDesc("floor", "plane", model_matrix((0, 0, 0), (0, 0, 0), fit("plane", 6.0)), floor),
    ]
    return Scene(
        "bench",
        objects,
        default_lights(n_lights),
        None,
        None,
        "orbit",
        Path.cwd(),
        src="bench scene",
    )
