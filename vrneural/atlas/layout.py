"""Charts -> atlas UVs: cut charts that fill their rectangle poorly, pack, split vertices.

Input: per-face corner coordinates of flattened charts (``cuv`` [F, 3, 2], world units, from
:mod:`vrneural.atlas.charts`, a mesh's own UV charts or another unwrapper) and the chart of
every face. Charts keep their shape and size relative to one another (one scale for the whole
atlas, so texel density stays what the flattening gave). Steps:

1. **Orient**: each chart is turned to its minimum-area bounding rectangle (rotating calipers
   over its convex hull).
2. **Cut**: a chart that fills less than :data:`FILL_TARGET` of its rectangle and is longer
   than :data:`MIN_CUT_TEXELS` at the expected scale is cut across its long side where the
   two halves' rectangles are smallest (a curved band becomes straighter pieces, a disc a
   square core and its rim); pieces are connected components. Repeated while it helps.
3. **Pack** (:mod:`vrneural.atlas.pack`): rectangles with gutters, the largest scale that fits.
"""

from __future__ import annotations

import numpy as np

from vrneural.atlas.charts import components
from vrneural.atlas.pack import chart_offset
from vrneural.atlas.raster import uv_area_px

#: charts filling less of their bounding rectangle than this are cut (when large enough)
FILL_TARGET = 0.8
#: ... and longer than this many texels at the expected scale
MIN_CUT_TEXELS = 48
#: rounds of cutting
CUT_ROUNDS = 6
#: most rotations :func:`min_area_angle` tries (memory: hull points x angles)
MAX_ANGLES = 360
#: expected fraction of the texture inside charts (first guess of the packing scale)
EXPECTED_FILL = 0.65


def uv_area(cuv: np.ndarray) -> np.ndarray:
    """[F] signed area of corner coordinates ``cuv`` [F, 3, 2]."""
    return 0.5 * uv_area_px(cuv)


