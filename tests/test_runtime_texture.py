"""Texture-space pass: generated WGSL vs its numpy twin, analytic Lambertian, counters."""

import numpy as np
import pytest
from runtime_helpers import quad_atlas

from vrneural.material import lambertian_material, random_material
from vrneural.runtime import reference

EYE = np.float32([0.3, 0.2, 1.5])
LP = np.float32([[0.5, 0.5, 1.0], [-1.0, 0.0, 0.5]])
LC = np.float32([[1.0, 0.5, 0.2], [2.0, 2.0, 2.0]])
TILING = (2.0, 2.0, 0.1, 0.0)


def _f16(x):
    return x.astype(np.float16).astype(np.float32)


def test_twin_lambertian_plane_is_analytic():
    at = quad_atlas(16)
    mat = lambertian_material((0.8, 0.5, 0.2))
    lp = np.float32([[0.1, -0.2, 0.7]])
    rad, cnt = reference.shade_texture_space(at, mat, np.eye(4), EYE, lp, np.float32([[3, 3, 3]]))
    ys, xs = np.nonzero(rad[..., 3] > 0)
    # texel -> block centre in atlas uv -> plane position (the quad spans atlas [1/8, 7/8])
    cu = (2 * (xs // 2) + 1) / 16
    cv = (2 * (ys // 2) + 1) / 16
    p = np.stack([(cu - 0.125) / 0.75 - 0.5, (cv - 0.125) / 0.75 - 0.5, 0 * cu], -1)
    lv = lp[0] - p
    d2 = (lv**2).sum(-1)
    want = np.float32([0.8, 0.5, 0.2]) / np.pi * (lv[:, 2] / np.sqrt(d2) * 3 / d2)[:, None]
    np.testing.assert_allclose(rad[ys, xs, :3], want, rtol=2e-5, atol=1e-6)
    assert cnt[0] == len(xs) // 4 and cnt[1] == 0


@pytest.mark.gpu
@pytest.mark.parametrize("arch", ["coarse_fine", "single"])
@pytest.mark.parametrize(
    "precision, weights, filtering",
    # storage weights: the comparison baseline (streamed ones: the test after next)
    [("f32", "constants", "exact"), ("f16", "constants", "exact"), ("f32", "storage", "exact"),
     ("f32", "constants", "hardware"), ("f16", "constants", "hardware")],
    ids=["f32-constants", "f16-constants", "f32-storage", "f32-hardware", "f16-hardware"],
)  # fmt: skip
def test_gpu_matches_twin(arch, precision, weights, filtering):
    from vrneural.runtime import texture_pass

    at = quad_atlas(32)
    mat = random_material(3, arch, output="log1p" if arch == "single" else "linear")
    model = np.eye(4, dtype=np.float32)
    model[:3, 3] = [0.05, -0.02, 0.0]
    args = (at, mat, model, EYE, LP, LC, TILING, precision)
    got, cg = texture_pass.shade_texture_space(*args, weights=weights, filtering=filtering)
    want, cw = reference.shade_texture_space(*args)
    np.testing.assert_array_equal(cg, cw)
    assert np.isfinite(got).all()
    np.testing.assert_array_equal(got[..., 3], want[..., 3])  # same texels written
    err = np.abs(got[..., :3] - _f16(want[..., :3]))
    scale = np.abs(want[..., :3]) + 1e-2
    if precision == "f32":
        # Same f32 math in another order, then both rounded to f16 (rgba16float): llvmpipe
        # measured <= 1 f16 ulp (2^-10 relative). Allow 2 ulps.
        assert (err / scale).max() <= 2 * 2.0**-10
    else:
        # GPU accumulates in f16, the twin rounds per layer and sums lights in f32: llvmpipe
        # measured 0.11 relative at the smallest values (|y| ~ 1e-2), 0.04 on the single net.
        assert (err / scale).max() <= 0.25
        assert np.median(err / scale) <= 0.01


@pytest.mark.gpu
@pytest.mark.parametrize("precision", ["f32", "f16"])
@pytest.mark.parametrize("width", [12, 16])
def test_gpu_matches_twin_for_a_wider_student(precision, width):
    """`distill --width 12/16` packs (the width sweep's): the generated kernel handles any
    M_c/M_f/z width, also one that is not a power of two."""
    from vrneural.runtime import texture_pass

    at = quad_atlas(32)
    mat = random_material(4, "coarse_fine", width=width, layers=2)  # M_c 2 layers, as trained
    assert mat.networks["fine"][0].weight.shape[0] == width
    args = (at, mat, np.eye(4, dtype=np.float32), EYE, LP, LC, TILING, precision)
    got, _ = texture_pass.shade_texture_space(*args)
    want, _ = reference.shade_texture_space(*args)
    np.testing.assert_array_equal(got[..., 3], want[..., 3])
    err = np.abs(got[..., :3] - _f16(want[..., :3])) / (np.abs(want[..., :3]) + 1e-2)
    assert err.max() <= (2 * 2.0**-10 if precision == "f32" else 0.25)


@pytest.mark.gpu
@pytest.mark.parametrize(
    "tiling",
    [(3.7, 5.3, -2.31, -7.9), (37.3, 41.9, 1000.37, -513.1)],  # negative uvs; large uvs
    ids=["negative", "large"],
)
@pytest.mark.parametrize("filtering", ["exact", "hardware"])
def test_gpu_neural_texture_wrap_matches_twin(tiling, filtering):
    """The samplers wrap texel indices without an integer division (wrap_index in
    neural_material.wgsl): material UVs far outside [0, 1) in both directions give the twin's
    np.mod indices; so does the sampler's repeat mode ("hardware")."""
    from vrneural.runtime import texture_pass

    at = quad_atlas(32)
    mat = random_material(5)
    args = (at, mat, np.eye(4, dtype=np.float32), EYE, LP, LC, tiling, "f32")
    got, _ = texture_pass.shade_texture_space(*args, filtering=filtering)
    want, _ = reference.shade_texture_space(*args)
    err = np.abs(got[..., :3] - _f16(want[..., :3])) / (np.abs(want[..., :3]) + 1e-2)
    # f32 both sides (2 f16 ulps, as above); at uv ~ 1e3 the f32 texel coordinate itself has
    # ~1e-3 texel spacing, so the large case gets the rounding of uv * W too.
    assert err.max() <= (2 * 2.0**-10 if tiling[2] < 100 else 2e-2)


@pytest.mark.gpu
def test_gpu_compaction_with_and_without_subgroups_agree():
    """The cull's two compaction paths (subgroup operations where the device has them, else
    workgroup atomics and barriers) list the same blocks: identical radiance and counters, both
    equal to the twin's counters; the candidate list spans several workgroups and subgroups."""
    from vrneural.gpu.device import has_feature
    from vrneural.runtime import texture_pass

    at = quad_atlas(64)
    mat = random_material(7)
    for eye in (np.float32([0.9, -0.4, 0.6]), np.float32([0.2, 0.1, -0.8])):  # front, behind
        args = (at, mat, np.eye(4, dtype=np.float32), eye, LP, LC, TILING, "f32")
        runs = [texture_pass.shade_texture_space(*args, subgroups=False)]
        if has_feature("subgroup"):
            runs.append(texture_pass.shade_texture_space(*args, subgroups=True))
        _, cw = reference.shade_texture_space(*args)
        for rad, cnt in runs:
            np.testing.assert_array_equal(cnt, cw)
            np.testing.assert_array_equal(rad, runs[0][0])
        assert max(cw[0], cw[1]) > 64 * 4  # several workgroups of listed / back-facing blocks


@pytest.mark.gpu
def test_gpu_back_facing_blocks_are_not_shaded():
    from vrneural.runtime import texture_pass

    at = quad_atlas(32)
    mat = random_material(1)
    behind = np.float32([0.0, 0.0, -1.0])  # the quad faces +z
    rad, cnt = texture_pass.shade_texture_space(at, mat, np.eye(4), behind, LP, LC)
    blocks = len(reference.non_empty_blocks(at.tri_ids)[0])
    assert cnt[0] == 0 and cnt[1] == blocks and cnt[2] == cnt[3] == 0
    assert not rad.any()
    # tilted so the eye sees it at a grazing angle from the front: everything shaded
    rad, cnt = texture_pass.shade_texture_space(at, mat, np.eye(4), EYE, LP, LC)
    assert cnt[0] == blocks and cnt[1] == 0


@pytest.mark.gpu
def test_gpu_lights_below_horizon_cost_nothing():
    from vrneural.runtime import texture_pass

    at = quad_atlas(32)
    mat = lambertian_material()
    under = np.float32([[0.0, 0.0, -0.5]])
    rad, cnt = texture_pass.shade_texture_space(at, mat, np.eye(4), EYE, under, LC[:1])
    assert cnt[0] > 0 and cnt[2] == cnt[3] == 0
    assert (rad[..., :3] == 0).all() and (rad[..., 3] == 1).sum() == 4 * cnt[0]


def test_twin_barycentrics_match_the_atlas_convention():
    atlas_mod = pytest.importorskip("vrneural.atlas")
    at = atlas_mod.build_atlas(atlas_mod.builtin_mesh("plane"), 64, cache=False)
    want = atlas_mod.texel_barycentrics(at)
    ys, xs = np.nonzero(at.tri_ids != atlas_mod.EMPTY)
    f = at.mesh.faces[at.tri_ids[ys, xs]].astype(np.int64)
    uva = at.uv_atlas
    p = (np.stack([xs, ys], -1) + 0.5).astype(np.float32) / 64
    got = reference.barycentric_2d(p, uva[f[:, 0]], uva[f[:, 1]], uva[f[:, 2]])
    np.testing.assert_allclose(got, want[ys, xs], atol=1e-4)


@pytest.mark.gpu
def test_gpu_matches_twin_on_a_transformed_sphere():
    atlas_mod = pytest.importorskip("vrneural.atlas")
    from vrneural.runtime import texture_pass
    from vrneural.runtime.scene import model_matrix

    at = atlas_mod.build_atlas(atlas_mod.builtin_mesh("sphere"), 128, cache=False)
    mat = random_material(7)
    model = model_matrix((0.1, 0.9, -0.2), (20, 40, 0), 1.7)
    eye = np.float32([0.3, 1.2, 1.0])
    args = (at, mat, model, eye, LP + np.float32([0, 1, 0]), LC, (0.5, 0.5, 0.0, 0.0))
    got, cg = texture_pass.shade_texture_space(*args)
    want, cw = reference.shade_texture_space(*args)
    np.testing.assert_array_equal(cg, cw)
    assert cg[0] > 0 and cg[1] > 0  # some blocks shaded, some back-facing
    err = np.abs(got[..., :3] - _f16(want[..., :3])) / (np.abs(want[..., :3]) + 1e-2)
    assert err.max() <= 2 * 2.0**-10  # f32 on both sides, f16 storage (see test above)


def test_grid_covers_and_respects_the_dispatch_limit():
    from vrneural.runtime.texture_pass import grid

    for n in (0, 1, 64, 65, 65535 * 64, 65535 * 64 + 1, 9_000_000, 300_000_000):
        x, y = grid(n)
        assert x <= 65535 and y <= 65535
        assert x * y * 64 >= n
        assert (x * y - 1) * 64 < n + 64 * y  # padding below one row of workgroups


@pytest.mark.gpu
def test_gpu_candidate_lists_partition_the_non_empty_blocks():
    """The compaction's candidate lists: per row period, phases are disjoint, cover every
    non-empty block once, and hold only rows by % period == phase."""
    atlas_mod = pytest.importorskip("vrneural.atlas")
    from vrneural.gpu.readback import read_buffer
    from vrneural.runtime.gpu_material import GpuAtlas

    at = atlas_mod.build_atlas(atlas_mod.builtin_mesh("torus"), 96, cache=False)
    g = GpuAtlas(at)
    for period in (1, 3, 5):
        buf, spans = g.block_list(period)
        data = read_buffer(buf, np.uint32, sum(n for _, n in spans))
        by = g.geometry()["by"]
        seen = []
        for phase, (off, n) in enumerate(spans):
            part = data[off : off + n]
            assert (by[part] % period == phase).all()
            seen.append(part)
        allb = np.concatenate(seen)
        assert len(np.unique(allb)) == len(allb) == g.non_empty_blocks


@pytest.mark.gpu
def test_gpu_geometry_atlas_holds_the_twins_block_geometry():
    """The buffers the texture-space kernels read are reference.block_geometry, bit for bit:
    packed block coordinates, object-space attributes, untiled texel UVs."""
    atlas_mod = pytest.importorskip("vrneural.atlas")
    from vrneural.gpu.readback import read_buffer
    from vrneural.runtime.gpu_material import GpuAtlas

    at = atlas_mod.build_atlas(atlas_mod.builtin_mesh("torus"), 64, cache=False)
    geo = GpuAtlas(at).geometry()
    want = reference.block_geometry(at)
    n = len(want["by"])
    got = {
        k: read_buffer(geo[k], np.float32, 4 * n).reshape(n, 4)
        for k in ("pos", "nrm", "tan", "uv01", "uv23")
    }
    packed = got["pos"][:, 3].view(np.uint32)
    np.testing.assert_array_equal(packed >> 16, want["by"])
    np.testing.assert_array_equal(packed & 0xFFFF, want["bx"])
    np.testing.assert_array_equal(got["pos"][:, :3], want["pos"])
    np.testing.assert_array_equal(got["nrm"][:, :3], want["nrm"])
    np.testing.assert_array_equal(got["nrm"][:, 3], np.where(want["tan"][:, 3] >= 0, 1, -1))
    np.testing.assert_array_equal(got["tan"][:, :3], want["tan"][:, :3])
    uv = np.concatenate([got["uv01"], got["uv23"]], 1).reshape(n, 4, 2)
    np.testing.assert_array_equal(uv, want["uv"])


@pytest.mark.gpu
def test_gpu_repeated_updates_of_one_target_give_the_same_result():
    """Each update re-lists the front-facing blocks (the count is reset by the pass itself), so
    the same target updated again, and then from the other side, matches the twin each time."""
    atlas_mod = pytest.importorskip("vrneural.atlas")
    from vrneural.gpu.device import get_device
    from vrneural.gpu.readback import read_texture
    from vrneural.runtime.gpu_material import GpuAtlas
    from vrneural.runtime.texture_pass import CounterBuffer, TextureSpacePass, TextureTarget

    at = atlas_mod.build_atlas(atlas_mod.builtin_mesh("sphere"), 64, cache=False)
    mat = random_material(3)
    tp = TextureSpacePass(mat, "f32", len(LP))
    cnt = CounterBuffer(1)
    tgt = TextureTarget(tp, GpuAtlas(at), cnt)
    for eye in (EYE, EYE, -EYE):
        cnt.clear()
        tgt.update(np.eye(4), eye, (1, 1, 0, 0), LP, LC)
        enc = get_device().create_command_encoder()
        tgt.encode(enc)
        get_device().queue.submit([enc.finish()])
        want, cw = reference.shade_texture_space(at, mat, np.eye(4), eye, LP, LC)
        np.testing.assert_array_equal(cnt.read()[0], cw)
        assert 0 < cw[0] < len(reference.non_empty_blocks(at.tri_ids)[0])
        got = read_texture(tgt.texture).astype(np.float32)
        m = want[..., 3] > 0  # the texels this update wrote
        err = np.abs(got[m, :3] - _f16(want[m, :3])) / (np.abs(want[m, :3]) + 1e-2)
        assert err.max() <= 2 * 2.0**-10
    # the last update (from -EYE) left the blocks seen only from EYE as they were
    got = read_texture(tgt.texture).astype(np.float32)
    assert (got[..., 3] > 0).sum() > 4 * cw[0]


@pytest.mark.gpu
@pytest.mark.parametrize("weights, width", [("uniform", 128), ("streamed", 64), ("uniform", 8)])
def test_wide_net_with_streamed_weights_matches_twin(weights, width):
    """The reference path: a 128-wide, 3-hidden-layer single net (each 128 x 128 matrix is
    exactly one 64 KiB uniform binding) streamed from uniform buffers, and a 64-wide one from
    the storage buffer. The "storage" variant (local arrays) got exactly these wrong on lavapipe:
    one block of 64 shaded at 64 wide, and wrong values per pixel at 128."""
    from vrneural.runtime import texture_pass
    from vrneural.runtime.codegen import uniform_weights_fit

    mat = random_material(5, "single", width=width, layers=3, output="log1p")
    assert uniform_weights_fit(mat)
    args = (quad_atlas(16), mat, np.eye(4, dtype=np.float32), EYE, LP, LC, TILING, "f32")
    got, cg = texture_pass.shade_texture_space(*args, weights=weights)
    want, cw = reference.shade_texture_space(*args)
    np.testing.assert_array_equal(cg, cw)
    np.testing.assert_array_equal(got[..., 3], want[..., 3])
    err = np.abs(got[..., :3] - _f16(want[..., :3])) / (np.abs(want[..., :3]) + 1e-2)
    assert err.max() <= 2 * 2.0**-10


def test_uniform_weights_fit_and_refusal():
    from vrneural.errors import VrnError
    from vrneural.runtime.codegen import (
        reference_weights,
        texture_space_wgsl,
        uniform_weights,
        uniform_weights_fit,
    )

    wide = random_material(0, "single", width=129, layers=2)  # 129 x 129 x 4 B > 64 KiB
    deep = random_material(0, "single", width=8, layers=9)  # 10 layers + biases > 12 - 2
    ok = random_material(0, "coarse_fine")
    assert not uniform_weights_fit(wide) and not uniform_weights_fit(deep)
    assert uniform_weights_fit(ok)
    for m in (wide, deep):
        with pytest.raises(VrnError, match="does not fit uniform-buffer weights"):
            texture_space_wgsl(m, weights="uniform")
    with pytest.raises(VrnError, match="weights = 'buffer' is not allowed"):
        texture_space_wgsl(ok, weights="buffer")
    with pytest.raises(VrnError, match="needs a single-level network"):
        texture_space_wgsl(ok, weights="streamed")
    with pytest.raises(VrnError, match="storage weights take layers up to 32 wide"):
        texture_space_wgsl(random_material(0, "single", width=33), weights="storage")
    # what --mode reference picks
    teacher = random_material(0, "single", width=128, layers=3)
    assert [reference_weights(m) for m in (ok, teacher, wide, deep)] == [
        "storage",
        "uniform",
        "streamed",
        "streamed",
    ]
    with pytest.raises(VrnError, match=r"this one has 72 \(.*render it with --mode screen"):
        reference_weights(random_material(0, "coarse_fine", width=64))
    code = texture_space_wgsl(wide, weights="streamed")
    assert "var<uniform> wl0" not in code and "var<storage, read> weights" in code
    # layout: one vec4-padded array per layer, then the biases
    parts = uniform_weights(ok)
    layers = [*ok.networks["coarse"], *ok.networks["fine"]]
    assert len(parts) == len(layers) + 1 and all(len(p) % 4 == 0 for p in parts)
    np.testing.assert_array_equal(parts[1][: layers[1].weight.size], layers[1].weight.ravel())
    np.testing.assert_array_equal(parts[-1][:8], layers[0].bias)
