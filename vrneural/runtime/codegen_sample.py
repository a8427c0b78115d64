"""The neural-texture samplers of a material kernel as WGSL lines (generated in Python, like the
networks in :mod:`vrneural.runtime.codegen_mlp`; included by ``neural_material.wgsl``).

Neural textures are ``texture_2d_array<u32>`` (rgba32uint: 8 float16 channels per texel and
layer, two per u32; see gpu_material.py) sampled by manual bilinear wrap: 4 ``textureLoad`` per
8 channels and ``unpack2x16float``, exactly as ``material.sample_bilinear_wrap`` (the texel
taps and weights from ``bilinear_taps`` in neural_material.wgsl). With a prefiltered pyramid,
``*_lod`` blends two levels (``material.sample_lod``).

With ``filtering = "hardware"`` (:data:`FILTERS`) the textures are ``texture_2d_array<f32>``
(rgba16float, 4 channels per layer) read by ``textureSampleLevel`` through one repeat, linear,
linear-mipmap sampler (``neural_samp``): the same bilinear wrap and trilinear blend, done by
the texture unit (one instruction per 4 channels instead of 4 loads, the wrap and the
weights in the shader), its weights at the adapter's sub-texel precision (float on llvmpipe:
the exact variant's values to float32 rounding; commonly 8 fractional bits on GPUs).
"""

from __future__ import annotations

from vrneural.gpu.unroll import IND
from vrneural.runtime.settings import NEURAL_FILTERS as FILTERS  # noqa: F401 (re-exported)

I2, I3 = IND * 2, IND * 3


def hardware_sampler_fn(name: str, tex: str, channels: int, lod: int = 0) -> list[str]:
    """``name(uv) -> array<f32, channels>`` by the sampler (level 0), or with ``lod`` (the
    pyramid's top level) ``name(uv, lod)``: trilinear between the levels around ``lod``."""
    if lod:
        head = [
            f"// Trilinear lookup in the prefiltered pyramid (levels 0..{lod}) by the sampler: "
            "levels",
            "// floor(lod) and the next blended by the fraction (twin: material.sample_lod).",
            f"fn {name}(uv: vec2<f32>, lod_in: f32) -> array<f32, {channels}> {{",
            f"{IND}let lod = clamp(lod_in, 0.0, {lod}.0);",
        ]
        lv = "lod"
    else:
        head = [
            f"// Bilinear wrap lookup of {channels} channels at material uv by the sampler "
            "(texel centres",
            "// at (i + 0.5) / W; twin: material.sample_bilinear_wrap).",
            f"fn {name}(uv: vec2<f32>) -> array<f32, {channels}> {{",
        ]
        lv = "0.0"
    layers = (channels + 3) // 4
    lines = [
        f"{IND}let v{k} = textureSampleLevel({tex}, neural_samp, uv, {k}, {lv});"
        for k in range(layers)
    ]
    vals = ", ".join(f"v{c // 4}.{'xyzw'[c % 4]}" for c in range(channels))
    return [*head, *lines, f"{IND}return array<f32, {channels}>({vals});", "}"]


