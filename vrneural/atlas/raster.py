"""Exact CPU rasterizer of the triangle-ID texture, sliver coverage, gutter, barycentrics.

This is the reference: vectorised numpy over (triangle, texel) candidate pairs, streamed in
chunks so memory stays bounded at any resolution. Pixel space is ``p = uv * R``; texel
``(x, y)`` has its centre at ``(x + 0.5, y + 0.5)`` (row ``y`` first in memory, no flip).

1. **Coverage**: a texel belongs to a triangle when its centre is inside. Centres exactly on an
   edge follow the *top-left rule* in this y-down pixel space (the rule of D3D/Vulkan/WebGPU
   rasterizers): with the triangle wound so that ``cross(b - a, c - a) > 0``, an edge
   ``a -> b`` owns its centres when ``dy < 0`` or ``dy == 0 and dx > 0``. The edge function of
   a shared edge is evaluated in a canonical vertex order, so two triangles sharing an edge
   never both own (or both miss) a centre on it. If UVs overlap, the lowest triangle ID wins.
2. **Slivers**: every triangle with non-zero UV area that owns no texel centre takes one texel
   whose square it touches (L-inf distance from the centre <= 0.5), preferring an empty texel,
   else one whose owner keeps at least one other texel, nearest first.
3. **Gutter**: every still-empty texel whose centre is within L-inf distance ``padding`` of a
   triangle gets the ID of the nearest such triangle (ties: lowest ID). A bilinear tap of a
   point ``q`` inside a triangle is a texel whose centre is within L-inf distance 1 of ``q``,
   so ``padding >= 1`` guarantees that all four taps have valid IDs.

The L-inf distance from a centre ``c`` to a triangle is exact: the separating-axis distance over
the triangle's edge normals (scaled by the normal's L1 norm) and the x/y axes.
"""

from __future__ import annotations

import time

import numpy as np

from vrneural.atlas.types import EMPTY

#: candidate (triangle, texel) pairs per chunk; bounds memory to ~100 MB
CHUNK_PAIRS = 1 << 20


def uv_area_px(px: np.ndarray) -> np.ndarray:
    """[F] signed area x2 in texels^2 of triangles ``px`` [F, 3, 2] (pixel space)."""
    a, b, c = px[:, 0], px[:, 1], px[:, 2]
    return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])


def _pairs(px: np.ndarray, tris: np.ndarray, R: int, grow: float):
    """Yield (tri [P], x [P], y [P]) candidate pairs, in chunks of about CHUNK_PAIRS: per
    triangle and texel row, the texel centres within L-inf distance ``grow`` of the triangle's
    span in that row (the triangle clipped to the band ``row centre +- grow``), clipped to the
    texture. Spans, not bounding boxes: a long diagonal needle costs its length, not its box."""
    tris = np.asarray(tris, np.int64)
    if not len(tris):
        return
    t_px = px[tris]
    y_lo = np.clip(np.floor(t_px[:, :, 1].min(1) - 0.5 - grow), 0, R - 1).astype(np.int64)
    y_hi = np.clip(np.ceil(t_px[:, :, 1].max(1) - 0.5 + grow), 0, R - 1).astype(np.int64)
    n_rows = np.maximum(y_hi - y_lo + 1, 0)
    r_end = np.cumsum(n_rows)
    for r0 in range(0, int(r_end[-1]), CHUNK_ROWS):
        r = np.arange(r0, min(r0 + CHUNK_ROWS, int(r_end[-1])), dtype=np.int64)
        k = np.searchsorted(r_end, r, side="right")
        y = y_lo[k] + r - (r_end[k] - n_rows[k])
        xl, xr = _band_span(t_px[k], y + 0.5 - grow, y + 0.5 + grow)
        x0 = np.clip(np.ceil(xl - 0.5 - grow - 1e-9), 0, R).astype(np.int64)
        x1 = np.clip(np.floor(xr - 0.5 + grow + 1e-9), -1, R - 1).astype(np.int64)
        count = np.maximum(x1 - x0 + 1, 0)
        ends = np.cumsum(count)
        total = int(ends[-1]) if len(ends) else 0
        for p0 in range(0, total, CHUNK_PAIRS):
            p = np.arange(p0, min(p0 + CHUNK_PAIRS, total), dtype=np.int64)
            j = np.searchsorted(ends, p, side="right")
            yield tris[k[j]], x0[j] + p - (ends[j] - count[j]), y[j]


