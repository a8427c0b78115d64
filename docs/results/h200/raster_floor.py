"""The adapter's raster floor (issue #41): what a render pass costs over the main job's eye
targets when it does nothing but cover them, against a compute pass writing the same texels.
``python docs/results/h200/raster_floor.py [WIDTHxHEIGHT] [OUT.json]`` (default 4128x2208, both
Quest 3 eyes side by side as the texture-mode forward pass draws them).

Each configuration is one render pass that clears its targets and draws one full-screen
triangle (constant colour unless named otherwise), timed by GPU timestamps (8 passes per submit,
their median over 5 submits, after a warm-up submit) and by the wall clock (submit to a
read-back that waits for it, per pass). Configurations: the renderer's colour target
(rgba16float with the usages the renderer gives it), without the storage usage, the 8-bit
display target, depth formats, depth not stored, the colour loaded instead of cleared (alone,
and after a compute pass that clears it), the depth cleared by one pass in four (the
renderer's depth_clear "slices") or never, no depth, depth only, one eye's width, clears alone,
and a
fragment shader that runs 256 dependent multiply-adds per pixel against a compute shader that
runs the same per texel (the fragment stage's arithmetic rate against the whole chip's).
"""

import json
import sys
import time

import numpy as np
import wgpu

from vrneural.gpu.device import get_device
from vrneural.gpu.timing import GpuTimer

W, H = (int(x) for x in (sys.argv[1] if len(sys.argv) > 1 else "4128x2208").split("x"))
OUT = sys.argv[2] if len(sys.argv) > 2 else None
dev = get_device()
tu = wgpu.TextureUsage
RENDERER = tu.RENDER_ATTACHMENT | tu.COPY_SRC | tu.STORAGE_BINDING | tu.TEXTURE_BINDING
PLAIN = tu.RENDER_ATTACHMENT | tu.COPY_SRC | tu.TEXTURE_BINDING
ALU = """
    var x = p.x * 1e-4; var y = p.y * 1e-4;
    for (var i = 0; i < 256; i++) { x = fma(x, 0.999, y); y = fma(y, 0.999, -x * 1e-3); }"""
WGSL = f"""
@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {{
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.5, 1.0);
}}
@fragment fn fs_const() -> @location(0) vec4<f32> {{ return vec4<f32>(0.2, 0.3, 0.4, 1.0); }}
@fragment fn fs_alu(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {{ {ALU}
    return vec4<f32>(x, y, 0.0, 1.0);
}}
@fragment fn fs_none() {{ }}
@group(0) @binding(0) var dst: texture_storage_2d<rgba16float, write>;
@compute @workgroup_size(8, 8) fn cs_store(@builtin(global_invocation_id) g: vec3<u32>) {{
    if (g.x >= {W}u || g.y >= {H}u) {{ return; }}
    textureStore(dst, g.xy, vec4<f32>(0.2, 0.3, 0.4, 1.0));
}}
@compute @workgroup_size(8, 8) fn cs_alu(@builtin(global_invocation_id) g: vec3<u32>) {{
    if (g.x >= {W}u || g.y >= {H}u) {{ return; }}
    let p = vec2<f32>(g.xy) + 0.5; {ALU}
    textureStore(dst, g.xy, vec4<f32>(x, y, 0.0, 1.0));
}}
"""
mod = dev.create_shader_module(code=WGSL)


def render_case(colour, depth, usage=PLAIN, width=W, fs="fs_const", draw=True, load="clear",
                depth_store="store", pre=None, slices=1):  # fmt: skip
    """An encoder callback: one render pass over ``width x H`` targets (``colour``/``depth``:
    formats or None; ``load``: the colour's load op; ``depth_store``: the depth's store op;
    ``pre``: a compute pass's encoder callback run before, on the colour texture; ``slices``:
    the depth cleared by one pass in that many, loaded by the others, each pass drawing into a
    nearer slice of the depth range, as the renderer's depth_clear "slices")."""
    ct = dev.create_texture(size=(width, H, 1), format=colour, usage=usage) if colour else None
    dt = None
    if depth:
        dt = dev.create_texture(size=(width, H, 1), format=depth, usage=tu.RENDER_ATTACHMENT)
    pipe = None
    if draw:
        pipe = dev.create_render_pipeline(
            layout="auto",
            vertex={"module": mod, "entry_point": "vs"},
            primitive={"topology": "triangle-list"},
            depth_stencil={"format": depth, "depth_write_enabled": True,
                           "depth_compare": "less"} if depth else None,
            fragment={"module": mod, "entry_point": fs,
                      "targets": [{"format": colour}] if colour else []},
        )  # fmt: skip

    n = [0]

    def encode(enc, timer, name):
        if pre is not None:
            pre(enc, timer, name, ct)
        k = n[0] % slices
        n[0] += 1
        rp = enc.begin_render_pass(
            color_attachments=[{"view": ct.create_view(), "load_op": load,
                                "store_op": "store", "clear_value": (0, 0, 0, 1)}]
            if ct else [],
            depth_stencil_attachment={"view": dt.create_view(),
                                      "depth_load_op": "load" if k else "clear",
                                      "depth_store_op": depth_store, "depth_clear_value": 1.0}
            if dt else None,
            timestamp_writes=timer.writes(name),
        )  # fmt: skip
        if slices > 1:
            rp.set_viewport(0, 0, width, H, 1 - (k + 1) / slices, 1 - k / slices)
        if pipe is not None:
            rp.set_pipeline(pipe)
            rp.draw(3)
        rp.end()

    return encode


