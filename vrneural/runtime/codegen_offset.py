"""NeuMIP's neural offset stage as WGSL lines (generated in Python like the networks; twin:
:func:`vrneural.neural_offset.offset_uv`).

Two functions, used by the texture-space and the screen-space templates before the neural
textures are looked up:

- ``offset_r(uv, wo) -> f32``: the offset MLP's ray depth (texels) at the *unmoved* UV ``uv``:
  ``sample_off(uv)`` (the offset texture's bilinear wrap lookup, runtime/codegen_sample.py)
  and the extended view's ``wo.x, wo.y`` through the offset MLP, unrolled with constant weights
  (:func:`vrneural.gpu.unroll.mlp_lines`, in the kernel's scalar type ``T`` as the numpy twin's
  ``precision``);
- ``offset_d(wo) -> vec2<f32>``: NeuMIP's fixed-function depth-to-offset scale (Eq. 6), the UV
  shift per texel of depth ``(wo.x / W, wo.y / H) / max(wo.z, 0.6)``
  (:func:`vrneural.neural_offset.offset_scale`, the same float32 operations in the same order).

The lookups then move to ``uv + offset_r(uv, wo) * offset_d(wo)`` (Eq. 7), per texel or once
per 2x2 block at the block's mean UV (the material's ``parallax_march``).
"""

from __future__ import annotations

from vrneural.gpu.unroll import IND, literal, mlp_lines
from vrneural.neural_offset import MIN_COS, VIEW_INPUTS


def offset_wgsl(spec, T: str) -> list[str]:
    """``offset_r`` and ``offset_d`` of ``spec``'s neural offset
    (:class:`~vrneural.runtime.codegen.MaterialSpec`; ``[]`` without one)."""
    if not spec.offset_net:
        return []
    layers, c = spec.offset_net, spec.offset_ch
    w, h = spec.offset_consts
    ins = [f"in_{k}" for k in range(c + VIEW_INPUTS)]
    return [
        "// NeuMIP's neural offset (twin: vrneural/neural_offset.py:offset_uv): the offset MLP's",
        "// ray depth in texels at the unmoved uv, seen along the extended view wo.",
        "fn offset_r(uv: vec2<f32>, wo: vec3<f32>) -> f32 {",
        f"{IND}let psi = sample_off(uv);",
        *(f"{IND}let in_{k} = {T}(psi[{k}]);" for k in range(c)),
        f"{IND}let in_{c} = {T}(wo.x);",
        f"{IND}let in_{c + 1} = {T}(wo.y);",
        *mlp_lines("o", ins, layers, T),
        f"{IND}return f32(o{len(layers)}_0);",
        "}",
        "// The UV shift per texel of depth (NeuMIP Eq. 6; neural_offset.offset_scale).",
        "fn offset_d(wo: vec3<f32>) -> vec2<f32> {",
        f"{IND}let c = max(wo.z, {literal(MIN_COS, 'f32')});",
        f"{IND}return vec2<f32>(wo.x / {literal(float(w), 'f32')} / c, "
        f"wo.y / {literal(float(h), 'f32')} / c);",
        "}",
    ]
