"""NeuMIP's neural offset module (numpy reference): a learned parallax without a height field.

NeuMIP (Kuznetsov et al. 2021, section 3.3) moves the lookup of the neural textures along the
view ray by an offset that a small network predicts, trained end to end with the rest and
supervised by nothing but the BTF values:

1. ``psi = T_off(u)``: a bilinear (wrap) lookup of the *offset texture* ``[H, W, C]`` float16
   at the unmoved material UV ``u`` (no pyramid);
2. ``r = F_off([psi, wo.x, wo.y])``: the *offset MLP* (ReLU between its layers, one linear
   output) predicts a ray depth ``r`` in texels of the ``[H, W]`` grid (the view enters as
   its projection on the tile's plane, NeuMIP's 2D form of a direction);
3. the fixed-function stage ``H(r, wo) = r / max(wo.z, 0.6) * (wo.x / W, wo.y / H)`` turns the
   depth into a UV shift (Eq. 6; the ``max`` bounds the shift at grazing views), and the
   neural textures are looked up at ``u + H(r, wo)`` (Eq. 7).

``wo`` is the extended view of :mod:`vrneural.grazing` (as for height-field parallax). The
module runs per texel (``march = "texel"``) or once per 2x2 block at the block's mean UV, the
block's four lookups shifted alike (``"block"``: a quarter of the offset MLP's work). Twins:
:func:`vrneural.distill.lookups.offset_uv` (torch, trained) and the WGSL stage of both render
passes (:mod:`vrneural.runtime.codegen_offset`).
"""

from __future__ import annotations

import numpy as np

from vrneural.mlp import Layer, macs, mlp_forward
from vrneural.sampling import block_rows, sample_bilinear_wrap

#: the lower bound of ``wo.z`` in the depth-to-offset stage (NeuMIP Eq. 6)
MIN_COS = 0.6
#: view inputs of the offset MLP: ``wo.x, wo.y``
VIEW_INPUTS = 2
#: the offset module of each method: (offset texture channels, the offset MLP's hidden widths).
#: NeuMIP's is the paper's (7 channels, 4 layers of 25 but the last); the teacher gets the same
#: network on its 8 channels; the 8-wide networks a module of their own size
OFFSET_SIZES = {
    "teacher": (8, [25, 25, 25]),
    "neumip": (7, [25, 25, 25]),
    "student": (4, [8, 8]),
    "single8": (4, [8, 8]),
}


def check_offset(layers: list[Layer], tex: np.ndarray, res: tuple[int, int]) -> np.ndarray:
    """Validate a pack's offset module: the texture ``[H, W, C]`` on the neural textures'
    full-resolution texel grid ``res``, finite; the MLP reads ``C + 2`` inputs and writes 1.
    Returns the texture as float16; ValueError otherwise."""
    t = np.asarray(tex)
    if t.ndim != 3 or tuple(t.shape[:2]) != tuple(res) or t.shape[2] < 1:
        raise ValueError(
            f"offset texture has shape {list(t.shape)}; expected [{res[0]}, {res[1]}, C > 0] "
            "(the neural textures' texels)"
        )
    if not np.isfinite(t.astype(np.float32)).all():
        raise ValueError("offset texture contains NaN/Inf")
    if not layers:
        raise ValueError("the offset MLP has no layers")
    if layers[0].n_in != t.shape[2] + VIEW_INPUTS:
        raise ValueError(
            f"offset MLP takes {layers[0].n_in} inputs, expected {t.shape[2]} texture channels "
            f"+ {VIEW_INPUTS} (wo.x, wo.y)"
        )
    if layers[-1].n_out != 1:
        raise ValueError(f"offset MLP outputs {layers[-1].n_out} values, expected 1 (a depth)")
    return t.astype(np.float16)


def offset_scale(wo: np.ndarray, res: tuple[int, int]) -> np.ndarray:
    """``[N, 2]`` float32: the UV shift per texel of depth along views ``wo: [N, 3]`` on a
    tile of ``res = (H, W)`` texels: ``(wo.x / W, wo.y / H) / max(wo.z, 0.6)``."""
    f = np.float32
    wo = np.asarray(wo, f)
    c = np.maximum(wo[:, 2], f(MIN_COS))
    return np.stack([wo[:, 0] / f(res[1]) / c, wo[:, 1] / f(res[0]) / c], -1).astype(f)


def offset_depth(
    layers: list[Layer], tex: np.ndarray, wo: np.ndarray, u: np.ndarray, precision: str = "f32"
) -> np.ndarray:
    """The offset MLP's ray depth ``r: [M]`` float32 (texels) at UVs ``u: [M, 2]`` seen along
    ``wo: [M, 3]``."""
    psi = sample_bilinear_wrap(tex, u)  # [M, C]
    x = np.concatenate([psi, np.asarray(wo, np.float32)[:, :VIEW_INPUTS]], -1)
    return mlp_forward(x, layers, precision)[:, 0]


def offset_uv(
    layers: list[Layer],
    tex: np.ndarray,
    wo: np.ndarray,
    uv: np.ndarray,
    march: str | np.ndarray = "texel",
    precision: str = "f32",
) -> np.ndarray:
    """The 2x2 blocks' UVs ``uv: [N, 4, 2]`` moved by the neural offset along ``wo: [N, 3]``
    (one view per block) -> ``[N, 4, 2]`` float32; per texel or per block (``march``:
    ``"texel"``, ``"block"`` or ``[N]`` bool, :func:`vrneural.sampling.block_rows`)."""
    f = np.float32
    uv = np.asarray(uv, f)
    wo = np.asarray(wo, f)
    s = offset_scale(wo, tex.shape[:2])  # [N, 2]
    blk = block_rows(march, len(uv))
    out = np.empty_like(uv)
    if blk.any():  # once per block, at the texels' mean
        r = offset_depth(layers, tex, wo[blk], uv[blk].mean(axis=1).astype(f), precision)
        out[blk] = uv[blk] + (r[:, None] * s[blk])[:, None, :]
    if not blk.all():
        t = ~blk
        r = offset_depth(layers, tex, np.repeat(wo[t], 4, axis=0), uv[t].reshape(-1, 2), precision)
        out[t] = uv[t] + r.reshape(-1, 4, 1) * s[t][:, None, :]
    return out


def offset_macs(layers: list[Layer], march: str = "texel") -> float:
    """Multiply-adds of the offset MLP per shaded texel (a quarter once per block)."""
    m = float(macs(layers))
    return m / 4 if march == "block" else m


def offset_fetches(tex: np.ndarray, march: str = "texel") -> float:
    """Texel loads of the offset texture per shaded texel (4 per bilinear lookup of up to 8
    channels; a quarter once per block)."""
    n = 4.0 * -(-int(tex.shape[2]) // 8)
    return n / 4 if march == "block" else n
