"""``build_atlas``: xatlas unwrap -> exact triangle-ID texture -> gutter, cached on disk."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from tqdm import tqdm

from vrneural.atlas.cache import cache_key, load_cached, split_mesh, store
from vrneural.atlas.geometry import check_geometry
from vrneural.atlas.raster import rasterize_ids
from vrneural.atlas.types import EMPTY, Atlas, Mesh
from vrneural.atlas.unwrap import unwrap
from vrneural.config import opt
from vrneural.errors import VrnError, check_int, check_range

#: largest accepted resolution (WebGPU guarantees 8192 for 2D textures; memory ~1.2 GB there)
MAX_RESOLUTION = 8192
MIN_RESOLUTION = 8
MAX_PADDING = 64


@dataclass
class AtlasConfig:
    """Settings of the atlas stage (the CLI parses into this)."""

    res: int = opt(
        1200, "atlas resolution R, even, in [8, 8192]: the radiance texture is R x R texels"
    )
    padding: int = opt(2, "gutter width in texels around charts (>= 1 for bilinear sampling)")
    cache: bool = opt(True, "reuse atlases cached on disk ($VRNEURAL_CACHE/atlas)")


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


def validate_mesh(mesh: Mesh) -> None:
    """Raise :class:`VrnError` for a mesh the atlas cannot handle (one line, names the mesh)."""
    if not isinstance(mesh, Mesh):
        hint = (
            " (load_mesh returns a list: pass one of its meshes)" if isinstance(mesh, list) else ""
        )
        raise VrnError(f"build_atlas: expected a Mesh, got {type(mesh).__name__}{hint}")
    pos = np.asarray(mesh.positions)
    check_geometry(mesh.name, pos, np.asarray(mesh.faces))
    for name, width in (("normals", 3), ("tangents", 4), ("uv", 2)):
        a = np.asarray(getattr(mesh, name))
        if a.shape != (len(pos), width):
            raise VrnError(f"{mesh.name}: {name} have shape {list(a.shape)}, expected [V, {width}]")


def build_atlas(
    mesh: Mesh, resolution: int, padding: int = 2, cache: bool = True, *, progress: bool = False
) -> Atlas:
    """Unwrap ``mesh`` into an R x R atlas with triangle IDs and a ``padding``-texel gutter.

    Returns an :class:`Atlas` whose mesh has vertices split at chart seams (faces in input
    order). ``stats`` holds coverage, charts, texels per triangle and timings (seconds).
    Degenerate (zero UV area) triangles are kept, own no texel and are counted in
    ``stats["zero_area_triangles"]``. ``progress`` shows a tqdm bar over the two stages.
    """
    check_int("resolution", resolution, MIN_RESOLUTION, MAX_RESOLUTION)
    check_int("padding", padding, 0, MAX_PADDING)
    resolution, padding = int(resolution), int(padding)
    validate_mesh(mesh)
    t0 = time.perf_counter()
    key = cache_key(mesh, resolution, padding)
    if cache:
        hit = load_cached(mesh, key, resolution, padding)
        if hit is not None:  # stage times stay those of the original build
            hit.stats["build_total_s"] = hit.stats.get("total_s")
            hit.stats["total_s"] = time.perf_counter() - t0
            return hit
    t1 = time.perf_counter()
    with tqdm(total=2, desc=f"atlas {mesh.name}", disable=not progress, leave=False) as bar:
        bar.set_postfix_str(f"xatlas unwrap, {len(mesh.faces)} triangles")
        vmap, uv, info = unwrap(mesh, resolution, padding)
        bar.update()
        t2 = time.perf_counter()
        bar.set_postfix_str(f"rasterize {resolution}^2 + gutter")
        ids, rinfo = rasterize_ids(uv, info["faces"], resolution, padding)
        bar.update()
    t3 = time.perf_counter()
    split = split_mesh(mesh, vmap, info["faces"])
    stats = {
        "mesh": mesh.name,
        "resolution": resolution,
        "padding": padding,
        "triangles": len(mesh.faces),
        "vertices_in": len(mesh.positions),
        "vertices_split": len(vmap),
        "charts": info["charts"],
        "texels_per_unit": info["texels_per_unit"],
        "xatlas_packed_size": info["packed_size"],
        "xatlas_packs": info["packs"],
        **texel_stats(ids, rinfo, len(mesh.faces)),
        "xatlas_s": t2 - t1,
        "raster_s": rinfo["raster_s"],
        "sliver_s": rinfo["sliver_s"],
        "dilate_s": rinfo["dilate_s"],
        "total_s": t3 - t0,
        "cache": "off" if not cache else "miss",
    }
    atlas = Atlas(split, uv, ids, resolution, padding, stats)
    if cache:
        path = store(atlas, vmap, key)
        stats["cache_file"] = str(path) if path else None
    return atlas


def texel_stats(ids: np.ndarray, rinfo: dict, n_faces: int) -> dict:
    """Coverage and texels-per-triangle numbers for ``stats`` (JSON-ready)."""
    own = rinfo["owned"]
    nz = own[rinfo["nonzero_area"]]
    filled = int(np.count_nonzero(ids != EMPTY))
    R2 = ids.size
    return {
        "coverage_pct": 100.0 * float(own.sum()) / R2,
        "filled_pct": 100.0 * filled / R2,
        "gutter_texels": rinfo["gutter_texels"],
        "texels_per_triangle_min": int(nz.min()) if len(nz) else 0,
        "texels_per_triangle_median": float(np.median(nz)) if len(nz) else 0.0,
        "triangles_without_texels": int(np.count_nonzero(nz == 0)),
        "zero_area_triangles": rinfo["zero_area_triangles"],
        "sliver_fixes": rinfo["sliver_fixes"],
        "overlap_texels": rinfo["overlap_texels"],
        "max_abs_barycentric": rinfo["max_abs_barycentric"],
    }
