"""``AtlasConfig``: what `vrneural atlas` takes (each field's help is its --help line), and the
atlas stage's bounds; a light module (the CLI's parser imports it, not the stage)."""

from __future__ import annotations

from dataclasses import dataclass

from vrneural.config import opt
from vrneural.errors import VrnError, check_range

#: largest accepted resolution (WebGPU guarantees 8192 for 2D textures; memory ~1.2 GB there)
MAX_RESOLUTION = 8192
MIN_RESOLUTION = 8
MAX_PADDING = 64
#: ``atlas_uv`` choices: the mesh's UVs when they serve, always, or a generated unwrap
MODES = ("auto", "mesh", "charts", "xatlas")


@dataclass
class AtlasConfig:
    """Settings of the atlas stage (the CLI parses into this)."""

    res: int = opt(
        1200, "atlas resolution R, even, in [8, 8192]: the radiance texture is R x R texels"
    )
    padding: int = opt(2, "gutter width in texels around charts (>= 1 for bilinear sampling)")
    cache: bool = opt(True, "reuse atlases cached on disk ($VRNEURAL_CACHE/atlas)")
    atlas_uv: str = opt(
        "auto",
        "atlas UVs: auto (the mesh's own lightmap/UV set when it serves, else generated), mesh "
        "(insist on the mesh's own), charts (generate: normal-direction charts), xatlas "
        "(generate with xatlas, falling back to charts)",
        choices=MODES,
    )


def check_texture_resolution(name: str, resolution: int) -> None:
    """Raise :class:`VrnError` unless ``resolution`` is in [:data:`MIN_RESOLUTION`,
    :data:`MAX_RESOLUTION`] and even: the radiance texture the runtime shades on this atlas
    works in 2x2 texel blocks (``vrneural run --texture-res`` rejects odd values too).
    :func:`build_atlas` itself accepts any resolution in range."""
    check_range(name, resolution, MIN_RESOLUTION, MAX_RESOLUTION)
    if resolution % 2:
        raise VrnError(
            f"{name} = {resolution} must be even (2x2 blocks); allowed: even values in "
            f"[{MIN_RESOLUTION}, {MAX_RESOLUTION}]"
        )
