"""Extreme geometry: degenerate, sliver, single and huge meshes, non-manifold meshes, NaN/Inf
vertices and objects far from the world origin. Each mesh goes through the atlas stage
(``make_mesh`` + ``build_atlas``) and the GPU texture-space kernel, compared with its numpy twin.
Positions in metres.
"""

from __future__ import annotations

import warnings

import numpy as np

from extremes.fixtures import finite_nonneg, quad_atlas, translate
from extremes.shading import GpuShade
from vrneural.material import random_material
from vrneural.runtime import reference as ref

EYE = np.float64([0.3, 0.4, 1.5])
LIGHT = np.float64([[0.2, 0.5, 1.0]])
LC = np.full((1, 3), 3.0)


def atlas_and_shade(pos, faces, uv=None, res: int = 32, drop_degenerate: bool = True) -> dict:
    """make_mesh -> build_atlas (no cache) -> GPU kernel vs twin. Returns measurements."""
    from vrneural.atlas import MeshWarning, build_atlas, make_mesh

    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always", MeshWarning)
        mesh = make_mesh("extreme", pos, faces, uv=uv, drop_degenerate=drop_degenerate)
    at = build_atlas(mesh, res, padding=1, cache=False)
    mat = random_material(2)
    got = GpuShade(at, mat).shade(np.eye(4), EYE, LIGHT, LC)
    want, cnt = ref.shade_texture_space(at, mat, np.eye(4), EYE, LIGHT, LC)
    w16 = want.astype(np.float16).astype(np.float32)
    err = np.abs(got - w16) / (np.abs(w16) + 1e-2)
    covered = int((at.tri_ids != 0xFFFFFFFF).sum())
    return {
        "ok": finite_nonneg(got) and bool(err.max() <= 2 * 2.0**-10),
        "triangles": len(mesh.faces),
        "warnings": [str(x.message) for x in w],
        "texels_covered": covered,
        "blocks_shaded": int(cnt[0]),
        "max_rel_err_vs_twin": float(err.max()),
        "tangents_finite": bool(np.isfinite(mesh.tangents).all()),
        "atlas": at,
    }


def _plain(r: dict) -> dict:
    return {k: v for k, v in r.items() if k != "atlas"}


def case_geo_zero_area_3d(quick: bool) -> dict:
    """Two good triangles plus a collinear one and one with a repeated index."""
    pos = np.float64([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 0, 0]])
    faces = [[0, 1, 2], [1, 3, 2], [0, 1, 4], [2, 2, 3]]
    dropped = atlas_and_shade(pos, faces)
    kept = atlas_and_shade(pos, faces, drop_degenerate=False)
    ok = dropped["ok"] and kept["ok"] and dropped["triangles"] == 2 and kept["triangles"] == 4
    return {
        "ok": ok,
        "dropped_warning": dropped["warnings"][:1],
        "kept_max_err": kept["max_rel_err_vs_twin"],
        "note": "skipped with a counted MeshWarning (or kept: no texels)",
    }


