"""Which mip level does this adapter's sampler read? (docs/lod.md, "What blurs the mips")

A 256^2 rgba16float texture whose level k holds the value k is drawn over a W x W target
(minification 256 / W), its v coordinate stretched 1x or 4x (an anisotropic footprint), with
``textureSample`` and ``textureSampleBias`` (-1, +1), through a sampler with
``max_anisotropy`` 1 and 8. Prints the mean level read against the isotropic level
log2(256 / W) and the major axis's. Usage: ``python scripts/research/mip_sampler_probe.py [W]``.
"""

from __future__ import annotations

import sys

import numpy as np
import wgpu

from vrneural.gpu.device import get_device

N, LEVELS = 256, 9
SRC = """
@group(0) @binding(0) var t: texture_2d<f32>;
@group(0) @binding(1) var s: sampler;
struct V { @builtin(position) p: vec4<f32>, @location(0) uv: vec2<f32> }
@vertex fn vs(@builtin(vertex_index) i: u32) -> V {
  var q = array<vec2<f32>, 6>(vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(0.0, 1.0),
                              vec2(1.0, 0.0), vec2(1.0, 1.0), vec2(0.0, 1.0));
  var o: V;
  o.uv = q[i] * vec2(1.0, STRETCH);
  o.p = vec4(q[i] * 2.0 - 1.0, 0.0, 1.0);
  return o;
}
@fragment fn fs(v: V) -> @location(0) vec4<f32> { return vec4(LOOKUP.r, 0.0, 0.0, 1.0); }
"""
LOOKUPS = {
    "sample": "textureSample(t, s, v.uv)",
    "bias -1": "textureSampleBias(t, s, v.uv, -1.0)",
    "bias +1": "textureSampleBias(t, s, v.uv, 1.0)",
}


def level_texture(dev):
    tex = dev.create_texture(
        size=(N, N, 1), format="rgba16float", mip_level_count=LEVELS,
        usage=wgpu.TextureUsage.TEXTURE_BINDING | wgpu.TextureUsage.COPY_DST,
    )  # fmt: skip
    for k in range(LEVELS):
        s = N >> k
        a = np.zeros((s, s, 4), np.float16)
        a[..., 0], a[..., 3] = k, 1
        dev.queue.write_texture(
            {"texture": tex, "mip_level": k}, a.tobytes(),
            {"bytes_per_row": s * 8, "rows_per_image": s}, (s, s, 1),
        )  # fmt: skip
    return tex


def mean_level(dev, tex, w: int, stretch: float, anisotropy: int, lookup: str) -> float:
    src = SRC.replace("LOOKUP", lookup).replace("STRETCH", f"{stretch:.1f}")
    mod = dev.create_shader_module(code=src)
    samp = dev.create_sampler(
        mag_filter="linear", min_filter="linear", mipmap_filter="linear",
        max_anisotropy=anisotropy,
    )  # fmt: skip
    frag = wgpu.ShaderStage.FRAGMENT
    bgl = dev.create_bind_group_layout(
        entries=[
            {"binding": 0, "visibility": frag, "texture": {"sample_type": "float"}},
            {"binding": 1, "visibility": frag, "sampler": {"type": "filtering"}},
        ]
    )
    pipe = dev.create_render_pipeline(
        layout=dev.create_pipeline_layout(bind_group_layouts=[bgl]),
        vertex={"module": mod, "entry_point": "vs"},
        fragment={"module": mod, "entry_point": "fs", "targets": [{"format": "rgba32float"}]},
        primitive={"topology": "triangle-list"},
    )
    bg = dev.create_bind_group(
        layout=bgl,
        entries=[{"binding": 0, "resource": tex.create_view()}, {"binding": 1, "resource": samp}],
    )
    usage = wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.COPY_SRC
    tgt = dev.create_texture(size=(w, w, 1), format="rgba32float", usage=usage)
    enc = dev.create_command_encoder()
    rp = enc.begin_render_pass(
        color_attachments=[
            {"view": tgt.create_view(), "load_op": "clear", "store_op": "store",
             "clear_value": (0, 0, 0, 0)}
        ]
    )  # fmt: skip
    rp.set_pipeline(pipe)
    rp.set_bind_group(0, bg)
    rp.draw(6)
    rp.end()
    dev.queue.submit([enc.finish()])
    raw = dev.queue.read_texture(
        {"texture": tgt}, {"bytes_per_row": w * 16, "rows_per_image": w}, (w, w, 1)
    )
    return float(np.frombuffer(raw, np.float32).reshape(w, w, 4)[..., 0].mean())


def main() -> None:
    w = int(sys.argv[1]) if len(sys.argv) > 1 else 64
    dev = get_device()
    tex = level_texture(dev)
    iso = np.log2(N / w)
    print(f"adapter: {dev.adapter.info['device']}; minification {N / w:g}")
    for stretch in (1.0, 4.0):
        for aniso in (1, 8):
            for name, lookup in LOOKUPS.items():
                lvl = mean_level(dev, tex, w, stretch, aniso, lookup)
                print(
                    f"footprint 1:{stretch:g}  max_anisotropy {aniso}  {name:8s} level {lvl:.3f}"
                    f"  (isotropic {iso + np.log2(stretch):.2f}, minor axis {iso:.2f})"
                )


if __name__ == "__main__":
    main()
