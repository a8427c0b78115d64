"""Prefiltered neural textures: pyramids in the models, the pack and every evaluator (numpy spec,
torch, the WGSL texture-space pass), trained against the BTF averaged over each level's texels."""

import numpy as np
import pytest

from vrneural.errors import VrnError
from vrneural.formats.vrnm import read_vrnm, write_vrnm
from vrneural.material import NeuralMaterial, material_forward, pool_level, random_material


def pyramid_material(levels: int = 3, seed: int = 2) -> NeuralMaterial:
    m = random_material(seed, tex_res=16)
    return NeuralMaterial(
        m.arch,
        m.networks,
        m.textures,
        m.output,
        m.meta,
        m.dir_range,
        {k: [pool_level(t, j) for j in range(1, levels)] for k, t in m.textures.items()},
    )


def test_lod_lookups_blend_levels_and_level_0_is_unchanged():
    m = pyramid_material(3)
    rng = np.random.default_rng(0)
    n = 32
    wi = np.tile(np.float32([[0.3, 0.1, 0.95]]), (n, 1))
    wo = np.tile(np.float32([[-0.2, 0.3, 0.93]]), (n, 1))
    uv = rng.uniform(0, 1, (n, 4, 2)).astype(np.float32)
    base = material_forward(m, wi, wo, uv)
    np.testing.assert_array_equal(material_forward(m, wi, wo, uv, lod=np.zeros(n)), base)
    y1 = material_forward(m, wi, wo, uv, lod=np.ones(n))
    y2 = material_forward(m, wi, wo, uv, lod=np.full(n, 2.0))
    half = material_forward(m, wi, wo, uv, lod=np.full(n, 1.5))
    assert not np.allclose(y1, y2)
    # lod 1.5 blends the textures of levels 1 and 2 half and half before the networks
    from vrneural.material import sample_lod

    f = sample_lod(m, "fine", uv.reshape(-1, 2), np.full(4 * n, 1.5, np.float32))
    f1 = sample_lod(m, "fine", uv.reshape(-1, 2), np.full(4 * n, 1.0, np.float32))
    f2 = sample_lod(m, "fine", uv.reshape(-1, 2), np.full(4 * n, 2.0, np.float32))
    np.testing.assert_allclose(f, 0.5 * f1 + 0.5 * f2, rtol=1e-6, atol=1e-7)
    assert np.isfinite(half).all()
    # past the top level: clamped to it
    np.testing.assert_array_equal(material_forward(m, wi, wo, uv, lod=np.full(n, 9.0)), y2)


def test_pack_keeps_its_pyramid_and_refuses_a_bad_one(tmp_path):
    m = pyramid_material(3)
    write_vrnm(tmp_path / "p.vrnm", m)
    back = read_vrnm(tmp_path / "p.vrnm")
    assert back.lod_levels == 3
    for k in m.textures:
        for a, b in zip(m.levels[k], back.levels[k], strict=True):
            np.testing.assert_array_equal(a, b)
    from vrneural.formats.container import read_container, write_container
    from vrneural.formats.vrnm import VRNM_VERSION

    header, arrays, _ = read_container(tmp_path / "p.vrnm", b"VRNM", (VRNM_VERSION,))
    arrays = {k: np.array(v) for k, v in arrays.items()}
    arrays["tex.fine.1"] = arrays["tex.fine.1"][:5]  # a level of the wrong size
    write_container(tmp_path / "bad.vrnm", b"VRNM", VRNM_VERSION, header, arrays)
    with pytest.raises(VrnError, match=r"bad.vrnm: invalid runtime pack: texture 'fine' level 1"):
        read_vrnm(tmp_path / "bad.vrnm")
    header["levels"]["fine"] = 9  # more levels than the file holds (above log2 of the size)
    arrays = {
        k: np.array(v)
        for k, v in read_container(tmp_path / "p.vrnm", b"VRNM", (VRNM_VERSION,))[1].items()
    }
    write_container(tmp_path / "bad2.vrnm", b"VRNM", VRNM_VERSION, header, arrays)
    with pytest.raises(VrnError, match=r"bad2.vrnm: runtime pack lacks 'tex.fine.3'"):
        read_vrnm(tmp_path / "bad2.vrnm")


def test_torch_pyramid_equals_the_pack(tmp_path):
    torch = pytest.importorskip("torch")
    from vrneural.distill.models import NeuralModel, make_spec

    for kind in ("filter", "levels"):
        spec = make_spec("student", (16, 16)) | {"lod": {"levels": 3, "kind": kind}}
        model = NeuralModel(spec, seed=3)
        mat = model.to_material()
        assert mat.lod_levels == 3
        if kind == "filter":  # the levels are box averages of level 0
            np.testing.assert_array_equal(
                mat.levels["fine"][0],
                model.texture("fine", 1).detach().numpy().astype(np.float16),
            )
        wi, wo = torch.tensor([0.3, 0.1, 0.95]), torch.tensor([-0.2, 0.3, 0.93])
        rng = np.random.default_rng(1)
        uv = rng.uniform(0, 1, (8, 4, 2)).astype(np.float32)
        for level in range(3):
            with torch.no_grad():
                got = model.predict(wi, wo, torch.from_numpy(uv), level).numpy()
            want = material_forward(
                mat, np.tile(wi.numpy(), (8, 1)), np.tile(wo.numpy(), (8, 1)), uv,
                lod=np.full(8, level, np.float32),
            )  # fmt: skip
            np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-6)


