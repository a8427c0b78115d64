"""Scalable charting: faces grouped by normal direction into connected, flattenable charts.

numpy/scipy only, vectorised over faces, so a million triangles chart in seconds:

1. **Directions** (:func:`cover_directions`): a small set of unit axes such that every face
   normal lies within :data:`CONE_DEG` of one of them: greedy cover (the face farthest from
   every axis so far adds one), then a few area-weighted spherical k-means steps. A flat height
   field needs one axis, a sphere or a torus about twenty.
2. **Charts**: each face takes its nearest axis; faces of one axis that share an edge (after
   welding coincident positions, so material-UV and normal seams do not cut charts) form a
   chart (connected components). Components smaller than :data:`MIN_CHART_FACES` faces or
   :data:`MIN_CHART_FRACTION` of the area (the 1-2-texel islands of a noisy surface) join the
   neighbouring chart they share the longest border with, when every face of theirs is within
   :data:`MERGE_DEG` of its axis.
3. **Flattening**: orthographic projection along the chart's axis. A face at angle ``a`` to
   it is shortened by ``cos a`` in one direction, so its texel density is at most
   ``1 / sqrt(cos a)`` times that of a face square to the axis (1.11x at 35 degrees): the
   density spread the atlas states (``stats["density_spread"]``). A face that projects flipped
   or to nothing (beyond 90 degrees, possible only after a merge) becomes its own chart.

Self-overlap of a projected chart (a surface that winds round its axis, such as a helical
ramp) is found after packing by the rasterizer and such charts are split
(:func:`vrneural.atlas.layout.layout_charts`).
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

#: largest angle (degrees) between a face normal and its chart's projection axis
CONE_DEG = 45.0
#: a merged island may be this far (degrees) from the axis of the chart it joins
MERGE_DEG = 60.0
#: components with fewer faces than this are merged into a neighbour when possible
MIN_CHART_FACES = 24
#: ... and so are components with less than this fraction of the mesh's area
MIN_CHART_FRACTION = 2e-4
#: spherical k-means refinement steps of the axes
KMEANS_STEPS = 4


def face_normals(pos: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(unit normals [F, 3], areas [F])`` of triangles (float64; zero-area faces: +z, 0)."""
    p = pos[faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    ln = np.linalg.norm(n, axis=1)
    ok = ln > 0
    n[ok] /= ln[ok, None]
    n[~ok] = (0.0, 0.0, 1.0)
    return n, ln / 2.0


def face_adjacency(pos: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of faces sharing a manifold edge, ``(a [E], b [E])`` with ``a < b``; positions are
    welded first (vertices split at material-UV or normal seams still connect)."""
    _, weld = np.unique(pos, axis=0, return_inverse=True)
    w = weld.reshape(-1)[faces]
    e = np.concatenate([w[:, [0, 1]], w[:, [1, 2]], w[:, [2, 0]]])
    e.sort(axis=1)
    key = e[:, 0].astype(np.int64) * (int(w.max()) + 1) + e[:, 1]
    f = np.tile(np.arange(len(faces)), 3)
    order = np.argsort(key, kind="stable")
    key, f = key[order], f[order]
    start = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    size = np.diff(np.r_[start, len(key)])
    two = start[size == 2]  # an edge of exactly two faces (not a border, not non-manifold)
    a, b = f[two], f[two + 1]
    keep = a != b
    a, b = a[keep], b[keep]
    return np.minimum(a, b), np.maximum(a, b)


def cover_directions(normals: np.ndarray, areas: np.ndarray, cone_deg: float) -> np.ndarray:
    """[K, 3] unit axes with every normal within about ``cone_deg`` of one (module doc)."""
    cos_cone = np.cos(np.radians(cone_deg))
    mean = (normals * areas[:, None]).sum(0)
    axes = [
        mean / np.linalg.norm(mean) if np.linalg.norm(mean) > 1e-3 * areas.sum() else normals[0]
    ]
    best = normals @ axes[0]
    while True:
        far = int(np.argmin(best))
        if best[far] >= cos_cone or len(axes) >= 512:
            break
        # the new axis: the mean of the uncovered normals near the farthest one
        near = (normals @ normals[far] >= cos_cone) & (best < cos_cone)
        d = (normals[near] * areas[near, None]).sum(0)
        d = d / np.linalg.norm(d) if np.linalg.norm(d) > 0 else normals[far]
        if d @ normals[far] < cos_cone:
            d = normals[far]
        axes.append(d)
        best = np.maximum(best, normals @ d)
    ax = np.array(axes)
    for _ in range(KMEANS_STEPS if len(ax) > 1 else 0):
        lab = np.argmax(normals @ ax.T, axis=1)
        acc = np.zeros_like(ax)
        np.add.at(acc, lab, normals * areas[:, None])
        ln = np.linalg.norm(acc, axis=1)
        ok = ln > 0
        ax[ok] = acc[ok] / ln[ok, None]
    return ax


def components(n_faces: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """[F] connected component of each face over the face pairs ``(a, b)``."""
    g = coo_matrix((np.ones(len(a), np.int8), (a, b)), shape=(n_faces, n_faces))
    return connected_components(g, directed=False)[1]


def chart_faces(pos: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(chart [F] int64 0..C-1, axes [C, 3])``: the chart of every face and its projection
    axis (module doc, steps 1-2)."""
    normals, areas = face_normals(pos, faces)
    fa, fb = face_adjacency(pos, faces)
    axes = cover_directions(normals[areas > 0], areas[areas > 0], CONE_DEG)
    label = np.argmax(normals @ axes.T, axis=1)
    same = (label[fa] == label[fb]) & (areas[fa] > 0) & (areas[fb] > 0)
    comp = components(len(faces), fa[same], fb[same])
    comp_axis = np.zeros((comp.max() + 1, 3))
    comp_axis[comp] = axes[label]
    comp = _merge_islands(comp, comp_axis, normals, areas, fa, fb)
    _, chart = np.unique(comp, return_inverse=True)
    chart = chart.reshape(-1)
    axis = np.zeros((chart.max() + 1, 3))
    axis[chart] = comp_axis[comp]
    # a face beyond 80 degrees of its axis would project flipped or to a sliver, and a face
    # without area has no normal: each is a chart of its own
    bad = (np.einsum("ij,ij->i", normals, axis[chart]) < np.cos(np.radians(80.0))) | (areas <= 0)
    if bad.any():
        n0 = axis.shape[0]
        chart[bad] = n0 + np.arange(int(bad.sum()))
        axis = np.concatenate([axis, normals[bad]])
        used, chart = np.unique(chart, return_inverse=True)  # charts left empty: gone
        chart, axis = chart.reshape(-1), axis[used]
    return chart, axis


def _merge_islands(comp, comp_axis, normals, areas, fa, fb) -> np.ndarray:
    """Small components join the neighbour they share the longest border with (module doc)."""
    cos_merge = np.cos(np.radians(MERGE_DEG))
    comp = comp.copy()
    for _ in range(4):
        n_c = comp.max() + 1
        n_f = np.bincount(comp, minlength=n_c)
        a_c = np.bincount(comp, weights=areas, minlength=n_c)
        small = (n_f < MIN_CHART_FACES) | (a_c < MIN_CHART_FRACTION * areas.sum())
        ca, cb = comp[fa], comp[fb]
        cross = ca != cb
        ca, cb = ca[cross], cb[cross]
        # border pairs seen from the small side, toward a neighbour that is not smaller
        src = np.concatenate([ca, cb])
        dst = np.concatenate([cb, ca])
        cand = small[src] & ((~small[dst]) | (a_c[dst] > a_c[src]))
        src, dst = src[cand], dst[cand]
        if not len(src):
            break
        # the worst (smallest) cosine of any face of the island with the neighbour's axis
        f_of = np.argsort(comp, kind="stable")
        starts = np.r_[0, np.cumsum(n_f)[:-1]]
        key = src * n_c + dst
        uk, cnt = np.unique(key, return_counts=True)
        s_u, d_u = uk // n_c, uk % n_c
        worst = np.full(len(uk), 2.0)
        for i, (s, d) in enumerate(zip(s_u, d_u, strict=True)):
            fs = f_of[starts[s] : starts[s] + n_f[s]]
            worst[i] = float((normals[fs] @ comp_axis[d]).min())
        ok = worst >= cos_merge
        if not ok.any():
            break
        s_u, d_u, cnt = s_u[ok], d_u[ok], cnt[ok]
        order = np.lexsort((-cnt, s_u))  # per island, the longest border first
        s_u, d_u = s_u[order], d_u[order]
        first = np.r_[True, s_u[1:] != s_u[:-1]]
        target = np.arange(n_c)
        target[s_u[first]] = d_u[first]
        # follow chains (an island joining an island that joins a chart) to their end
        for _ in range(8):
            target = target[target]
        if np.array_equal(target, np.arange(n_c)):
            break
        comp = target[comp]
    return comp


def project(pos: np.ndarray, faces: np.ndarray, chart: np.ndarray, axis: np.ndarray):
    """Corner UVs ``[F, 3, 2]`` (float64, world units) by orthographic projection of each face
    along its chart's axis (in a right-handed frame, so a face facing the axis stays
    counter-clockwise)."""
    ax = axis[chart]  # [F, 3]
    helper = np.where(np.abs(ax[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    u = np.cross(helper, ax)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(ax, u)
    p = pos[faces]  # [F, 3, 3]
    return np.stack([np.einsum("fkd,fd->fk", p, u), np.einsum("fkd,fd->fk", p, v)], -1)