def compute_case(entry, tex=None):
    """An encoder callback: a compute pass running ``entry`` over every texel of an
    rgba16float ``W x H`` texture (its own, or the one the callback is given)."""
    pipe = dev.create_compute_pipeline(layout="auto", compute={"module": mod, "entry_point": entry})
    groups = {}

    def encode(enc, timer, name, target=None):
        t = target or tex
        if id(t) not in groups:
            groups[id(t)] = dev.create_bind_group(
                layout=pipe.get_bind_group_layout(0),
                entries=[{"binding": 0, "resource": t.create_view()}])  # fmt: skip
        cp = enc.begin_compute_pass(timestamp_writes=timer.writes(name))
        cp.set_pipeline(pipe)
        cp.set_bind_group(0, groups[id(t)])
        cp.dispatch_workgroups((W + 7) // 8, (H + 7) // 8)
        cp.end()

    return encode


def own(entry):
    return compute_case(entry, dev.create_texture(size=(W, H, 1), format="rgba16float",
                                                   usage=RENDERER))  # fmt: skip


CASES = {
    "renderer colour (rgba16float, storage usage) + depth32float": render_case(
        "rgba16float", "depth32float", RENDERER),
    "rgba16float + depth32float": render_case("rgba16float", "depth32float"),
    "rgba16float + depth32float, depth not stored (discard)": render_case(
        "rgba16float", "depth32float", depth_store="discard"),
    "colour loaded, not cleared + depth32float (discard)": render_case(
        "rgba16float", "depth32float", load="load", depth_store="discard"),
    "compute clear, then colour loaded + depth32float (discard); both passes": render_case(
        "rgba16float", "depth32float", RENDERER, load="load", depth_store="discard",
        pre=compute_case("cs_store")),
    "compute clear, then colour loaded + depth32float in 4 slices (3 passes in 4 load it)":
        render_case("rgba16float", "depth32float", RENDERER, load="load",
                    pre=compute_case("cs_store"), slices=4),
    "compute clear, then colour loaded + depth32float loaded, never cleared": render_case(
        "rgba16float", "depth32float", RENDERER, load="load", pre=compute_case("cs_store"),
        slices=1 << 20),
    "rgba16float, no depth": render_case("rgba16float", None),
    "rgba8unorm-srgb + depth32float": render_case("rgba8unorm-srgb", "depth32float"),
    "rgba16float + depth24plus": render_case("rgba16float", "depth24plus"),
    "rgba16float + depth16unorm": render_case("rgba16float", "depth16unorm"),
    "depth32float only": render_case(None, "depth32float", fs="fs_none"),
    "one eye's width: rgba16float + depth32float": render_case(
        "rgba16float", "depth32float", width=W // 2),
    "clear alone: rgba16float + depth32float": render_case(
        "rgba16float", "depth32float", draw=False),
    "clear alone: rgba16float": render_case("rgba16float", None, draw=False),
    "clear alone: depth32float": render_case(None, "depth32float", draw=False),
    "fragment: 256 FMAs per pixel, rgba16float + depth32float": render_case(
        "rgba16float", "depth32float", fs="fs_alu"),
    "compute: store rgba16float": own("cs_store"),
    "compute: 256 FMAs per texel + store": own("cs_alu"),
}  # fmt: skip


def measure(encode, name, per_submit=8, submits=5):
    timer = GpuTimer(2 * per_submit)  # two passes per case at most
    stamps, walls = [], []
    for s in range(submits + 1):
        enc = dev.create_command_encoder()
        for _ in range(per_submit):
            encode(enc, timer, name)
        timer.resolve(enc)
        t0 = time.perf_counter()
        dev.queue.submit([enc.finish()])
        ts = timer.read()  # maps the resolved timestamps: waits for the submit
        if s:
            walls.append((time.perf_counter() - t0) * 1e3 / per_submit)
            if ts:
                stamps.append(ts[name] / per_submit)
    return {"timestamp_ms": float(np.median(stamps)) if stamps else None,
            "wall_ms": float(np.median(walls))}  # fmt: skip


res = {}
for _ in range(3):  # interleaved rounds, the median kept
    for name, enc in CASES.items():
        res.setdefault(name, []).append(measure(enc, name))
rows = {}
px = W * H
for name, rs in res.items():
    ts = [r["timestamp_ms"] for r in rs if r["timestamp_ms"] is not None]
    t = float(np.median(ts)) if ts else None
    w = float(np.median([r["wall_ms"] for r in rs]))
    width = W // 2 if name.startswith("one eye") else W
    rows[name] = {"timestamp_ms": t, "wall_ms": w,
                  "gpix_per_s": (width * H / (t * 1e-3) / 1e9) if t else None}  # fmt: skip
    print(f"{name:60s} {t if t is None else round(t, 3)!s:>8} ms  wall {w:.3f} ms"
          + (f"  {rows[name]['gpix_per_s']:.1f} Gpix/s" if t else ""))
doc = {"size": [W, H], "pixels": px, "adapter": dict(getattr(dev, "adapter_info", {}) or {}),
       "rows": rows, "note": __doc__}  # fmt: skip
if OUT:
    with open(OUT, "w") as f:
        json.dump(doc, f, indent=1)