#: (triangle, row) spans per chunk of :func:`_pairs`
CHUNK_ROWS = 1 << 18


def _band_span(tri: np.ndarray, y0: np.ndarray, y1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(x_min, x_max)`` [N] of triangles ``tri`` [N, 3, 2] clipped to the bands
    ``y0 <= y <= y1`` [N] (inf, -inf where a band misses its triangle): the extremes are among
    the vertices inside the band and the edges' crossings of its two lines."""
    vx, vy = tri[:, :, 0], tri[:, :, 1]
    inb = (vy >= y0[:, None]) & (vy <= y1[:, None])
    lo = np.where(inb, vx, np.inf).min(1)
    hi = np.where(inb, vx, -np.inf).max(1)
    for e in range(3):
        ax, ay = vx[:, e], vy[:, e]
        bx, by = vx[:, (e + 1) % 3], vy[:, (e + 1) % 3]
        dy = by - ay
        safe = np.where(dy != 0, dy, 1.0)
        for yl in (y0, y1):
            t = (yl - ay) / safe
            ok = (dy != 0) & (t >= 0) & (t <= 1)
            x = ax + t * (bx - ax)
            lo = np.minimum(lo, np.where(ok, x, np.inf))
            hi = np.maximum(hi, np.where(ok, x, -np.inf))
    return lo, hi


def _edge_setup(px: np.ndarray) -> dict:
    """Per-triangle edge equations ``w = A x + B y + C`` ([3, F] each), top-left flags,
    1 / L1 norm of each edge normal, and the bounding box, for triangles wound positive.

    Each edge's coefficients are computed from its lexicographically smaller endpoint and
    negated for the other direction, so a shared edge gets exactly negated equations in its
    two triangles: a centre on it goes to exactly one of them (the top-left one).
    """
    A, B, C, TL, IL1 = (np.empty((3, len(px))) for _ in range(5))
    for k in range(3):
        a, b = px[:, k], px[:, (k + 1) % 3]
        swap = (a[:, 0] > b[:, 0]) | ((a[:, 0] == b[:, 0]) & (a[:, 1] > b[:, 1]))
        s = np.where(swap[:, None], b, a)
        e = np.where(swap[:, None], a, b)
        dx, dy = e[:, 0] - s[:, 0], e[:, 1] - s[:, 1]
        sign = np.where(swap, -1.0, 1.0)
        # w(p) = dx (py - sy) - dy (px - sx), inside >= 0 for positive winding
        A[k], B[k], C[k] = -dy * sign, dx * sign, (dy * s[:, 0] - dx * s[:, 1]) * sign
        odx, ody = dx * sign, dy * sign
        TL[k] = (ody < 0) | ((ody == 0) & (odx > 0))
        l1 = np.abs(dx) + np.abs(dy)
        IL1[k] = 1.0 / np.where(l1 > 0, l1, 1.0)
    return {
        "A": A,
        "B": B,
        "C": C,
        "TL": TL.astype(bool),
        "IL1": IL1,
        "lo": px.min(axis=1),
        "hi": px.max(axis=1),
    }


def _edge_terms(es: dict, t: np.ndarray, cx: np.ndarray, cy: np.ndarray, need_dist: bool = True):
    """Per pair: inside mask (top-left rule) and L-inf distance to the triangle (0 inside)."""
    inside = np.ones(len(t), bool)
    dist = np.zeros(len(t)) if need_dist else None
    for k in range(3):
        w = es["A"][k][t] * cx
        w += es["B"][k][t] * cy
        w += es["C"][k][t]
        inside &= (w > 0) | ((w == 0) & es["TL"][k][t])
        if need_dist:
            w *= es["IL1"][k][t]
            np.maximum(dist, -w, out=dist)
    if need_dist:
        lo, hi = es["lo"][t], es["hi"][t]
        np.maximum(dist, lo[:, 0] - cx, out=dist)
        np.maximum(dist, cx - hi[:, 0], out=dist)
        np.maximum(dist, lo[:, 1] - cy, out=dist)
        np.maximum(dist, cy - hi[:, 1], out=dist)
    return inside, dist


def _setup(uv: np.ndarray, faces: np.ndarray, R: int):
    """Pixel-space triangles [F, 3, 2] wound positive, signed areas x2 [F], edge setup."""
    return _wound(uv.astype(np.float64)[np.asarray(faces, dtype=np.int64)] * R)


def _wound(px: np.ndarray):
    """Triangles ``px`` [F, 3, 2] (a float64 copy) wound positive, their signed areas x2 [F]
    as given, and the edge setup."""
    q = px.astype(np.float64)
    area = uv_area_px(q)
    flip = area < 0
    q[flip] = q[flip][:, [0, 2, 1]]
    return q, area, _edge_setup(q)


def _coverage(px, es, tris, R: int) -> tuple[np.ndarray, int]:
    """Step 1: IDs [R*R] of texel centres inside ``tris`` (top-left rule, lowest ID on
    overlap) and the number of (texel, triangle) claims."""
    ids = np.full(R * R, EMPTY, np.uint32)
    claims = 0
    for t, x, y in _pairs(px, tris, R, 0.0):
        inside, _ = _edge_terms(es, t, x + 0.5, y + 0.5, need_dist=False)
        claims += int(inside.sum())
        np.minimum.at(ids, (y * R + x)[inside], t[inside].astype(np.uint32))
    return ids, claims


def raster_coverage(uv: np.ndarray, faces: np.ndarray, R: int) -> np.ndarray:
    """[R, R] uint32: step 1 alone (exact centre coverage, no sliver fixes, no gutter).

    The numpy twin of the GPU cross-check ``gpu_raster_coverage`` in tests/atlas_helpers.py
    (same signature), which draws the triangles with a wgpu render pipeline.
    """
    px, area, es = _setup(uv, faces, R)
    return _coverage(px, es, np.flatnonzero(area != 0), R)[0].reshape(R, R)


#: resolution of the overlap check of :func:`overlap_pairs` (at most R)
OVERLAP_CHECK_RES = 1024


def overlap_pairs(px: np.ndarray, R: int) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of triangles ``px`` [F, 3, 2] (texel coordinates in R x R) that claim the same
    texel centre, checked at ``min(R, OVERLAP_CHECK_RES)`` texels (coordinates scaled):
    ``(a [P], b [P])`` with ``a < b``, one pair (lowest and highest claimant) per texel."""
    s = min(1.0, OVERLAP_CHECK_RES / R)
    Rc = max(int(np.ceil(R * s)), 1)
    q, area, es = _wound(px.astype(np.float64) * s)
    tris = np.flatnonzero(area != 0)
    hits = np.zeros(Rc * Rc, np.int32)
    lo = np.full(Rc * Rc, EMPTY, np.uint32)
    hi = np.zeros(Rc * Rc, np.uint32)
    for t, x, y in _pairs(q, tris, Rc, 0.0):
        inside, _ = _edge_terms(es, t, x + 0.5, y + 0.5, need_dist=False)
        tex, tt = (y * Rc + x)[inside], t[inside].astype(np.uint32)
        hits += np.bincount(tex, minlength=Rc * Rc).astype(np.int32)
        np.minimum.at(lo, tex, tt)
        np.maximum.at(hi, tex, tt)
    two = np.flatnonzero(hits >= 2)
    return lo[two].astype(np.int64), hi[two].astype(np.int64)


def overlapping_faces(px: np.ndarray, R: int) -> np.ndarray:
    """Sorted indices of triangles ``px`` [F, 3, 2] that share a texel centre with another
    (:func:`overlap_pairs`)."""
    a, b = overlap_pairs(px, R)
    return np.unique(np.concatenate([a, b]))


def chart_conflicts(px: np.ndarray, faces: np.ndarray, chart: np.ndarray, R: int) -> int:
    """Texels within L-inf distance 1 of two different charts: a bilinear tap there reads
    another chart (``px`` [F, 3, 2] texel coordinates, ``faces`` [F, 3] for the chart borders,
    ``chart`` [F]). Only chart-border triangles are tested (overlaps are found apart)."""
    q, area, es = _wound(px)
    border = np.intersect1d(boundary_faces(np.asarray(faces, np.int64)), np.flatnonzero(area != 0))
    lo = np.full(R * R, np.iinfo(np.int64).max, np.int64)
    hi = np.full(R * R, -1, np.int64)
    for t, x, y in _pairs(q, border, R, 1.0):
        _, d = _edge_terms(es, t, x + 0.5, y + 0.5)
        near = d <= 1.0
        tex, c = (y * R + x)[near], chart[t[near]]
        np.minimum.at(lo, tex, c)
        np.maximum.at(hi, tex, c)
    return int(np.count_nonzero((hi >= 0) & (lo != hi)))


def rasterize_ids(
    uv: np.ndarray, faces: np.ndarray, R: int, padding: int
) -> tuple[np.ndarray, dict]:
    """The triangle-ID texture of triangles ``faces`` [F, 3] over atlas UVs ``uv`` [V, 2].

    Returns ``(tri_ids [R, R] uint32, info)``; ``info`` counts zero-area triangles, sliver
    fixes, overlapping texels and gutter texels, times the three steps (seconds), and holds
    ``owned`` [F] (texels per triangle before the gutter) and ``nonzero_area`` [F] bool.
    See the module docstring for the rules.
    """
    t0 = time.perf_counter()
    px, area, es = _setup(uv, faces, R)
    good = np.flatnonzero(area != 0)
    ids, claims = _coverage(px, es, good, R)
    covered = ids != EMPTY
    t1 = time.perf_counter()
    counts = np.bincount(ids[ids != EMPTY], minlength=len(faces))
    overlap = claims - int(counts.sum())
    slivers = np.flatnonzero((counts == 0) & (area != 0))
    fixed = _cover_slivers(px, es, slivers, ids, counts, R)
    owned = counts.copy()  # texels per triangle after sliver fixes, before the gutter
    t2 = time.perf_counter()
    border = np.intersect1d(boundary_faces(faces), good)
    gutter = dilate_ids(ids, px, es, border, R, padding)
    t3 = time.perf_counter()
    # texels outside their triangle (sliver + gutter): how far the runtime extrapolates
    out_tex = np.flatnonzero(~covered & (ids != EMPTY))
    extra = _centre_barycentrics(px[ids[out_tex]], out_tex, R) if len(out_tex) else np.zeros((1, 3))
    info = {
        "zero_area_triangles": int(len(faces) - len(good)),
        "sliver_fixes": fixed,
        "slivers_unfixed": int(len(slivers) - fixed),
        "overlap_texels": overlap,
        "gutter_texels": gutter,
        "max_abs_barycentric": float(np.abs(extra).max()),
        "raster_s": t1 - t0,
        "sliver_s": t2 - t1,
        "dilate_s": t3 - t2,
        "owned": owned,
        "nonzero_area": area != 0,
    }
    return ids.reshape(R, R), info


def boundary_faces(faces: np.ndarray) -> np.ndarray:
    """Indices of faces with an edge used by no other face (chart borders and holes)."""
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    key = e[:, 0].astype(np.int64) * (int(faces.max()) + 1) + e[:, 1]
    _, inv, cnt = np.unique(key, return_inverse=True, return_counts=True)
    once = cnt[inv.reshape(-1)] == 1
    return np.unique(np.flatnonzero(once) % len(faces))


def dilate_ids(ids, px, es, tris, R: int, padding: int) -> int:
    """Fill empty texels of ``ids`` [R*R] within L-inf distance ``padding`` of triangles
    ``tris`` with the nearest one (ties: lowest ID). Returns the number of texels filled.

    Only chart-border triangles need testing: the nearest point of a chart to a texel outside
    it lies on a border edge.
    """
    if padding <= 0 or len(tris) == 0:
        return 0
    best_d = np.full(R * R, np.inf)
    best_t = np.full(R * R, EMPTY, np.uint32)
    for t, x, y in _pairs(px, tris, R, float(padding)):
        tex = y * R + x
        empty = ids[tex] == EMPTY
        t, tex, cx, cy = t[empty], tex[empty], x[empty] + 0.5, y[empty] + 0.5
        _, d = _edge_terms(es, t, cx, cy)
        near = d <= padding
        if near.any():
            _keep_nearest(best_d, best_t, tex[near], d[near], t[near])
    fill = (ids == EMPTY) & (best_t != EMPTY)
    ids[fill] = best_t[fill]
    return int(fill.sum())


def _keep_nearest(best_d, best_t, tex, d, t) -> None:
    """Update per-texel (distance, triangle) minima; ties go to the lower triangle ID."""
    order = np.lexsort((t, d, tex))
    tex, d, t = tex[order], d[order], t[order]
    first = np.ones(len(tex), bool)
    first[1:] = tex[1:] != tex[:-1]
    tex, d, t = tex[first], d[first], t[first].astype(np.uint32)
    better = (d < best_d[tex]) | ((d == best_d[tex]) & (t < best_t[tex]))
    best_d[tex[better]] = d[better]
    best_t[tex[better]] = t[better]


def _cover_slivers(px, es, slivers, ids, counts, R: int) -> int:
    """Give each triangle in ``slivers`` one texel it touches (see module docstring)."""
    if len(slivers) == 0:
        return 0
    t, x, y = (np.concatenate(c) for c in zip(*_pairs(px, slivers, R, 0.5), strict=True))
    _, d = _edge_terms(es, t, x + 0.5, y + 0.5)
    keep = d <= 0.5
    t, tex, d = t[keep], (y * R + x)[keep], d[keep]
    order = np.lexsort((d, t))
    t, tex = t[order], tex[order]
    starts = np.searchsorted(t, slivers)
    ends = np.searchsorted(t, slivers, side="right")
    fixed = 0
    for tri, s0, s1 in zip(slivers, starts, ends, strict=True):
        options = tex[s0:s1]
        owners = ids[options]
        free = options[owners == EMPTY]
        if len(free) == 0:
            ok = owners != EMPTY
            ok[ok] = counts[owners[ok]] > 1
            free = options[ok]
        if len(free) == 0:
            continue
        texel = free[0]
        if ids[texel] != EMPTY:
            counts[ids[texel]] -= 1
        ids[texel] = tri
        counts[tri] += 1
        fixed += 1
    return fixed


def texel_barycentrics(atlas) -> np.ndarray:
    """[R, R, 3] float32 barycentrics of each texel centre in its triangle's atlas UVs.

    Gutter and sliver texels lie outside their triangle: their barycentrics extrapolate (some
    weights negative). Empty texels get zeros. This is the numpy twin of what the runtime's
    texture-space shader computes from ``tri_ids`` and the triangle buffers.
    """
    R = atlas.resolution
    ids = atlas.tri_ids.reshape(-1)
    out = np.zeros((R * R, 3), np.float32)
    tex = np.flatnonzero(ids != EMPTY)
    if len(tex) == 0:
        return out.reshape(R, R, 3)
    tri = atlas.uv_atlas.astype(np.float64)[atlas.mesh.faces[ids[tex]].astype(np.int64)] * R
    out[tex] = _centre_barycentrics(tri, tex, R)
    return out.reshape(R, R, 3)


def _centre_barycentrics(tri: np.ndarray, tex: np.ndarray, R: int) -> np.ndarray:
    """[N, 3] float64 barycentrics of texel centres ``tex`` (flat indices) in pixel-space
    triangles ``tri`` [N, 3, 2] (zero-area triangles give finite garbage, never NaN)."""
    cx, cy = tex % R + 0.5, tex // R + 0.5
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    den = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    den = np.where(den == 0, 1.0, den)
    l1 = ((cx - a[:, 0]) * (c[:, 1] - a[:, 1]) - (cy - a[:, 1]) * (c[:, 0] - a[:, 0])) / den
    l2 = ((b[:, 0] - a[:, 0]) * (cy - a[:, 1]) - (b[:, 1] - a[:, 1]) * (cx - a[:, 0])) / den
    return np.stack([1.0 - l1 - l2, l1, l2], axis=1)
