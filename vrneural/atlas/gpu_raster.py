"""GPU cross-check of the triangle-ID rasterizer: a wgpu render pipeline into an r32uint
target, drawing the triangles in atlas-UV space (``shaders/atlas_ids.wgsl``).

Twin of :func:`vrneural.atlas.raster.raster_coverage` (step 1 only: exact centre coverage).
Both follow the top-left rule, so they agree on every texel centre not on an edge; on an edge
the GPU decides after snapping vertices to its sub-pixel grid (8 bits on llvmpipe), so a
centre within ~1/256 texel of an edge may go to the other triangle. Slivers and the gutter are
CPU-only (lavapipe has no conservative rasterization); the CPU rasterizer is the reference.
"""

from __future__ import annotations

import numpy as np

from vrneural.atlas.types import EMPTY
from vrneural.errors import check_range


def raster_coverage(uv: np.ndarray, faces: np.ndarray, R: int) -> np.ndarray:
    """[R, R] uint32 triangle IDs of texel centres inside triangles ``faces`` [F, 3] over
    atlas UVs ``uv`` [V, 2], EMPTY elsewhere (GPU)."""
    import wgpu

    from vrneural.gpu import get_device, load_wgsl, read_texture, upload_buffer
    from vrneural.gpu.pipelines import pipeline_cache

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
    mod = pipeline_cache().module(load_wgsl("atlas_ids.wgsl"), "atlas_ids")
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
