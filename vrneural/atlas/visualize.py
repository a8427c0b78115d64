"""PNG visualisation of a triangle-ID texture and chart labelling."""

from __future__ import annotations

import numpy as np

from vrneural.atlas.raster import texel_barycentrics
from vrneural.atlas.types import EMPTY, Atlas


def chart_ids(atlas: Atlas) -> np.ndarray:
    """[F] int: the chart of each face: connected components over shared atlas-UV points.

    Split vertices alone are not enough: xatlas welds coincident input vertices (e.g. across a
    material-UV seam) into one chart while keeping them as separate output vertices with
    identical atlas UVs. Different charts never share an atlas-UV point (they are padded apart).
    """
    return uv_charts(atlas.uv_atlas, atlas.mesh.faces)


def uv_charts(uv: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """[F] int: :func:`chart_ids` of faces [F, 3] over UVs [V, 2] (components over shared UV
    points), numbered by first face."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    _, weld = np.unique(uv, axis=0, return_inverse=True)
    faces = weld.reshape(-1)[np.asarray(faces, dtype=np.int64)]
    F, V = len(faces), int(weld.max()) + 1
    rows = np.repeat(np.arange(F), 3)
    g = coo_matrix((np.ones(3 * F), (rows, F + faces.reshape(-1))), shape=(F + V, F + V))
    _, labels = connected_components(g, directed=False)
    return labels[:F]


def _hash_colors(keys: np.ndarray) -> np.ndarray:
    """[N, 3] uint8 pseudo-random bright colours from integer keys (deterministic)."""
    h = keys.astype(np.uint64) * np.uint64(0x9E3779B97F4A7C15)
    h ^= h >> np.uint64(29)
    rgb = np.stack([(h >> np.uint64(s)) & np.uint64(0xFF) for s in (8, 24, 40)], axis=-1)
    return (64 + rgb.astype(np.uint16) * 191 // 255).astype(np.uint8)


def atlas_image(atlas: Atlas, by: str = "triangle", gutter: np.ndarray | None = None) -> np.ndarray:
    """[R, R, 3] uint8: a colour per triangle (``by="triangle"``) or per chart (``"chart"``),
    black where empty; texels in ``gutter`` ([R, R] bool) at half brightness. Row 0 is the
    top row of the image, i.e. atlas v = 0 at the top (the texture's memory order)."""
    ids = atlas.tri_ids
    valid = ids != EMPTY
    key = ids.astype(np.int64)
    if by == "chart":
        key = np.where(valid, chart_ids(atlas)[np.where(valid, ids, 0)], 0)
    img = _hash_colors(key)
    img[~valid] = 0
    if gutter is not None:
        img[gutter & valid] //= 2
    return img


def gutter_mask(atlas: Atlas) -> np.ndarray:
    """[R, R] bool: texels whose centre is outside their triangle (gutter and sliver texels)."""
    bary = texel_barycentrics(atlas)
    return (atlas.tri_ids != EMPTY) & (bary.min(axis=-1) < -1e-6)
