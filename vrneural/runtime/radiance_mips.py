"""Mip chains of the radiance textures (``shaders/radiance_mips.wgsl``), rebuilt after each
update so the forward pass can sample them trilinearly (and anisotropically where the adapter
allows): minified objects then average their texels instead of aliasing.

Every level holds radiance premultiplied by coverage (alpha): level 0 as the texture-space pass
stores it (alpha 1 on shaded texels; empty texels are 0), each further level the 2 x 2 mean of
the level above, so a level's colour over its alpha is the coverage-weighted mean of the shaded
texels under it and empty texels never darken a chart's edge. The forward pass divides the
filtered colour by the filtered alpha. Chart gutters are a few texels wide, so the deepest
levels also average neighbouring charts; :data:`MIPS_MAX` bounds the chain.
"""

from __future__ import annotations

import numpy as np

#: the most levels below level 0 (a level is at least 8 texels wide)
MIPS_MAX = 6
MIN_SIDE = 8


def mip_count(resolution: int) -> int:
    """Levels in a radiance texture of side ``resolution``, level 0 included: level ``k`` is
    ``resolution >> k`` wide, at least :data:`MIN_SIDE`, and ``k`` at most :data:`MIPS_MAX`."""
    return 1 + min(MIPS_MAX, max(0, (resolution // MIN_SIDE).bit_length() - 1))


def mip_chain(level0: np.ndarray, levels: int) -> list[np.ndarray]:
    """numpy twin of the GPU chain: ``[R, R, 4]`` float32 level 0 -> the ``levels`` levels, each
    ``[R >> k, R >> k, 4]``, rounded to float16 as rgba16float stores them."""
    out = [np.asarray(level0, np.float32)]
    for _ in range(1, levels):
        a = out[-1]
        h, w = a.shape[0] // 2, a.shape[1] // 2
        a = a[: 2 * h, : 2 * w]
        s = a[0::2, 0::2] + a[0::2, 1::2] + a[1::2, 0::2] + a[1::2, 1::2]
        out.append((s * np.float32(0.25)).astype(np.float16).astype(np.float32))
    return out


def _pipeline():
    from vrneural.gpu.pipelines import compute_pipeline
    from vrneural.gpu.shaders import render_wgsl
    from vrneural.runtime.interface import MIP_BINDINGS

    code = render_wgsl("radiance_mips", bindings=MIP_BINDINGS.wgsl())
    return compute_pipeline(code, "main", label="radiance_mips")


class MipChain:
    """The bind groups that build ``texture``'s levels 1.. from level 0 (one dispatch each)."""

    def __init__(self, texture, levels: int):
        from vrneural.gpu.device import get_device
        from vrneural.runtime.interface import MIP_BINDINGS

        layout = _pipeline().get_bind_group_layout(0)
        self.groups = []  # per level from 1: (bind group, side)
        for k in range(1, levels):
            src = texture.create_view(base_mip_level=k - 1, mip_level_count=1)
            dst = texture.create_view(base_mip_level=k, mip_level_count=1)
            entries = MIP_BINDINGS.entries({"src": src, "dst": dst})
            group = get_device().create_bind_group(layout=layout, entries=entries)
            self.groups.append((group, max(1, texture.size[0] >> k)))

    def dispatch(self, cp) -> None:
        """Record the chain into an open compute pass (each level after the one it reads)."""
        cp.set_pipeline(_pipeline())
        for group, side in self.groups:
            cp.set_bind_group(0, group)
            n = -(-side // 8)
            cp.dispatch_workgroups(n, n, 1)
