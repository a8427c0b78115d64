"""``build_atlas``: atlas UVs (the mesh's own, or generated) -> exact triangle-ID texture ->
gutter, cached on disk."""

from __future__ import annotations

import time

import numpy as np

from vrneural.atlas import meshuv
from vrneural.atlas.cache import cache_key, load_cached, split_mesh, store
from vrneural.atlas.charts import face_normals
from vrneural.atlas.config import (
    MAX_PADDING,
    MAX_RESOLUTION,
    MIN_RESOLUTION,
    MODES,
    AtlasConfig,  # noqa: F401 (its old home)
)
from vrneural.atlas.generate import Layout, generated_layout
from vrneural.atlas.geometry import check_geometry, check_uv
from vrneural.atlas.layout import uv_area
from vrneural.atlas.meshuv import density_spread
from vrneural.atlas.progress import Stages
from vrneural.atlas.raster import rasterize_ids
from vrneural.atlas.types import EMPTY, Atlas, Mesh
from vrneural.atlas.visualize import uv_charts
from vrneural.errors import VrnError, check_choice, check_int, count

#: more triangles than this many per texel of R x R cannot be shown (at most a quarter of
#: them could own a texel even in a full atlas): refused before any work
MAX_TRIANGLES_PER_TEXEL = 4


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
    if mesh.lightmap_uv is not None:
        check_uv(mesh.name, "lightmap UV", mesh.lightmap_uv, len(pos))
    p = pos.astype(np.float64)[np.asarray(mesh.faces, np.int64)]
    if not np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]).any():
        n = len(p)
        every = "its only triangle is" if n == 1 else f"all {n} triangles are"
        raise VrnError(f"{mesh.name}: {every} degenerate (no area)")


def check_fit(mesh: Mesh, resolution: int) -> None:
    """The "will it fit" check, before any work: at most :data:`MAX_TRIANGLES_PER_TEXEL`
    triangles per texel (one line naming the mesh, its triangles and the smallest R)."""
    n, R = len(mesh.faces), resolution
    if n > MAX_TRIANGLES_PER_TEXEL * R * R:
        need = int(np.ceil(np.sqrt(n / MAX_TRIANGLES_PER_TEXEL)))
        need += need % 2
        raise VrnError(
            f"{mesh.name}: {count(n, 'triangle')} do not fit {R}^2 = {R * R} texels (at most "
            f"{MAX_TRIANGLES_PER_TEXEL} triangles per texel); use a resolution of at least "
            f"{need}, or decimate the mesh"
        )


def build_atlas(
    mesh: Mesh,
    resolution: int,
    padding: int = 2,
    cache: bool = True,
    *,
    progress: bool = False,
    atlas_uv: str = "auto",
) -> Atlas:
    """The R x R atlas of ``mesh``: atlas UVs, triangle IDs with a ``padding``-texel gutter.

    ``atlas_uv`` (:data:`vrneural.atlas.config.MODES`): ``auto`` uses the mesh's own lightmap
    or UV set when it passes the checks of :mod:`vrneural.atlas.meshuv`, else generates one
    (:mod:`vrneural.atlas.generate`); ``mesh`` insists on the mesh's own (an unusable set is a
    :class:`VrnError`); ``charts`` and ``xatlas`` always generate. Returns an :class:`Atlas`
    whose mesh has vertices split at chart seams (faces in input order). ``stats`` holds
    coverage, charts, texels per triangle, timings (seconds), which UVs were used and why
    (``uv_source``, ``uv_reason``, ``unwrap_path``) and the texel density spread. Degenerate
    (zero UV area) triangles are kept, own no texel and are counted in
    ``stats["zero_area_triangles"]``. ``progress`` shows a tqdm bar over the stages.
    """
    check_int("resolution", resolution, MIN_RESOLUTION, MAX_RESOLUTION)
    check_int("padding", padding, 0, MAX_PADDING)
    check_choice("atlas_uv", atlas_uv, MODES)
    resolution, padding = int(resolution), int(padding)
    validate_mesh(mesh)
    check_fit(mesh, resolution)
    t0 = time.perf_counter()
    key = cache_key(mesh, resolution, padding, atlas_uv)
    if cache:
        hit = load_cached(mesh, key, resolution, padding)
        if hit is not None:  # stage times stay those of the original build
            hit.stats["build_total_s"] = hit.stats.get("total_s")
            hit.stats["total_s"] = time.perf_counter() - t0
            return hit
    with Stages(mesh.name, 8, progress) as bar:
        lay, uv_stats = choose_layout(mesh, resolution, padding, atlas_uv, bar)
        t2 = time.perf_counter()
        bar.stage(f"rasterize {resolution}^2 + gutter, {len(mesh.faces)} triangles")
        ids, rinfo = rasterize_ids(lay.uv, lay.faces, resolution, padding)
    t3 = time.perf_counter()
    split = split_mesh(mesh, lay.vmap, lay.faces)
    stats = {
        "mesh": mesh.name,
        "resolution": resolution,
        "padding": padding,
        "triangles": len(mesh.faces),
        "vertices_in": len(mesh.positions),
        "vertices_split": len(lay.vmap),
        **uv_stats,
        **layout_stats(split, lay.uv, resolution),
        **texel_stats(ids, rinfo),
        "unwrap_s": t2 - t0,
        "raster_s": rinfo["raster_s"],
        "sliver_s": rinfo["sliver_s"],
        "dilate_s": rinfo["dilate_s"],
        "total_s": t3 - t0,
        "cache": "off" if not cache else "miss",
    }
    atlas = Atlas(split, lay.uv, ids, resolution, padding, stats)
    if cache:
        path = store(atlas, lay.vmap, key)
        stats["cache_file"] = str(path) if path else None
    return atlas


