"""A mesh's own UVs as its atlas: which set, whether it serves, kept as it is or re-packed.

The candidate: the mesh's lightmap set (glTF ``TEXCOORD_1``, :attr:`Mesh.lightmap_uv`), else
its material UVs when they came from the file (glTF ``TEXCOORD_0``, OBJ ``vt``); built-in and
box-projected UVs are never candidates. Checks at the atlas resolution R (:func:`inspect`):

- **zero-area** UV triangles (of non-zero 3D area) and **flipped** ones (wound against the rest
  of their chart: a fold);
- **overlap**: triangles sharing a texel centre (at ``min(R, 1024)``), within one chart
  (a fold or a self-overlapping chart) or between charts (stacked or mirrored islands);
- **texel density spread**: the ratio of the 95th to the 5th percentile (area-weighted) of the
  linear texel density ``sqrt(uv area / 3D area)`` over triangles;
- **packing**: a set inside [0, 1] whose charts are apart (no texel within L-inf distance 1
  of two charts, so bilinear taps never read another chart) is kept as it is when its coverage
  is at least :data:`KEEP_PACKING` of what re-packing its charts gives (:mod:`vrneural.atlas.pack`,
  same chart shapes and relative sizes); otherwise it is re-packed.

``atlas_uv = "auto"`` uses the set when it has no zero-area, flipped or overlapping triangles
(overlapping islands of a lightmap set are re-packed apart; a material set whose islands
overlap shares texture space on purpose and is not used), a density spread of at most
:data:`MAX_DENSITY_SPREAD`, and, for material UVs, stays inside [0, 1] (outside, they tile a
material). ``"mesh"`` insists: no candidate, zero-area, flipped or overlapping triangles are a
one-line :class:`VrnError` naming the mesh, the set and the count.
"""

from __future__ import annotations

import numpy as np

from vrneural.atlas import layout as lay
from vrneural.atlas.charts import face_normals
from vrneural.atlas.pack import pack_scale
from vrneural.atlas.raster import chart_conflicts, overlap_pairs
from vrneural.atlas.types import Mesh
from vrneural.atlas.visualize import uv_charts
from vrneural.errors import VrnError, count

#: largest texel density spread (95th / 5th percentile) that ``auto`` accepts
MAX_DENSITY_SPREAD = 2.0
#: the asset's own packing is kept when it covers at least this fraction of a re-packing's
KEEP_PACKING = 0.85


def candidate(mesh: Mesh) -> tuple[str, np.ndarray] | tuple[str, None]:
    """``(name of the set, uv [V, 2] float64)``, or ``(why there is none, None)``."""
    if mesh.lightmap_uv is not None:
        return "lightmap UVs (TEXCOORD_1)", np.asarray(mesh.lightmap_uv, np.float64)
    if mesh.uv_source == "file":
        return "UVs (TEXCOORD_0 / vt)", np.asarray(mesh.uv, np.float64)
    why = {
        "builtin": "a built-in mesh (its UVs tile the material)",
        "box": "the mesh has no UVs of its own",
    }
    return why.get(mesh.uv_source, f"its UVs are {mesh.uv_source}"), None


def density_spread(uv_area: np.ndarray, area3d: np.ndarray) -> float:
    """95th / 5th percentile (area-weighted) of ``sqrt(|uv_area| / area3d)`` over triangles
    of non-zero area in both (1.0 = uniform texel density)."""
    ok = (area3d > 0) & (np.abs(uv_area) > 0)
    if ok.sum() < 2:
        return 1.0
    d = np.sqrt(np.abs(uv_area[ok]) / area3d[ok])
    order = np.argsort(d)
    cw = np.cumsum(area3d[ok][order])
    cw /= cw[-1]
    lo, hi = d[order][np.searchsorted(cw, [0.05, 0.95]).clip(0, len(d) - 1)]
    return float(hi / lo)


def uv_chart_labels(mesh: Mesh, uv: np.ndarray) -> np.ndarray:
    """[F] chart of each face: components over shared vertices, vertices welded by (position,
    UV) so a split for normals alone does not cut a chart."""
    key = np.concatenate([np.asarray(mesh.positions, np.float64), uv], axis=1)
    _, weld = np.unique(key, axis=0, return_inverse=True)
    return uv_charts(weld.reshape(-1, 1).astype(np.float64), np.asarray(mesh.faces, np.int64))