def sampler_fn(name: str, tex: str, channels: int, level: bool = False) -> list[str]:
    """``name(uv[, level]) -> array<f32, channels>``: the bilinear wrap lookup of ``tex`` (at
    pyramid level ``level`` when asked)."""
    at = ", at pyramid level `level`" if level else ""
    lines = [
        f"// Bilinear wrap lookup of {channels} channels at material uv (texel centres at "
        f"(i + 0.5) / W){at}.",
        f"fn {name}(uv: vec2<f32>{', level: i32' if level else ''}) -> array<f32, {channels}> {{",
    ]
    if level:
        lines += [
            f"{IND}// the level's size from level 0's: llvmpipe reads textureDimensions at a level",
            f"{IND}// that differs between the lanes of one SIMD group as if every lane had the",
            f"{IND}// first one's",
            f"{IND}let dims = max(vec2<i32>(textureDimensions({tex}, 0)) >> vec2<u32>(u32(level)), "
            "vec2<i32>(1));",
        ]  # fmt: skip
    else:
        lines.append(f"{IND}let dims = vec2<i32>(textureDimensions({tex}));")
    lines.append(f"{IND}let tp = bilinear_taps(uv, dims);")
    lines += [f"{IND}let {v} = tp.{f};" for v, f in (("xi0", "i0.x"), ("yi0", "i0.y"),
              ("xi1", "i1.x"), ("yi1", "i1.y"), ("fx", "f.x"), ("fy", "f.y"))]  # fmt: skip
    lines.append(f"{IND}var out: array<f32, {channels}>;")
    lv = "level" if level else "0"
    for layer in range((channels + 7) // 8):
        lines.append(f"{IND}{{")
        for t, x, y in (("t00", 0, 0), ("t10", 1, 0), ("t01", 0, 1), ("t11", 1, 1)):
            lines.append(
                f"{I2}let {t} = textureLoad({tex}, vec2<i32>(xi{x}, yi{y}), {layer}, {lv});"
            )
        for q in range(4):
            c = layer * 8 + 2 * q
            if c >= channels:
                continue
            lines += [
                f"{I2}{{",
                f"{I3}let top = unpack2x16float(t00[{q}]) * (1.0 - fx) + "
                f"unpack2x16float(t10[{q}]) * fx;",
                f"{I3}let bot = unpack2x16float(t01[{q}]) * (1.0 - fx) + "
                f"unpack2x16float(t11[{q}]) * fx;",
                f"{I3}let v = top * (1.0 - fy) + bot * fy;",
                f"{I3}out[{c}] = v.x;",
                *([f"{I3}out[{c + 1}] = v.y;"] if c + 1 < channels else []),
                f"{I2}}}",
            ]
        lines.append(f"{IND}}}")
    return [*lines, f"{IND}return out;", "}"]


def lod_fn(name: str, channels: int, top: int) -> list[str]:
    """``{name}_lod(uv, lod)``: the trilinear lookup in the prefiltered pyramid (levels
    0..``top``), levels floor(lod) and the next blended by the fraction."""
    return [
        f"// Trilinear lookup in the prefiltered pyramid (levels 0..{top}): levels floor(lod) "
        "and the",
        "// next blended by the fraction. Twin: vrneural/material.py:sample_lod.",
        f"fn {name}_lod(uv: vec2<f32>, lod_in: f32) -> array<f32, {channels}> {{",
        f"{IND}let lod = clamp(lod_in, 0.0, {top}.0);",
        f"{IND}let l0 = floor(lod);",
        f"{IND}let t = lod - l0;",
        f"{IND}let a = {name}_at(uv, i32(l0));",
        f"{IND}if (t == 0.0) {{ return a; }}",
        f"{IND}let b = {name}_at(uv, min(i32(l0) + 1, {top}));",
        f"{IND}var out: array<f32, {channels}>;",
        *(f"{IND}out[{c}] = a[{c}] * (1.0 - t) + b[{c}] * t;" for c in range(channels)),
        f"{IND}return out;",
        "}",
    ]


def samplers_wgsl(spec) -> str:
    """Every sampler of ``spec``'s material (:class:`~vrneural.runtime.codegen.MaterialSpec`):
    ``sample_a`` (and ``sample_b`` for coarse-to-fine), with a pyramid their ``*_at`` level
    lookups and ``*_lod`` blends; with a neural offset ``sample_off`` (the offset texture)."""
    texs = [("sample_a", "tex_a", spec.ca)]
    if spec.arch == "coarse_fine":
        texs.append(("sample_b", "tex_b", spec.cb))
    if spec.filtering == "hardware":
        lines = [line for n, t, c in texs for line in hardware_sampler_fn(n, t, c)]
        if spec.lod_levels > 1:
            for n, t, c in texs:
                lines += hardware_sampler_fn(n + "_lod", t, c, spec.lod_levels - 1)
        if spec.offset_net:
            lines += hardware_sampler_fn("sample_off", "off_tex", spec.offset_ch)
        return "\n".join(lines)
    lines = [line for n, t, c in texs for line in sampler_fn(n, t, c)]
    if spec.lod_levels > 1:
        for n, t, c in texs:
            lines += sampler_fn(n + "_at", t, c, level=True)
            lines += lod_fn(n, c, spec.lod_levels - 1)
    if spec.offset_net:  # NeuMIP's offset texture: level 0 only, at the unmoved uv
        lines += sampler_fn("sample_off", "off_tex", spec.offset_ch)
    return "\n".join(lines)