def choose_layout(mesh: Mesh, R: int, padding: int, atlas_uv: str, bar):
    """``(Layout, stats)``: the mesh's own UVs when ``atlas_uv`` asks and they serve, else a
    generated layout; the stats say which and why."""
    reason = f"atlas_uv = {atlas_uv}"
    if atlas_uv in ("auto", "mesh"):
        name, uv = meshuv.candidate(mesh)
        if uv is None:
            if atlas_uv == "mesh":
                raise VrnError(f"{mesh.name}: atlas_uv = mesh, but {name}")
            reason = name
        else:
            bar.stage(f"check the mesh's {name}")
            rep = meshuv.inspect(mesh, uv, R)
            err = meshuv.insist_error(mesh, name, rep) if atlas_uv == "mesh" else None
            if err is not None:
                raise err
            refused = meshuv.refusal(name, rep, mesh.lightmap_uv is not None)
            if refused is None or atlas_uv == "mesh":
                try:
                    vmap, faces, out, info = meshuv.mesh_layout(mesh, uv, rep, R, padding)
                except ValueError:
                    refused = f"{name}: its {rep['charts']} islands do not fit {R}x{R}"
                else:
                    used = refused is None
                    stats = {
                        "uv_source": f"mesh {name}",
                        "uv_reason": "they passed the checks" if used else "atlas_uv = mesh",
                        "unwrap_path": [f"mesh {name}", info["uv_packing"]],
                        "mesh_uv_density_spread": rep["density_spread"],
                    }
                    return Layout(vmap, faces, out, info), stats
            reason = refused
    method = "xatlas" if atlas_uv == "xatlas" else "charts"
    lay = generated_layout(mesh, R, padding, method, bar)
    path = lay.info["unwrap_path"]
    source = "strips" if path[-1].startswith("strips") else path[-1].split(" ")[0]
    return lay, {"uv_source": source, "uv_reason": reason, "unwrap_path": path}


def layout_stats(split: Mesh, uv: np.ndarray, R: int) -> dict:
    """Charts (components over shared atlas-UV points), texels per metre and the texel
    density spread (95th / 5th percentile, :func:`vrneural.atlas.meshuv.density_spread`)."""
    faces = np.asarray(split.faces, np.int64)
    a_uv = uv_area(uv.astype(np.float64)[faces] * R)
    _, a3 = face_normals(np.asarray(split.positions, np.float64), faces)
    tpu = float(np.sqrt(np.abs(a_uv).sum() / max(a3.sum(), 1e-300)))
    return {
        "charts": int(uv_charts(uv, faces).max()) + 1,
        "texels_per_unit": tpu,
        "density_spread": density_spread(a_uv, a3),
    }


def texel_stats(ids: np.ndarray, rinfo: dict) -> dict:
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