def test_distill_trains_a_pyramid_and_names_levels_that_do_not_fit(tmp_path):
    from distill_helpers import FAST, analytic_btf, expect_one_line_error, run_cli

    btf = analytic_btf(tmp_path / "b.btf", res=16)
    assert run_cli("teach", btf, "-o", tmp_path / "t.pt", "--epochs", "1", *FAST)[0] == 0
    argv = ["distill", tmp_path / "t.pt", "-o", tmp_path / "s.pt", "--epochs", "1", *FAST]
    assert run_cli(*argv, "--lod-levels", "3")[0] == 0
    mat = read_vrnm(tmp_path / "s.vrnm")
    assert mat.lod_levels == 3 and mat.meta["metrics"]["pack_vs_torch_max_abs"] <= 1e-5
    assert [a.shape for a in mat.levels["fine"]] == [(8, 8, 8), (4, 4, 8)]
    # a run without a pyramid: export gives it the box averages of level 0 (untrained)
    assert run_cli(*argv, "--force", "-o", tmp_path / "p.pt")[0] == 0
    out = tmp_path / "p3.vrnm"
    assert run_cli("export", tmp_path / "p.pt", "-o", out, "--lod-levels", "3")[0] == 0
    flat = read_vrnm(out)
    assert flat.lod_levels == 3 and flat.meta["metrics"]["pack_vs_torch_max_abs"] <= 1e-5
    np.testing.assert_array_equal(flat.levels["fine"][0], pool_level(flat.textures["fine"], 1))
    expect_one_line_error(
        ["export", tmp_path / "s.pt", "-o", tmp_path / "x.vrnm", "--lod-levels", "2"],
        "was trained with a 3-level pyramid",
    )
    expect_one_line_error(
        [*argv, "--force", "--lod-levels", "5"],
        "--lod-levels = 5 does not fit",
        "16x16 texels",
        "allowed [1, 4]",
    )


@pytest.mark.gpu
@pytest.mark.parametrize("filtering", ["exact", "hardware"])
@pytest.mark.parametrize(
    ("tiling", "scale"), [(1.0, 1.0), (3.0, 1.0), (11.0, 1.0), (40.0, 1.0), (1.0, 2.5), (3.0, 1.7)]
)
def test_gpu_lod_lookups_follow_the_twin(tiling, scale, filtering):
    """The texture-space kernel computes each block's footprint and looks the pyramid up as
    the numpy twin does (lod 0, 1, 2.9 and 4.7, clamped to the top level 3); "hardware":
    trilinear by the sampler. ``scale``: the footprint of a pixel larger than the texel
    (``lod_scale``, resolution from the screen): lod 1.3 and 2.3."""
    from runtime_helpers import assert_gpu_matches_twin, quad_atlas

    from vrneural.runtime import reference as ref

    m = pyramid_material(4)
    at = quad_atlas(32)
    eye, lp, lc = np.float32([0.2, 0.1, 1.5]), np.float32([[0.3, 0.4, 2.0]]), np.ones((1, 3))
    tl = (tiling, tiling, 0, 0)
    want = assert_gpu_matches_twin(at, m, eye, lp, lc, filtering, tiling=tl, lod_scale=scale)
    if scale != 1.0:  # the scale moved the level: not the texel's footprint's image
        one, _ = ref.shade_texture_space(at, m, np.eye(4), eye, lp, lc, tiling=tl)
        assert np.abs(one - want).max() > 0.05 * want.max()


@pytest.mark.gpu
@pytest.mark.parametrize("filtering", ["exact", "hardware"])
def test_gpu_lod_that_varies_between_blocks_follows_the_twin(filtering):
    """On a sphere the level of detail differs from block to block (the material is compressed
    toward its poles), so the lanes of one SIMD group read different pyramid levels: llvmpipe
    read textureDimensions at such a level as the first lane's (garbage where they differed);
    the level's size is now derived from level 0's. The sampler ("hardware") takes each
    lane's own level."""
    from runtime_helpers import assert_gpu_matches_twin

    from vrneural.atlas import build_atlas
    from vrneural.runtime import reference as ref
    from vrneural.runtime.assets import get_mesh

    m = pyramid_material(4)
    at = build_atlas(get_mesh("sphere"), 128)
    eye, lp, lc = np.float32([0.0, 1.5, 0.8]), np.float32([[0.3, 1.0, 0.9]]), np.ones((1, 3))
    tl = (2.5, 2.5, 0, 0)
    lod = ref.block_lod(m, ref.texture_blocks(at, np.eye(4), tl)["foot"])
    assert lod.max() - lod.min() > 1.0  # varies
    assert_gpu_matches_twin(at, m, eye, lp, lc, filtering, tiling=tl)
