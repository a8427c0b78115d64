"""Shared checks for the atlas tests (the acceptance properties, written independently of the
rasterizer: plain barycentric sampling and the bilinear tap rule of a clamp-to-edge sampler),
and the GPU cross-check of the rasterizer (:func:`gpu_raster_coverage`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vrneural.atlas import EMPTY
from vrneural.errors import check_range


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


def gpu_raster_coverage(uv: np.ndarray, faces: np.ndarray, R: int) -> np.ndarray:
    """[R, R] uint32 triangle IDs of texel centres inside triangles ``faces`` [F, 3] over
    atlas UVs ``uv`` [V, 2], EMPTY elsewhere: a wgpu render pipeline into an r32uint target,
    drawing the triangles in atlas-UV space (``atlas_ids.wgsl`` next to this file).

    Twin of :func:`vrneural.atlas.raster.raster_coverage` (step 1 only: exact centre
    coverage). Both follow the top-left rule, so they agree on every texel centre not on an
    edge; on an edge the GPU decides after snapping vertices to its sub-pixel grid (8 bits on
    llvmpipe), so a centre within ~1/256 texel of an edge may go to the other triangle.
    Slivers and the gutter are CPU-only (lavapipe has no conservative rasterization); the CPU
    rasterizer is the reference.
    """
    import wgpu

    from vrneural.gpu import get_device, read_texture, upload_buffer
    from vrneural.gpu.pipelines import PIPELINES

    dev = get_device()
    limit = dev.limits["max-texture-dimension-2d"]
    check_range("resolution", R, 1, limit)  # the adapter's 2D texture limit
    verts = np.ascontiguousarray(uv.astype(np.float32)[np.asarray(faces, np.int64).reshape(-1)])
    vbuf = upload_buffer(verts, wgpu.BufferUsage.VERTEX, label="atlas uv")
    target = dev.create_texture(
        size=(R, R, 1),
        format="r32uint",
        usage=wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.COPY_SRC,
        label="atlas ids",
    )
    wgsl = Path(__file__).with_name("atlas_ids.wgsl").read_text()
    mod = PIPELINES.module(wgsl, "atlas_ids")
    pipe = dev.create_render_pipeline(
        layout="auto",
        vertex={
            "module": mod,
            "entry_point": "vs_main",
            "buffers": [
                {
                    "array_stride": 8,
                    "attributes": [{"format": "float32x2", "offset": 0, "shader_location": 0}],
                }
            ],
        },
        primitive={"topology": "triangle-list", "cull_mode": "none"},
        fragment={"module": mod, "entry_point": "fs_main", "targets": [{"format": "r32uint"}]},
        label="atlas ids",
    )
    enc = dev.create_command_encoder()
    rp = enc.begin_render_pass(
        color_attachments=[
            {
                "view": target.create_view(),
                "clear_value": (float(EMPTY), 0, 0, 0),
                "load_op": "clear",
                "store_op": "store",
            }
        ]
    )
    rp.set_pipeline(pipe)
    rp.set_vertex_buffer(0, vbuf)
    rp.draw(len(verts))
    rp.end()
    dev.queue.submit([enc.finish()])
    return read_texture(target).astype(np.uint32)
