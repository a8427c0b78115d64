"""Footprint taps (`run --lod-taps N`): where an atlas texel's footprint spans n > 1 neural
texels, the texture-space pass shades n x n points over it and stores their mean, the network's
output averaged over the footprint (the exact prefilter that a latent pyramid approximates).
The numpy twin (reference.footprint_taps, tapped_forward), its convergence to a dense average
of the network over the footprint, the WGSL kernel's parity with it on lavapipe, the CLI."""

import numpy as np
import pytest
from test_neural_lod import pyramid_material

from vrneural.material import random_material
from vrneural.runtime import reference as ref
from vrneural.runtime.codegen import texture_space_wgsl


def test_one_tap_compiles_the_code_of_before_and_more_a_loop():
    m = pyramid_material(3)
    base = texture_space_wgsl(m)
    assert texture_space_wgsl(m, taps=1) == base
    four = texture_space_wgsl(m, taps=4)
    assert "for (var j = 0u; j < nta * u32(nb); j++)" in four
    assert "clamp(floor(tap_foot + 0.5), 1.0, 4.0)" in four
    assert "nta" not in base


@pytest.mark.parametrize("bad", [0, 9, 2.5, True])
def test_a_tap_count_out_of_range_is_one_line(bad):
    from vrneural.errors import VrnError

    with pytest.raises(VrnError, match=r"^--lod-taps = .*(out of range; allowed \[1, 8\]|must)"):
        texture_space_wgsl(random_material(0), taps=bad)


def test_taps_round_the_footprint_and_take_their_share_of_it():
    """n: the footprint's width in the full-resolution texture's texels (16 here), rounded and
    capped; each tap ``foot / n`` apart and looked up at ``log2(width / n)`` (at least 0)."""
    foot = np.float32([0.01, 1.4 / 16, 1.6 / 16, 3.0 / 16, 10.0 / 16, 100.0 / 16])
    tp = ref.footprint_taps(pyramid_material(4), foot, 4)
    assert tp["na"].tolist() == tp["nb"].tolist() == [1, 1, 2, 3, 4, 4]
    np.testing.assert_allclose(tp["a"], np.stack([foot / tp["na"], 0 * foot], -1), rtol=1e-6)
    np.testing.assert_allclose(tp["b"], np.stack([0 * foot, foot / tp["nb"]], -1), rtol=1e-6)
    np.testing.assert_allclose(tp["lod"], np.log2(np.maximum(foot * 16 / tp["na"], 1)), rtol=1e-6)
    tp2 = ref.footprint_taps(random_material(0, tex_res=16), foot, 8)
    assert tp2["na"].tolist() == [1, 1, 2, 3, 8, 8] and tp2["lod"] is None  # level 0


def test_a_pixels_footprint_stretches_along_the_view():
    """A pixel's footprint on a surface seen at theta from its normal is 1 / cos(theta) longer
    along the view's direction in the tangent plane (at most 8x): more taps there, a step
    along that direction, the level of the longer share; a texel's footprint does not."""
    m = pyramid_material(4)
    foot = np.full(3, 2.0 / 16, np.float32)  # 2 texels
    th = np.radians([0.0, 60.0, 89.0])
    wo = np.stack([np.sin(th) * 0.6, np.sin(th) * 0.8, np.cos(th)], -1).astype(np.float32)
    tp = ref.footprint_taps(m, foot, 8, wo, pixel=True)
    assert tp["nb"].tolist() == [2, 2, 2] and tp["na"].tolist() == [2, 4, 8]  # 2, 4, 16 texels
    d = tp["a"] / np.linalg.norm(tp["a"], axis=1, keepdims=True)
    np.testing.assert_allclose(d[1:], [[0.6, 0.8]] * 2, atol=1e-6)  # along the view
    np.testing.assert_allclose((tp["a"] * tp["b"]).sum(-1), 0, atol=1e-9)  # across it
    np.testing.assert_allclose(np.linalg.norm(tp["a"], axis=1) * tp["na"] * 16, [2, 4, 16],
                               rtol=1e-5)  # fmt: skip
    np.testing.assert_allclose(tp["lod"], [0, 0, 1], atol=1e-6)  # 16 texels over 8 taps
    same = ref.footprint_taps(m, foot, 8, wo, pixel=False)
    assert same["na"].tolist() == [2, 2, 2]