def groups(label: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(order, starts)``: faces sorted by ``label``; group ``g`` is
    ``order[starts[g]:starts[g + 1]]`` (``starts`` has one more entry than groups)."""
    order = np.argsort(label, kind="stable")
    counts = np.bincount(label)
    return order, np.r_[0, np.cumsum(counts)]


def min_area_angle(pts: np.ndarray) -> float:
    """The rotation (radians) that turns 2D points ``pts`` [N, 2] to their minimum-area
    bounding rectangle (0 for degenerate point sets)."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = pts[ConvexHull(pts).vertices]
    except (QhullError, ValueError):
        return 0.0
    e = np.roll(hull, -1, axis=0) - hull
    ang = np.unique(np.mod(np.arctan2(e[:, 1], e[:, 0]), np.pi / 2))
    if len(ang) > MAX_ANGLES:  # a round hull of thousands of edges: a fine fan of angles
        ang = np.linspace(0.0, np.pi / 2, MAX_ANGLES, endpoint=False)
    c, s = np.cos(ang), np.sin(ang)
    x = hull[:, 0, None] * c + hull[:, 1, None] * s  # [H, A] coordinates along each angle
    y = -hull[:, 0, None] * s + hull[:, 1, None] * c
    area = np.ptp(x, axis=0) * np.ptp(y, axis=0)
    return float(ang[int(np.argmin(area))])


def rotate(p: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([p[..., 0] * c + p[..., 1] * s, -p[..., 0] * s + p[..., 1] * c], -1)


def orient(cuv: np.ndarray, chart: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each chart turned to its minimum-area rectangle and moved to the origin. Returns
    ``(cuv [F, 3, 2], extent [C, 2])`` (the chart's rectangle, width >= height)."""
    order, starts = groups(chart)
    out = np.empty_like(cuv)
    extent = np.zeros((len(starts) - 1, 2))
    for c in range(len(starts) - 1):
        f = order[starts[c] : starts[c + 1]]
        p = rotate(cuv[f], min_area_angle(cuv[f].reshape(-1, 2)))
        lo, hi = p.reshape(-1, 2).min(0), p.reshape(-1, 2).max(0)
        if hi[1] - lo[1] > hi[0] - lo[0]:  # width >= height
            p = np.stack([p[..., 1], -p[..., 0]], -1)
            lo, hi = p.reshape(-1, 2).min(0), p.reshape(-1, 2).max(0)
        out[f] = p - lo
        extent[c] = hi - lo
    return out, extent


def relabel(chart: np.ndarray, fa: np.ndarray, fb: np.ndarray) -> np.ndarray:
    """Connected components of faces with the same ``chart`` label over adjacency (fa, fb)."""
    same = chart[fa] == chart[fb]
    comp = components(len(chart), fa[same], fb[same])
    # components never join different labels (edges only within a label)
    _, out = np.unique(comp, return_inverse=True)
    return out.reshape(-1)


def cut_charts(
    cuv: np.ndarray,
    chart: np.ndarray,
    fa: np.ndarray,
    fb: np.ndarray,
    min_len: float,
) -> np.ndarray:
    """Step 2 of the module doc: the new chart of every face (connected pieces)."""
    area = np.abs(uv_area(cuv))
    for _ in range(CUT_ROUNDS):
        oriented, extent = orient(cuv, chart)
        a_c = np.bincount(chart, weights=area, minlength=len(extent))
        box = extent[:, 0] * extent[:, 1]
        fill = np.where(box > 0, a_c / np.maximum(box, 1e-300), 1.0)
        todo = np.flatnonzero((fill < FILL_TARGET) & (extent[:, 0] > min_len))
        if not len(todo):
            break
        order, starts = groups(chart)
        new = chart.copy()
        nxt = int(chart.max()) + 1
        for c in todo:
            f = order[starts[c] : starts[c + 1]]
            p = oriented[f]  # [n, 3, 2], long side along x
            cx = p[:, :, 0].mean(1)
            lo_f, hi_f = p.min(1), p.max(1)  # [n, 2] per-face boxes
            best = None
            for t in np.linspace(0.2, 0.8, 13):
                left = cx < t * extent[c, 0]
                if left.all() or not left.any():
                    continue
                cost = 0.0
                for side in (left, ~left):
                    lo, hi = lo_f[side].min(0), hi_f[side].max(0)
                    cost += float(np.prod(hi - lo))
                if best is None or cost < best[0]:
                    best = (cost, left)
            if best is not None:
                new[f[~best[1]]] = nxt
                nxt += 1
        if np.array_equal(new, chart):
            break
        chart = relabel(new, fa, fb)
    return chart


def chart_vertices(
    faces: np.ndarray, chart: np.ndarray, cuv: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split vertices per chart: ``(vmap [V'], faces' [F, 3], uv [V', 2])``; vertex ``i`` copies
    input vertex ``vmap[i]``, one per (chart, input vertex) pair, with that corner's coordinates."""
    key = chart[:, None].astype(np.int64) * (int(faces.max()) + 1) + faces
    uk, first, inv = np.unique(key.reshape(-1), return_index=True, return_inverse=True)
    vmap = uk % (int(faces.max()) + 1)
    uv = cuv.reshape(-1, 2)[first]
    return vmap, inv.reshape(-1, 3), uv


def place(
    cuv: np.ndarray, chart: np.ndarray, extent: np.ndarray, scale: float, xy, rotated, padding: int
) -> np.ndarray:
    """Texel coordinates [F, 3, 2] of oriented charts ``cuv`` (from :func:`orient`) packed by
    :func:`vrneural.atlas.pack.pack_scale` (``scale``, cell corners ``xy``, ``rotated``): each
    chart scaled, turned a quarter for a rotated cell, and moved into its cell, half the gap
    from its lower-left corner."""
    p = cuv * scale
    h = (extent[:, 1] * scale)[chart][:, None]
    turned = np.stack([h - p[..., 1], p[..., 0]], -1)
    p = np.where(rotated[chart][:, None, None], turned, p)
    return p + (xy[chart] + chart_offset(padding))[:, None, :]
