"""Texture lookups shared by the numpy twins (material evaluation, parallax marching): the
semantics every kernel's sampler matches."""

from __future__ import annotations

import numpy as np


def sample_bilinear_wrap(tex: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Bilinear, wrap-around lookup of ``tex: [H, W, C]`` at ``uv: [..., 2]`` -> ``[..., C]``."""
    t = np.asarray(tex, np.float32)
    H, W = t.shape[:2]
    x = np.asarray(uv[..., 0], np.float64) * W - 0.5
    y = np.asarray(uv[..., 1], np.float64) * H - 0.5
    x0 = np.floor(x)
    y0 = np.floor(y)
    fx = (x - x0)[..., None].astype(np.float32)
    fy = (y - y0)[..., None].astype(np.float32)
    xi0 = x0.astype(np.int64) % W
    yi0 = y0.astype(np.int64) % H
    xi1 = (xi0 + 1) % W
    yi1 = (yi0 + 1) % H
    top = t[yi0, xi0] * (1 - fx) + t[yi0, xi1] * fx
    bot = t[yi1, xi0] * (1 - fx) + t[yi1, xi1] * fx
    return top * (1 - fy) + bot * fy


#: where a lookup-moving march (height parallax, neural offset) runs: per texel, or once per
#: 2x2 block at the block's mean UV
MARCHES = ("texel", "block")


def block_rows(march: str | np.ndarray, n: int) -> np.ndarray:
    """``[n]`` bool: which of ``n`` blocks march once per block, for a march ``"texel"``,
    ``"block"`` or already a ``[n]`` bool array (:func:`vrneural.parallax.auto_blocks`)."""
    if isinstance(march, str):
        if march not in MARCHES:
            raise ValueError(f"parallax march {march!r} not in {MARCHES} (resolve 'auto' first)")
        return np.full(n, march == "block")
    return np.asarray(march, bool).reshape(n)