def case_geo_zero_area_uv(quick: bool) -> dict:
    """A triangle whose material UVs coincide (no tangent from UVs: fallback frame)."""
    pos = np.float64([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    uv = np.float64([[0, 0], [1, 0], [0.5, 0.5], [0.5, 0.5]])
    r = atlas_and_shade(pos, [[0, 1, 2], [1, 3, 2]], uv=uv)
    r["ok"] = r["ok"] and r["tangents_finite"]
    return _plain(r)


def case_geo_sliver(quick: bool) -> dict:
    """Aspect ratio 1e-5 slivers next to a normal triangle."""
    pos = np.float64([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1e-5, 0], [0, 1e-5, 0]])
    r = atlas_and_shade(pos, [[0, 1, 2], [0, 1, 3], [0, 3, 4]], res=64)
    return _plain(r)


def case_geo_one_triangle(quick: bool) -> dict:
    r = atlas_and_shade(np.float64([[0, 0, 0], [1, 0, 0], [0, 1, 0]]), [[0, 1, 2]], res=8)
    r["ok"] = r["ok"] and r["blocks_shaded"] > 0
    return _plain(r)


def case_geo_non_manifold(quick: bool) -> dict:
    """Three triangles on one edge (a fin) plus a bow-tie vertex shared by two fans."""
    pos = np.float64(
        [[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -1, 0], [0.5, 0, 1], [1.5, 1, 0], [1.5, -1, 0]]
    )
    faces = [[0, 1, 2], [1, 0, 3], [0, 1, 4], [1, 5, 6]]
    r = atlas_and_shade(pos, faces, res=64)
    r["ok"] = r["ok"] and r["triangles"] == 4
    return _plain(r)


def case_geo_nan_vertex(quick: bool) -> dict:
    from vrneural.atlas import make_mesh

    make_mesh("nan", [[0, 0, 0], [1, np.nan, 0], [0, 1, 0]], [[0, 1, 2]])
    return {"ok": False}


def case_geo_inf_vertex_file(quick: bool) -> dict:
    """An OBJ file with an Inf coordinate: load_mesh rejects it naming the file."""
    import tempfile
    from pathlib import Path

    from vrneural.atlas import load_mesh

    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "inf.obj"
        p.write_text("v 0 0 0\nv 1 0 inf\nv 0 1 0\nf 1 2 3\n")
        load_mesh(p)
    return {"ok": False}


def far_origin(offset: float = 1e5, precision: str = "f32", R: int = 32) -> dict:
    """The same quad, eye and light translated by ``offset`` m on every axis: the GPU kernel's
    radiance must match the untranslated one (camera-relative coordinates)."""
    at = quad_atlas(R)
    mat = random_material(6)
    g = GpuShade(at, mat, precision)
    base = g.shade(np.eye(4), EYE, LIGHT, LC)
    o = np.full(3, offset)
    far = g.shade(translate(*o), EYE + o, LIGHT + o, LC)
    twin, _ = ref.shade_texture_space(at, mat, translate(*o), EYE + o, LIGHT + o, LC)
    rel = np.abs(far - base) / (np.abs(base) + 1e-2)
    return {
        "finite": finite_nonneg(far),
        "max_rel_diff": float(rel.max()),
        "twin_max_rel_diff": float((np.abs(twin - base) / (np.abs(base) + 1e-2)).max()),
        "f32_spacing_m": float(np.spacing(np.float32(offset))),
    }


def case_geo_far_origin(quick: bool) -> dict:
    r = far_origin(1e5)
    # the offsets cancel in float64 before rounding: identical up to one f16 ulp of storage
    ok = r["finite"] and r["max_rel_diff"] <= 2.0**-10 and r["twin_max_rel_diff"] <= 2.0**-9
    return {"ok": ok, **{k: v for k, v in r.items() if k != "finite"}}


def grid_mesh(n_tris: int):
    """A wavy square grid of about ``n_tris`` triangles (positions [V, 3], faces [F, 3])."""
    k = max(1, int(np.sqrt(n_tris / 2)))
    y, x = np.meshgrid(np.linspace(0, 1, k + 1), np.linspace(0, 1, k + 1), indexing="ij")
    z = 0.05 * np.sin(6 * x) * np.cos(5 * y)
    pos = np.stack([x, y, z], -1).reshape(-1, 3)
    i = np.arange(k)[:, None] * (k + 1) + np.arange(k)[None, :]
    a, b, c, d = i, i + 1, i + k + 1, i + k + 2
    faces = np.concatenate([np.stack([a, b, c], -1), np.stack([b, d, c], -1)]).reshape(-1, 3)
    return pos, faces


def case_geo_many_triangles(quick: bool) -> dict:
    """1M triangles (20k with --quick) through atlas + kernel (R = 2048, 512 quick)."""
    pos, faces = grid_mesh(20_000 if quick else 1_000_000)
    r = atlas_and_shade(pos, faces, res=512 if quick else 2048)
    r["ok"] = r["ok"] and r["blocks_shaded"] > 0
    r["atlas_s"] = float(r["atlas"].stats.get("total_s", 0.0))
    return _plain(r)