def inspect(mesh: Mesh, uv: np.ndarray, R: int) -> dict:
    """The checks of the module doc (counts, spread, charts) for UV set ``uv`` [V, 2]."""
    faces = np.asarray(mesh.faces, np.int64)
    cuv = uv[faces]
    a_uv = lay.uv_area(cuv)
    _, a3 = face_normals(np.asarray(mesh.positions, np.float64), faces)
    chart = uv_chart_labels(mesh, uv)
    # a chart's orientation: the sign of most of its UV area
    side = np.bincount(chart, weights=a_uv)
    zero = (a_uv == 0) & (a3 > 0)
    flipped = (a_uv * side[chart] < 0) & ~zero
    lo, hi = uv.min(0), uv.max(0)
    span = float(max(np.max(hi - lo), 1e-300))
    # overlap at R texels over the set's own [0, 1] square (or its bounding square)
    origin = np.minimum(lo, 0.0)
    scale = R / max(1.0, span + float(np.max(origin * -1.0, initial=0.0)))
    a, b = overlap_pairs((cuv - origin) * scale, R)
    same = chart[a] == chart[b]
    return {
        "charts": int(chart.max()) + 1,
        "chart": chart,
        "zero_area": int(zero.sum()),
        "flipped": int(flipped.sum()),
        "overlap_same_chart": len(np.unique(np.concatenate([a[same], b[same]]))),
        "overlap_between_charts": len(np.unique(np.concatenate([a[~same], b[~same]]))),
        "inside_unit_square": bool(lo.min() >= 0.0 and hi.max() <= 1.0),
        "density_spread": density_spread(a_uv, a3),
    }


def refusal(name: str, rep: dict, is_lightmap: bool) -> str | None:
    """Why ``auto`` does not use the set (None: it serves)."""
    if rep["zero_area"]:
        return f"{name}: {count(rep['zero_area'], 'triangle')} with zero UV area"
    if rep["flipped"]:
        return f"{name}: {count(rep['flipped'], 'triangle')} flipped (folded UVs)"
    if rep["overlap_same_chart"]:
        return f"{name}: {count(rep['overlap_same_chart'], 'triangle')} overlap within a chart"
    if rep["overlap_between_charts"] and not is_lightmap:
        n = rep["overlap_between_charts"]
        return f"{name}: {count(n, 'triangle')} of different islands overlap (shared texture)"
    if not is_lightmap and not rep["inside_unit_square"]:
        return f"{name} leave [0, 1] (they tile a material)"
    if rep["density_spread"] > MAX_DENSITY_SPREAD:
        return (
            f"{name}: texel density varies {rep['density_spread']:.1f}x (95th/5th percentile), "
            f"more than {MAX_DENSITY_SPREAD:g}x"
        )
    return None


def insist_error(mesh: Mesh, name: str, rep: dict) -> VrnError | None:
    """The one-line error of ``atlas_uv = "mesh"`` for a set that cannot be an atlas."""
    bad = []
    if rep["zero_area"]:
        bad.append(f"{count(rep['zero_area'], 'triangle')} with zero UV area")
    if rep["flipped"]:
        bad.append(f"{count(rep['flipped'], 'triangle')} flipped")
    n = rep["overlap_same_chart"] + rep["overlap_between_charts"]
    if n:
        bad.append(f"{count(n, 'triangle')} overlapping others")
    if not bad:
        return None
    return VrnError(
        f"{mesh.name}: its {name} cannot be the atlas: {', '.join(bad)} of "
        f"{len(mesh.faces)}; atlas_uv = mesh needs a non-overlapping, unfolded UV set "
        "(auto or charts unwraps the mesh instead)"
    )


def mesh_layout(mesh: Mesh, uv: np.ndarray, rep: dict, R: int, padding: int):
    """``(vmap, faces, uv [V, 2] float32 in [0, 1], info)``: the set as it is or re-packed."""
    faces = np.asarray(mesh.faces, np.int64)
    chart = rep["chart"]
    cuv = uv[faces]
    area = float(np.abs(lay.uv_area(cuv)).sum())
    oriented, extent = lay.orient(cuv, chart)
    s0 = R * np.sqrt(lay.EXPECTED_FILL / max(area, 1e-300))
    try:
        scale, xy, rot = pack_scale(extent, R, padding, s0)
        repacked = scale * scale * area / (R * R)
    except ValueError:
        repacked = 0.0
    own = area  # its coverage of [0, 1]^2 as it is
    conflicts = None
    if rep["inside_unit_square"] and not rep["overlap_between_charts"]:
        conflicts = chart_conflicts(cuv * R, faces, chart, R)
    keep = conflicts == 0 and own >= KEEP_PACKING * repacked
    info = {"uv_packing": "as in the file" if keep else "re-packed"}
    if not keep:
        if repacked == 0.0:
            raise ValueError("the set's charts do not fit")
        why = (
            "islands overlap"
            if rep["overlap_between_charts"]
            else "outside [0, 1]"
            if not rep["inside_unit_square"]
            else f"{conflicts} texels between islands closer than a bilinear tap"
            if conflicts
            else f"its packing covers {100 * own:.0f}%, re-packed {100 * repacked:.0f}%"
        )
        info["uv_packing"] = f"re-packed ({why})"
        px = lay.place(oriented, chart, extent, scale, xy, rot, padding)
        vmap, new_faces, out = lay.chart_vertices(faces, chart, px / R)
        return vmap, new_faces, np.clip(out, 0, 1).astype(np.float32), info
    vmap = np.arange(len(uv))
    return vmap, faces, uv.astype(np.float32), info
