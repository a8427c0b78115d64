"""The relief a BTF's views show, measured without a height field (``--parallax auto``).

A BTF slice is rectified on the tile's reference plane: on a material with relief, texel ``u``
of a view ``wo`` at polar angle ``theta`` shows the surface point at ``u + z * d`` with ``d =
(wo.x, wo.y) / wo.z`` (:mod:`vrneural.parallax`; ``z`` the point's height in texels). So
between the most normal view and a grazing one each texel's content moves along ``d`` by its
height times ``|d|``. :func:`apparent_relief` finds that move per texel by block matching:
for every shift ``s`` along ``d`` (half-texel steps up to a quarter of the tile) the
normalised cross-correlation of a 7x7 window of the grazing slice with the normal slice
moved by ``s``; the best ``s / |d|`` is the texel's height. Only texels that match well
(correlation >= 0.6) in a window with contrast (its variance above the slice's median) count.
A match counts only where it is unique (every shift 2 texels or more away correlates at
least 0.1 less): a stripe along the ray matches at many shifts. The relief of one (light,
view) pair is the 5th-to-95th percentile range of those heights; the BTF's is their 25th
percentile over a few well-lit lights and the most grazing views (up to 76 degrees, the last
bin of ``bench quality``): the relief three quarters of the pairs show at least. Geometry
moves the content of every pair alike; a highlight that moves with the view (brushed metal)
fools only some of them.

A flat material's content does not move (its heights stay within a texel); a relief of
several texels moves by several texels at 65-76 degrees. The window smooths the heights, so
the estimate is below the height field's own 1st-99th percentile range: on the path-traced
pebbles it reads 2.5 at 32^2 (height field 4.9 texels) and 7.9 at 64^2 (9.9); the
synthetic presets 0-0.6 (docs/parallax.md).
"""

from __future__ import annotations

import numpy as np

from vrneural.sampling import sample_bilinear_wrap

#: the correlation window (texels per side)
WINDOW = 7
#: a texel counts when its best correlation reaches this
MIN_NCC = 0.6
#: a match counts only where every shift this many texels away correlates this much less
UNIQUE_TEXELS = 2.0
UNIQUE_MARGIN = 0.1
#: lights and grazing views measured
LIGHTS = 6
VIEWS = 4
#: the steepest view used, degrees
MAX_THETA = 76.0
#: larger slices are box-averaged to about this many texels per side first (the search costs
#: the cube of the side), and the relief scaled back
MAX_SIDE = 64


def _box(a: np.ndarray) -> np.ndarray:
    from scipy.ndimage import uniform_filter

    return uniform_filter(a, WINDOW, mode="wrap")


def _shifted(img: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """``img: [H, W]`` looked up bilinearly (wrap) at every texel moved by ``shift: [2]``
    texels (x, y)."""
    H, W = img.shape
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    uv = np.stack([(x + 0.5 + shift[0]) / W, (y + 0.5 + shift[1]) / H], -1)
    return sample_bilinear_wrap(img[..., None], uv)[..., 0]


def pair_relief(normal: np.ndarray, grazing: np.ndarray, d: np.ndarray) -> float | None:
    """The relief (texels) one pair of grey slices ``[H, W]`` shows: the normal view's and a
    grazing view's of the same light, ``d`` the grazing view's ``(wo.x, wo.y) / wo.z``. None
    where too few texels match (under 5%)."""
    H, W = normal.shape
    t = float(np.hypot(*d))
    if t < 1e-3:
        return None
    dhat = np.asarray(d, np.float64) / t
    a = grazing.astype(np.float64)
    ma = _box(a)
    va = _box(a * a) - ma * ma
    reach = max(1.0, min(H, W) / 4)
    shifts = np.arange(-reach, reach + 0.25, 0.5)
    nccs = []
    for s in shifts:
        b = _shifted(normal.astype(np.float64), s * dhat)
        mb = _box(b)
        vb = _box(b * b) - mb * mb
        nccs.append((_box(a * b) - ma * mb) / np.sqrt(np.maximum(va * vb, 1e-20)))
    ncc = np.stack(nccs)  # [S, H, W]
    i = ncc.argmax(0)
    best = np.take_along_axis(ncc, i[None], 0)[0]
    best_s = shifts[i]
    # unique: every shift 2 texels or more away matches clearly worse (a stripe pattern along
    # the ray, or a highlight that moves with the view, matches at many shifts)
    far = np.abs(shifts[:, None, None] - best_s[None]) >= UNIQUE_TEXELS
    rival = np.where(far, ncc, -np.inf).max(0)
    ok = (best >= MIN_NCC) & (best - rival >= UNIQUE_MARGIN) & (va > np.median(va))
    if ok.sum() < 0.05 * a.size:
        return None
    lo, hi = np.percentile(best_s[ok] / t, [5.0, 95.0])
    return float(hi - lo)


def apparent_relief(btf) -> float:
    """The relief (texels) the views of ``btf`` (a :class:`~vrneural.btf.format.Btf`) show:
    see the module docstring. 0 where nothing can be measured (no view beyond 30 degrees, or
    no pair with enough matching texels)."""
    vz = np.asarray(btf.view_dirs, np.float64)[:, 2]
    theta = np.degrees(np.arccos(np.clip(vz, -1, 1)))
    normal = int(np.argmax(vz))
    grazing = [v for v in np.argsort(-theta) if 30.0 < theta[v] <= MAX_THETA][:VIEWS]
    lz = np.asarray(btf.light_dirs, np.float64)[:, 2]
    lit = np.argsort(-lz)[: max(1, len(lz) // 2)]  # the better-lit half, spread over it
    lights = lit[np.linspace(0, len(lit) - 1, min(LIGHTS, len(lit))).round().astype(int)]
    H, W = btf.resolution
    k = max(1, -(-max(H, W) // MAX_SIDE))

    def grey(light, view):  # [H // k, W // k], box-averaged
        g = btf.slice(int(light), int(view)).mean(-1)[: H // k * k, : W // k * k]
        return g.reshape(H // k, k, W // k, k).mean((1, 3))

    found = []
    for light in lights:
        ref = grey(light, normal)
        for v in grazing:
            wo = np.asarray(btf.view_dirs[v], np.float64)
            r = pair_relief(ref, grey(light, v), wo[:2] / wo[2])
            if r is not None:
                found.append(r * k)
    return float(np.percentile(found, 25.0)) if found else 0.0
