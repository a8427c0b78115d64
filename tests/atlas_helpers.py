"""Shared checks for the atlas tests (the acceptance properties, written independently of the
rasterizer: plain barycentric sampling and the bilinear tap rule of a clamp-to-edge sampler)."""

from __future__ import annotations

import numpy as np

from vrneural.atlas import EMPTY


def random_points(atlas, rng, per_tri: int = 4):
    """[N] triangle ids and [N, 2] atlas-UV points strictly inside non-zero-area triangles."""
    uv = atlas.uv_atlas.astype(np.float64)[atlas.mesh.faces.astype(np.int64)]  # [F, 3, 2]
    a, b, c = uv[:, 0], uv[:, 1], uv[:, 2]
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    tri = np.repeat(np.flatnonzero(area != 0), per_tri)
    w = rng.uniform(0.01, 1.0, (len(tri), 3))
    w /= w.sum(axis=1, keepdims=True)
    return tri, np.einsum("nk,nkd->nd", w, uv[tri])


def bilinear_taps(points_uv: np.ndarray, R: int) -> tuple[np.ndarray, np.ndarray]:
    """The 4 texels a bilinear, clamp-to-edge sampler reads at ``points_uv`` [N, 2]: texel
    centres at (i + 0.5) / R, so taps are floor(p R - 0.5) and +1, clamped. Returns x, y [N, 4]."""
    p = points_uv * R - 0.5
    x0, y0 = np.floor(p[:, 0]).astype(np.int64), np.floor(p[:, 1]).astype(np.int64)
    xs = np.stack([x0, x0 + 1, x0, x0 + 1], 1).clip(0, R - 1)
    ys = np.stack([y0, y0, y0 + 1, y0 + 1], 1).clip(0, R - 1)
    return xs, ys


def gutter_failures(atlas, rng, per_tri: int = 4) -> int:
    """How many sampled points have a bilinear tap on an EMPTY texel (must be 0)."""
    _, pts = random_points(atlas, rng, per_tri)
    xs, ys = bilinear_taps(pts, atlas.resolution)
    return int(np.count_nonzero((atlas.tri_ids[ys, xs] == EMPTY).any(axis=1)))


def texels_per_triangle(atlas) -> np.ndarray:
    """[F] texels per triangle in the final ID texture (gutter included)."""
    ids = atlas.tri_ids[atlas.tri_ids != EMPTY]
    return np.bincount(ids, minlength=len(atlas.mesh.faces))


def uv_area(atlas) -> np.ndarray:
    uv = atlas.uv_atlas.astype(np.float64)[atlas.mesh.faces.astype(np.int64)]
    a, b, c = uv[:, 0], uv[:, 1], uv[:, 2]
    return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])


def linf_distance(atlas) -> np.ndarray:
    """[R, R] L-inf distance (texels) from each texel centre to its own triangle (0 inside,
    NaN for empty texels): the largest separation over the x, y axes and the three edge
    normals, each measured in the L-inf metric (separating-axis theorem)."""
    R = atlas.resolution
    ids = atlas.tri_ids.reshape(-1)
    out = np.full(R * R, np.nan)
    tex = np.flatnonzero(ids != EMPTY)
    tri = atlas.uv_atlas.astype(np.float64)[atlas.mesh.faces[ids[tex]].astype(np.int64)] * R
    c = np.stack([tex % R + 0.5, tex // R + 0.5], 1)
    d = np.maximum(tri.min(axis=1) - c, c - tri.max(axis=1)).max(axis=1)
    for k in range(3):
        a, b, o = tri[:, k], tri[:, (k + 1) % 3], tri[:, (k + 2) % 3]
        n = np.stack([a[:, 1] - b[:, 1], b[:, 0] - a[:, 0]], 1)  # edge normal
        n *= np.sign(np.sum(n * (a - o), axis=1))[:, None]  # pointing away from the 3rd vertex
        sep = np.sum(n * (c - a), axis=1) / np.abs(n).sum(axis=1)
        d = np.maximum(d, sep)
    out[tex] = np.maximum(d, 0.0)
    return out.reshape(R, R)
