"""GPU twin of the exact coverage step (wgpu render pipeline into r32uint) vs the CPU."""

from __future__ import annotations

import numpy as np
import pytest
from atlas_helpers import gpu_raster_coverage

from vrneural.atlas import EMPTY, build_atlas, builtin_mesh
from vrneural.atlas.raster import raster_coverage as cpu_raster_coverage

# llvmpipe snaps vertices to 1/256 texel (8 sub-pixel bits) before its top-left test, so a
# centre closer than that to an edge may land on the other side. Worst case measured on
# lavapipe (torus, 256^2): 0.0021 texel. We allow 2 snapping steps.
EDGE_TOL = 2.0 / 256


def _edge_distance(uv, faces, ids, R):
    """[N] distance (texels) from each texel centre to the nearest edge line of ids' triangle."""
    ys, xs = np.nonzero(ids != EMPTY)
    tri = uv.astype(np.float64)[faces[ids[ys, xs]].astype(np.int64)] * R
    p = np.stack([xs + 0.5, ys + 0.5], 1)
    d = np.full(len(p), np.inf)
    for k in range(3):
        a, b = tri[:, k], tri[:, (k + 1) % 3]
        e = b - a
        n = np.stack([-e[:, 1], e[:, 0]], 1) / np.linalg.norm(e, axis=1, keepdims=True)
        d = np.minimum(d, np.abs(np.sum((p - a) * n, axis=1)))
    out = np.full(ids.shape, np.inf)
    out[ys, xs] = d
    return out


@pytest.mark.gpu
@pytest.mark.parametrize("name", ["torus", "sphere"])
def test_gpu_and_cpu_rasterizers_agree(name):

    R = 256
    atlas = build_atlas(builtin_mesh(name), R, 2, cache=False)
    uv, faces = atlas.uv_atlas, atlas.mesh.faces
    cpu = cpu_raster_coverage(uv, faces, R)
    gpu = gpu_raster_coverage(uv, faces, R)
    assert gpu.shape == (R, R) and gpu.dtype == np.uint32
    differ = cpu != gpu
    # every disagreement is a centre on (within snapping of) an edge of both candidates
    near = (_edge_distance(uv, faces, cpu, R) < EDGE_TOL) | (cpu == EMPTY)
    near_gpu = (_edge_distance(uv, faces, gpu, R) < EDGE_TOL) | (gpu == EMPTY)
    assert np.all(near[differ] & near_gpu[differ])
    assert differ.sum() < 0.005 * np.count_nonzero(cpu != EMPTY)
    assert np.count_nonzero(cpu != EMPTY) > 0.3 * R * R


@pytest.mark.gpu
def test_gpu_top_left_rule_on_a_grid_through_centres():
    """Grid lines and diagonals exactly through texel centres: both rasterizers give each
    interior centre exactly one owner, and the same one (vertices are exactly representable,
    so no snapping ambiguity)."""
    from vrneural.atlas.builtin import grid_faces

    R = 32
    s = np.linspace(4.5 / R, 28.5 / R, 5)
    u, v = np.meshgrid(s, s, indexing="xy")
    uv = np.stack([u.ravel(), v.ravel()], 1).astype(np.float32)
    faces = grid_faces(4, 4)
    cpu = cpu_raster_coverage(uv, faces, R)
    gpu = gpu_raster_coverage(uv, faces, R)
    np.testing.assert_array_equal(gpu, cpu)


@pytest.mark.gpu
def test_gpu_raster_states_the_allowed_resolution_range():
    from vrneural.errors import VrnError
    from vrneural.gpu import get_device

    limit = get_device().limits["max-texture-dimension-2d"]
    uv = np.float32([[0.1, 0.1], [0.9, 0.1], [0.1, 0.9]])
    with pytest.raises(VrnError) as e:
        gpu_raster_coverage(uv, np.uint32([[0, 1, 2]]), limit + 2)
    assert str(e.value) == f"resolution = {limit + 2} is out of range; allowed [1, {limit}]"
