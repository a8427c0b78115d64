"""`vrneural atlas MESH --res 1200 -o atlas.png`: atlas UVs (the mesh's own or generated),
rasterize IDs, write a PNG, stats."""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path

from vrneural.atlas.config import MAX_PADDING, AtlasConfig, check_texture_resolution
from vrneural.config import add_config_args, config_dict, config_from_args
from vrneural.errors import VrnError, check_range
from vrneural.outputs import atomic_path, check_output, write_json

STAT_LINES = (
    ("uv_source", "UVs", "{}"),
    ("uv_reason", "because", "{}"),
    ("coverage_pct", "coverage", "{:.2f} % of texels inside triangles"),
    ("filled_pct", "with gutter", "{:.2f} % of texels have an ID"),
    ("charts", "charts", "{}"),
    ("triangles", "triangles", "{}"),
    ("texels_per_triangle_min", "texels/tri min", "{}"),
    ("texels_per_triangle_median", "texels/tri median", "{:g}"),
    ("triangles_without_texels", "tris w/o texels", "{}"),
    ("zero_area_triangles", "zero-area tris", "{}"),
    ("max_abs_barycentric", "max |barycentric|", "{:.2f} (gutter extrapolation)"),
    ("density_spread", "density spread", "{:.2f}x (texels per area, 95th / 5th percentile)"),
    ("cache", "cache", "{}"),
    ("total_s", "time", "{:.2f} s"),
)


def register(sub) -> None:
    p = sub.add_parser(
        "atlas",
        help="atlas a mesh (its own UVs or an unwrap), rasterize its triangle-ID texture, write a "
        "PNG + stats",
        description="Build the atlas of MESH (a file: OBJ/PLY/GLB/GLTF, or a built-in name: "
        "sphere, torus, plane, cloth, highpoly) at R x R texels with a gutter, from the mesh's "
        "own lightmap/UV set when it serves (--atlas-uv), else from an unwrap; write a PNG of "
        "the triangle-ID texture (a colour per triangle or chart, gutter at half brightness, "
        "black = empty; row 0 = atlas v 0 at the top) and print coverage, charts and "
        "texels-per-triangle stats. A file with several meshes gives OUT-<k>.png per mesh.",
    )
    p.add_argument("mesh", metavar="MESH", help="mesh file or built-in mesh name")
    p.add_argument("-o", "--output", required=True, help="output PNG path")
    add_config_args(p, AtlasConfig)
    p.add_argument(
        "--color",
        choices=("triangle", "chart"),
        default="triangle",
        help="colour per triangle or per chart (default: triangle)",
    )
    p.add_argument(
        "--crease-angle",
        type=float,
        default=None,
        metavar="DEG",
        help="for meshes without normals: neighbouring triangles more than DEG degrees apart "
        "meet at a hard edge, in [0, 180] (0 = flat facets; default: 60 for files, 180 for "
        "the built-ins). A file's own normals are kept",
    )
    p.add_argument("--json", action="store_true", help="print the stats as JSON")
    p.add_argument(
        "--force",
        action="store_true",
        help="overwrite existing outputs (PNGs and the .config.json sidecar)",
    )
    p.set_defaults(func=run)


def _meshes(spec: str, crease: float | None = None):
    from vrneural.atlas import BUILTIN_MESHES, builtin_mesh, load_mesh

    if spec in BUILTIN_MESHES and not Path(spec).exists():
        return [builtin_mesh(spec, crease)]
    head = spec.rsplit(":", 1)[0]
    if not Path(spec).exists() and ":" in spec and Path(head).is_file():
        from vrneural.runtime.assets import get_mesh  # FILE:NAME, as in a scene file

        return [get_mesh(spec, field="MESH", crease_deg=crease)]
    if not Path(spec).exists() and not Path(spec).suffix:
        raise VrnError(
            f"{spec}: no such file, and not a built-in mesh ({', '.join(BUILTIN_MESHES)})"
        )
    return load_mesh(spec, crease)


def run(args) -> int:
    import imageio.v3 as iio

    from vrneural.atlas.build import build_atlas  # the stage (scipy), when it runs
    from vrneural.atlas.visualize import atlas_image, gutter_mask
    from vrneural.runtime.assets import collapsed_triangles, lost_triangles

    cfg = config_from_args(AtlasConfig, args)
    check_texture_resolution("--res", cfg.res)
    check_range("--padding", cfg.padding, 0, MAX_PADDING)
    if args.crease_angle is not None:
        check_range("--crease-angle", args.crease_angle, 0, 180)
    out = Path(args.output)
    if out.suffix.lower() != ".png":
        raise VrnError(f"{out}: output must be a .png file")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        meshes = _meshes(args.mesh, args.crease_angle)
        n = len(meshes)  # one mesh: OUT; several: OUT-<k>.png each (OUT itself not written)
        outs = [out] if n == 1 else [out.with_name(f"{out.stem}-{k}{out.suffix}") for k in range(n)]
        for o in [*outs, sidecar_path(out)]:  # every file written, before any is
            check_output(o, args.force)
        results = []
        for mesh, o in zip(meshes, outs, strict=True):
            atlas = build_atlas(
                mesh,
                cfg.res,
                cfg.padding,
                cache=cfg.cache,
                progress=True,
                atlas_uv=cfg.atlas_uv,
            )
            img = atlas_image(atlas, by=args.color, gutter=gutter_mask(atlas))
            with atomic_path(o) as tmp:
                iio.imwrite(tmp, img, extension=".png")
            results.append({"output": str(o), **atlas.stats})
    notes = [" ".join(str(w.message).splitlines()) for w in caught]
    if cfg.padding == 0:
        notes.append("--padding 0: bilinear lookups at chart edges read texels with no triangle")
    for r in results:  # the same rule as `vrneural run`'s warning
        lost = lost_triangles(r, cfg.res, "a renderer shows their neighbours' shading")
        if lost:
            notes.append(f"{r['mesh']}: {lost}; raise --res")
        flat = collapsed_triangles(r)
        if flat:
            notes.append(f"{r['mesh']}: {flat}")
    # what write_config writes, at the path checked before anything was written (even where
    # OUT of a multi-mesh file is a directory: it is not written then)
    doc = {
        **config_dict(cfg),
        "crease_angle": args.crease_angle,
        "stats": results,
        "warnings": notes,
    }
    write_json(sidecar_path(out), doc)
    for n in notes:  # stderr: stdout is the stats alone (valid JSON with --json)
        print(f"warning: {n}", file=sys.stderr)
    if args.json:
        print(json.dumps(results[0] if len(results) == 1 else results, indent=2))
    else:
        for r in results:
            print(f"{r['mesh']} -> {r['output']} ({r['resolution']}^2, padding {r['padding']})")
            for key, label, fmt in STAT_LINES:
                print(f"  {label:18s} {fmt.format(r[key])}")
            when = " (of the cached build)" if r["cache"] == "hit" else ""
            print(f"  {'unwrap path':18s} {' -> '.join(r['unwrap_path'])}")
            print(
                f"  {'stage times':18s} unwrap {r['unwrap_s']:.2f} s, "
                f"raster {r['raster_s']:.2f} s, slivers {r['sliver_s']:.3f} s, "
                f"dilate {r['dilate_s']:.2f} s{when}"
            )
    return 0


def sidecar_path(out: Path) -> Path:
    """``<out>.config.json``: config, stats and warnings of every mesh (the name
    :func:`vrneural.config.write_config` gives it beside a file)."""
    return out.with_name(out.name + ".config.json")
