"""Generated atlas UVs, with a path that always ends in an atlas.

``method="charts"`` (the default): :mod:`vrneural.atlas.charts` (numpy, scales to millions of
triangles, cannot crash). ``method="xatlas"``: xatlas's charts (in a child process,
:mod:`vrneural.atlas.unwrap`); when xatlas crashes or fails, it is retried once on a copy of the
mesh moved by 1e-6 of its size with other chart options (the crash of jpcy/xatlas#146 depends
on exact positions), and then the mesh is charted by :mod:`vrneural.atlas.charts` in pieces
(one or more charts per connected part and normal direction). Either way the charts are cut and
packed by :mod:`vrneural.atlas.layout` / :mod:`vrneural.atlas.pack`; charts that overlap
themselves once flattened (found by the rasterizer) are cut in two and packed again. When the
charts cannot be packed at all (more charts than R x R has room for), the last resort is
:mod:`vrneural.atlas.strips`, which always succeeds. ``info["unwrap_path"]`` lists every step
taken, e.g. ``["xatlas crashed (SIGSEGV, signal 11)", "xatlas retry crashed (...)",
"charts"]``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from vrneural.atlas import layout as lay
from vrneural.atlas.charts import chart_faces, face_adjacency, face_normals, project
from vrneural.atlas.pack import pack_scale
from vrneural.atlas.raster import overlapping_faces
from vrneural.atlas.types import Mesh
from vrneural.atlas.unwrap import unwrap
from vrneural.atlas.visualize import uv_charts
from vrneural.errors import VrnError, count

#: rounds of cutting self-overlapping charts in two
OVERLAP_ROUNDS = 4
#: chart options of the xatlas retry (other than xatlas's defaults)
RETRY_OPTIONS = {"max_iterations": 0, "normal_seam_weight": 2.0}
#: the retry moves every vertex by up to this fraction of the mesh's extent
RETRY_JITTER = 1e-6


@dataclass
class Layout:
    """Atlas UVs of a mesh: vertex ``i`` copies input vertex ``vmap[i]``; faces keep their
    order."""

    vmap: np.ndarray  # [V'] int64
    faces: np.ndarray  # [F, 3] int64, indices into vmap / uv
    uv: np.ndarray  # [V', 2] float32 in [0, 1]
    info: dict


def generated_layout(mesh: Mesh, R: int, padding: int, method: str, bar) -> Layout:
    """Unwrap and pack ``mesh`` into R x R texels (module doc). ``bar``: the build's
    :class:`vrneural.atlas.progress.Stages`."""
    pos = np.asarray(mesh.positions, np.float64)
    faces = np.asarray(mesh.faces, np.int64)
    path: list[str] = []
    found = _xatlas(mesh, R, padding, path, bar) if method == "xatlas" else None
    bar.stage("adjacency")
    fa, fb = face_adjacency(pos, faces)
    if found is None:
        bar.stage("charts by normal direction")
        chart, axis = chart_faces(pos, faces)
        cuv = project(pos, faces, chart, axis)
        path.append("charts")
    else:
        cuv, chart = found
    try:
        px, chart, scale, cut = pack_charts(cuv, chart, fa, fb, R, padding, bar)
    except ValueError:
        from vrneural.atlas.strips import strip_layout

        path.append(f"strips ({int(chart.max()) + 1} charts do not fit {R}x{R})")
        bar.stage("strips")
        _, weld = np.unique(pos, axis=0, return_inverse=True)
        px, _ = strip_layout(weld.reshape(-1)[faces], fa, fb, R, padding)
        chart = np.arange(len(faces))
        scale, cut = float("nan"), 0
    # a triangle without 3D area gets none in the atlas either (all corners on one point; a
    # rotated line of three points would not stay exactly straight)
    flat = face_normals(pos, faces)[1] == 0
    px[flat] = px[flat][:, :1]
    vmap, new_faces, uv = lay.chart_vertices(faces, chart, px / R)
    info = {
        "charts_before_cuts": int(chart.max()) + 1 - cut,
        "texels_per_unit": float(scale),
        "unwrap_path": path,
    }
    return Layout(vmap, new_faces, np.clip(uv, 0.0, 1.0).astype(np.float32), info)


def pack_charts(cuv, chart, fa, fb, R: int, padding: int, bar):
    """Cut, orient and pack charts (module doc). Returns ``(texel coords [F, 3, 2], chart [F],
    scale (texels per unit), charts added by cuts)``; ValueError when they cannot fit."""
    area = float(np.abs(lay.uv_area(cuv)).sum())
    s0 = R * np.sqrt(lay.EXPECTED_FILL / max(area, 1e-300))
    n0 = int(chart.max()) + 1
    bar.stage(f"cut {n0} charts")
    chart = lay.cut_charts(cuv, chart, fa, fb, lay.MIN_CUT_TEXELS / s0)
    for _ in range(OVERLAP_ROUNDS):
        bar.stage(f"pack {int(chart.max()) + 1} charts")
        oriented, extent = lay.orient(cuv, chart)
        scale, xy, rot = pack_scale(extent, R, padding, s0)
        px = lay.place(oriented, chart, extent, scale, xy, rot, padding)
        bad = overlapping_faces(px, R)
        if not len(bad):
            break
        chart = _halve(cuv, chart, np.unique(chart[bad]), fa, fb)
    return px, chart, scale, int(chart.max()) + 1 - n0


def _halve(cuv, chart, charts, fa, fb) -> np.ndarray:
    """Cut each of ``charts`` across its long side at the middle (self-overlap)."""
    oriented, extent = lay.orient(cuv, chart)
    new = chart.copy()
    nxt = int(chart.max()) + 1
    for c in charts:
        f = np.flatnonzero(chart == c)
        right = oriented[f, :, 0].mean(1) > extent[c, 0] / 2
        if right.any() and not right.all():
            new[f[right]] = nxt
            nxt += 1
    return lay.relabel(new, fa, fb)


def _xatlas(mesh: Mesh, R: int, padding: int, path: list, bar):
    """xatlas's charts ``(cuv [F, 3, 2] mesh units, chart [F])``, retried once (module doc);
    None (with the reasons in ``path``) when both tries fail."""
    tries = (("xatlas", mesh, None), ("xatlas retry", _jittered(mesh), RETRY_OPTIONS))
    for label, m, options in tries:
        bar.stage(f"{label} ({len(mesh.faces)} triangles, child process)")
        try:
            rx = max(R, 1024)  # xatlas packs too; any size does, its charts are re-packed
            _, uv, info = unwrap(m, rx, padding, chart_options=options)
        except VrnError as e:
            path.append(f"{label} failed: {_short(str(e), mesh.name)}")
            continue
        faces = info["faces"]
        bad = overlapping_faces(uv.astype(np.float64)[faces] * rx, rx)
        if len(bad):  # xatlas gave folded or self-overlapping charts
            path.append(f"{label} failed: {count(len(bad), 'triangle')} overlap in its charts")
            continue
        path.append(label)
        cuv = uv.astype(np.float64)[faces] * (rx / info["texels_per_unit"])
        return cuv, uv_charts(uv, faces)
    return None


def _jittered(mesh: Mesh) -> Mesh:
    pos = np.asarray(mesh.positions, np.float64)
    ext = float(np.ptp(pos, axis=0).max())
    rng = np.random.default_rng(0)
    moved = pos + rng.uniform(-1.0, 1.0, pos.shape) * RETRY_JITTER * ext
    return dataclasses.replace(mesh, positions=moved.astype(np.float32))


def _short(message: str, name: str) -> str:
    """An unwrap error without the mesh name and the advice (the path records what happened)."""
    text = message.split(": ", 1)[1] if message.startswith(name) else message
    return text.split(", a known xatlas bug")[0]
