"""Rectangle packing of charts into R x R texels: a skyline packer over columns (numpy).

Every chart is packed as its bounding rectangle (charts are cut to fill their rectangles well
beforehand, :mod:`vrneural.atlas.layout`), grown by a gutter and rounded up to whole 2 x 2 blocks
(cells at even texel positions), so:

- two charts are at least ``padding + 1`` texels apart, and at least 3: a bilinear tap of one
  chart (a texel within L-inf distance 1 of it) is always nearer to it than to any other chart;
- every 2 x 2 block (one texel of mip level 1, and the runtime's shading block) lies in one
  chart's cell.

The packer is bottom-left on a skyline of column heights: charts sorted (longest side first,
by area, or shortest side first: :data:`ORDERS`, the best kept), each placed, in either
orientation, where its bottom is lowest (ties: leftmost), found with a sliding-window maximum
over the columns. :func:`pack_scale` finds by bisection the largest
scale (texels per world unit) at which all charts fit into R x R.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import maximum_filter1d

#: cells start and end on multiples of this many texels
ALIGN = 2
#: bisection steps of the scale search (the last scale that fits is kept)
SCALE_STEPS = 14


def chart_gap(padding: int) -> int:
    """Texels between the rectangles of two charts: ``padding + 1``, at least 3 (more than 2, so
    a texel within L-inf distance 1 of a chart, a bilinear tap of it, is nearer to it than to
    any other chart)."""
    return max(int(padding) + 1, 3)


def chart_offset(padding: int) -> int:
    """Texels from a cell's lower-left corner to its chart's rectangle."""
    return chart_gap(padding) // 2


def cell_sizes(extent: np.ndarray, scale: float, padding: int) -> np.ndarray:
    """[N, 2] int cell width/height in texels of charts of ``extent`` [N, 2] world units at
    ``scale`` texels per unit: the chart's rectangle plus :func:`chart_gap`, rounded up to a
    multiple of :data:`ALIGN`."""
    c = np.ceil(extent * scale - 1e-9).astype(np.int64) + chart_gap(padding)
    return c + (c % ALIGN)


#: orders in which :func:`pack_scale` tries to place the cells (the best result is kept;
#: measured at 1200^2: longest side first 62.2 / 66.4 / 65.1 % coverage on the knot / torus /
#: cloth, by area 60.6 / 66.3 / 63.5, shortest side first 59.9 / 64.7 / 61.8)
ORDERS = {
    "longest side": lambda c: np.lexsort((-np.min(c, 1), -np.max(c, 1))),
    "area": lambda c: np.argsort(-(c[:, 0] * c[:, 1]), kind="stable"),
    "shortest side": lambda c: np.lexsort((-np.max(c, 1), -np.min(c, 1))),
}


def skyline_pack(
    cells: np.ndarray, width: int, height: int, order: str = "longest side"
) -> tuple[np.ndarray, np.ndarray] | None:
    """Place rectangles ``cells`` [N, 2] (w, h; even) into ``width`` x ``height``, in the
    order ``order`` (:data:`ORDERS`).

    Returns ``(xy [N, 2] int lower-left corners, rotated [N] bool)`` or None when they do not
    fit. Works on a skyline of 2-texel columns (all sizes are even).
    """
    cols = width // ALIGN
    sky = np.zeros(cols, np.int64)
    n = len(cells)
    xy = np.zeros((n, 2), np.int64)
    rot = np.zeros(n, bool)
    for i in ORDERS[order](cells):
        w, h = int(cells[i, 0]), int(cells[i, 1])
        best = None
        for r, (cw, ch) in enumerate(((w, h), (h, w))):
            k = cw // ALIGN
            if k > cols or (r == 1 and w == h):
                continue
            # the bottom of a cell starting at column j: max(sky[j : j + k])
            m = maximum_filter1d(sky, size=k, origin=-(k // 2))[: cols - k + 1]
            j = int(np.argmin(m))
            y = int(m[j])
            if y + ch <= height and (best is None or (y, j) < (best[0], best[1])):
                best = (y, j, r, cw, ch)
        if best is None:
            return None
        y, j, r, cw, ch = best
        sky[j : j + cw // ALIGN] = y + ch
        xy[i] = (ALIGN * j, y)
        rot[i] = bool(r)
    return xy, rot


def pack_scale(
    extent: np.ndarray, R: int, padding: int, scale0: float
) -> tuple[float, np.ndarray, np.ndarray]:
    """The largest scale (bisection from ``scale0``, for each of :data:`ORDERS`) at which
    charts of ``extent`` [N, 2] (world units) fit R x R; returns ``(scale, xy [N, 2],
    rotated [N])``. ValueError when not even specks of charts fit (too many charts)."""
    best = None
    for order in ORDERS:
        found = _bisect(extent, R, padding, scale0, order)
        if found is not None and (best is None or found[0] > best[0]):
            best = found
    if best is None:
        raise ValueError("charts do not fit at any scale")
    return best


def _bisect(extent, R: int, padding: int, scale0: float, order: str):
    lo, hi = 0.0, None
    s = scale0
    found = None
    for _ in range(SCALE_STEPS):
        res = skyline_pack(cell_sizes(extent, s, padding), R, R, order)
        if res is not None:
            lo, found = s, (s, *res)
            s = s * 1.25 if hi is None else (s + hi) / 2
        else:
            hi = s
            s = (lo + hi) / 2 if lo > 0 else s * 0.7
    while found is None and s > 1e-12 * scale0:  # a scale so small every chart is a speck
        s *= 0.5
        res = skyline_pack(cell_sizes(extent, s, padding), R, R, order)
        if res is not None:
            found = (s, *res)
    return found