def _flat_blocks(tiling: float):
    """The quad atlas's blocks facing a near eye and light, at ``tiling``."""
    from runtime_helpers import quad_atlas

    g = ref.texture_blocks(quad_atlas(32), np.eye(4), (tiling, tiling, 0, 0))
    eye, lp, lc = np.float32([0.2, 0.1, 1.5]), np.float32([[0.3, 0.4, 2.0]]), np.ones((1, 3))
    return g, eye, lp, lc


def _shade(m, g, uvs, eye, lp, lc, taps=None, lod=None):
    return ref.shade_points(m, g["pos"], g["n"], g["t"], g["b"], uvs, eye, lp, lc, "f32", 0.0,
                            lod, g["foot"], taps)[0]  # fmt: skip


@pytest.mark.parametrize("pyramid", [False, True])
def test_taps_converge_to_the_network_averaged_over_the_footprint(pyramid):
    """Against the network evaluated on a dense 24 x 24 grid over each texel's footprint and
    averaged (the prefilter's definition, computed without the taps' code), one tap per texel
    is far off (the footprint spans 5.5 texels) and the error falls with every tap count; the
    averaged-latent pyramid (one tap at the footprint's level) is not the output average.
    (A footprint of a whole number of texels would put every tap at the same place in its
    texel, which with these white-noise latents is not the blends between texels: 8.3 here.)"""
    m = pyramid_material(4) if pyramid else random_material(3, tex_res=16)
    g, eye, lp, lc = _flat_blocks(8.3)
    foot = g["foot"]
    assert 5.4 < float(np.median(foot * 16)) < 5.6
    k = 24
    dense = np.zeros((len(foot), 4, 3), np.float32)
    for j in range(k * k):
        o = ((np.float32([j % k, j // k]) + 0.5) / k - 0.5)[None, :] * foot[:, None]
        dense += _shade(m, g, g["uvs"] + o[:, None, :], eye, lp, lc) / (k * k)
    err = {}
    for taps in (1, 2, 3, 4, 6):
        tp = (foot, taps, False) if taps > 1 else None
        got = _shade(m, g, g["uvs"], eye, lp, lc, tp, ref.block_lod(m, foot))
        err[taps] = float(np.abs(got - dense).mean() / dense.mean())
    assert err[1] > err[2] > err[3] > err[4] > err[6], err
    assert err[6] < 0.15 * err[1] and err[6] < 0.1, err


def test_the_twin_counts_every_taps_evaluations():
    m = random_material(3, tex_res=16)
    from runtime_helpers import quad_atlas

    at = quad_atlas(32)
    eye, lp, lc = np.float32([0.2, 0.1, 1.5]), np.float32([[0.3, 0.4, 2.0]]), np.ones((1, 3))
    _, c1 = ref.shade_texture_space(at, m, np.eye(4), eye, lp, lc, tiling=(3, 3, 0, 0))
    _, c3 = ref.shade_texture_space(at, m, np.eye(4), eye, lp, lc, tiling=(3, 3, 0, 0), taps=3)
    assert c3[0] == c1[0] and c3[2] == 4 * c1[2] and c3[3] == 4 * c1[3]  # n = 2 everywhere


@pytest.mark.gpu
@pytest.mark.parametrize("filtering", ["exact", "hardware"])
@pytest.mark.parametrize(
    ("kind", "tiling", "scale", "taps"),
    [
        ("pyramid", 1.0, 1.0, 3),  # n = 1: as without taps
        ("pyramid", 3.0, 1.0, 3),  # n = 2, lod 0
        ("pyramid", 11.0, 1.0, 4),  # 7.3 texels: n = 4 (capped), lod 0.87
        ("pyramid", 3.0, 1.7, 2),  # a pixel's footprint (resolution from the screen): n = 2
        ("oblique", 3.0, 1.7, 4),  # seen at 70-80 degrees: 2 taps across the view, 4 along
        ("plain", 5.0, 1.0, 3),  # n = 3, level 0
        ("single", 15.0, 1.0, 8),  # n = 8 (10 texels, capped)
    ],
)
def test_gpu_taps_follow_the_twin(kind, tiling, scale, taps, filtering):
    from runtime_helpers import assert_gpu_matches_twin, quad_atlas

    m = {
        "oblique": lambda: pyramid_material(4),
        "pyramid": lambda: pyramid_material(4),
        "plain": lambda: random_material(3, tex_res=16),
        "single": lambda: random_material(4, arch="single", tex_res=16),
    }[kind]()
    at = quad_atlas(32)
    eye, lp, lc = np.float32([0.2, 0.1, 1.5]), np.float32([[0.3, 0.4, 2.0]]), np.ones((1, 3))
    if kind == "oblique":
        eye = np.float32([2.5, 1.2, 0.6])
    tl = (tiling, tiling, 0, 0)
    want = assert_gpu_matches_twin(at, m, eye, lp, lc, filtering, tiling=tl, lod_scale=scale,
                                   taps=taps)  # fmt: skip
    one, _ = ref.shade_texture_space(at, m, np.eye(4), eye, lp, lc, tiling=tl, lod_scale=scale)
    if tiling * scale > 2:  # n > 1: the taps changed the texels
        assert np.abs(one - want).max() > 0.02 * want.max()
    else:
        np.testing.assert_array_equal(one, want)


@pytest.mark.gpu
def test_gpu_taps_that_vary_between_blocks_follow_the_twin():
    """On a sphere the footprint differs from block to block (compressed toward the poles),
    so neighbouring lanes loop over different tap counts."""
    from runtime_helpers import assert_gpu_matches_twin

    from vrneural.atlas import build_atlas
    from vrneural.runtime.assets import get_mesh

    m = pyramid_material(4)
    at = build_atlas(get_mesh("sphere"), 128)
    eye, lp, lc = np.float32([0.0, 1.5, 0.8]), np.float32([[0.3, 1.0, 0.9]]), np.ones((1, 3))
    tl = (2.5, 2.5, 0, 0)
    tp = ref.footprint_taps(m, ref.texture_blocks(at, np.eye(4), tl)["foot"], 3)
    assert set(tp["na"].tolist()) == {1, 2, 3}
    assert_gpu_matches_twin(at, m, eye, lp, lc, tiling=tl, taps=3)


def test_run_refuses_taps_out_of_range_or_outside_texture_mode():
    from distill_helpers import expect_one_line_error

    expect_one_line_error(["run", "--lod-taps", "9"], "--lod-taps = 9 is out of range", "[1, 8]")
    expect_one_line_error(
        ["run", "--lod-taps", "2", "--mode", "screen"], "--lod-taps 2 needs --mode texture"
    )


@pytest.mark.gpu
def test_run_with_taps_records_them_and_their_evaluations(tmp_path, capsys):
    """The built-in scene at the tiny profile: its materials are minified there, so the taps
    multiply the evaluations (summary.json counts each tap's) and change the image."""
    import json

    from PIL import Image

    from vrneural.cli import main

    sm, img = {}, {}
    for taps in (1, 3):
        out = tmp_path / f"t{taps}"
        argv = ["run", "--frames", "2", "--eyes", "1", "--profile", "tiny", "--lod-taps",
                str(taps), "--no-video", "--save-frames", "1", "--out", str(out)]  # fmt: skip
        assert main(argv) == 0
        assert (" lod-taps=3 " in capsys.readouterr().out) == (taps == 3)  # the run line
        sm[taps] = json.loads((out / "summary.json").read_text())
        img[taps] = np.asarray(Image.open(out / "frame0001_eye0.png"), np.float32) / 255
    assert sm[3]["resolved"]["lod_taps"] == 3 and sm[1]["resolved"]["lod_taps"] == 1
    ev = {t: s["mlp_evaluations_per_frame"]["median"] for t, s in sm.items()}
    assert sm[3]["blocks_shaded_per_frame"] == sm[1]["blocks_shaded_per_frame"]
    assert ev[3] > 2 * ev[1], ev
    assert np.abs(img[3] - img[1]).max() > 0.01
