"""NeuMIP's neural offset rendered (issue #44): the generated WGSL stage (its multiply-adds,
its binding, unchanged kernels for packs without it), the texture-space pass against the numpy
twin on lavapipe, and ``vrneural run`` with a neural-offset pack in each mode."""

import re

import numpy as np
import pytest
from distill_helpers import run_cli
from runtime_helpers import count_macs
from test_neural_offset import _model

from vrneural.formats.vrnm import write_vrnm
from vrneural.material import NeuralMaterial, random_material
from vrneural.mlp import macs
from vrneural.runtime.codegen import material_spec, screen_space_wgsl, texture_space_wgsl
from vrneural.runtime.codegen_offset import offset_wgsl


def _offset_material(method="student", march="texel", scale=0.5) -> NeuralMaterial:
    meta = {"name": f"off-{method}-{march}", "method": method}
    return _model(method, march, scale=scale).to_material(meta)


@pytest.mark.parametrize("precision", ["f32", "f16"])
@pytest.mark.parametrize("method", ["student", "neumip"])
def test_offset_stage_costs_the_offset_mlps_macs(method, precision):
    """Every non-zero weight of the offset MLP is one constant multiply-add in ``offset_r``;
    the kernels gain exactly those, and the offset texture's binding and sampler."""
    mat = _offset_material(method)
    fns = dict(re.findall(r"\nfn (\w+)\(.*?\n(.*?)\n\}", "\n" + "\n".join(
        offset_wgsl(material_spec(mat), precision)), re.S))  # fmt: skip
    assert set(fns) == {"offset_r", "offset_d"}
    assert count_macs(fns["offset_r"]) == macs(mat.offset_net) > 0
    assert count_macs(fns["offset_d"]) == 0
    plain = NeuralMaterial(mat.arch, mat.networks, mat.textures, mat.output, mat.meta)
    for gen in (texture_space_wgsl, screen_space_wgsl):
        code, base = gen(mat, precision), gen(plain, precision)
        assert count_macs(code) - count_macs(base) == macs(mat.offset_net)
        assert "var off_tex: texture_2d_array<u32>" in code and "off_tex" not in base
        assert "fn sample_off(" in code and "max(wo.z, 0.6000000" in code
    # the module's MACs per shaded texel: all of them per texel, a quarter per 2x2 block
    blk = _offset_material(method, "block")
    assert mat.macs_per_texel == plain.macs_per_texel + macs(mat.offset_net)
    assert blk.macs_per_texel == plain.macs_per_texel + macs(mat.offset_net) / 4
    assert texture_space_wgsl(blk, precision).count("offset_r(") == 2  # its fn + one call


def test_packs_without_an_offset_generate_no_offset_stage():
    flat = random_material(0, tex_res=16)
    for code in (texture_space_wgsl(flat), screen_space_wgsl(flat)):
        assert "off_tex" not in code and "offset_r" not in code


@pytest.mark.gpu
@pytest.mark.parametrize("method,march,filtering", [
    ("student", "texel", "exact"), ("student", "block", "exact"), ("neumip", "texel", "exact"),
    ("student", "texel", "hardware"), ("neumip", "texel", "hardware")])  # fmt: skip
def test_gpu_texture_space_offset_follows_the_twin(method, march, filtering):
    """The texture-space kernel moves each texel's lookups as neural_offset.offset_uv does
    (per eye: a grazing and a near-normal eye), within the height route's tolerance."""
    from runtime_helpers import assert_moved_lookup_parity, quad_atlas

    m = _offset_material(method, march)
    plain = NeuralMaterial(m.arch, m.networks, m.textures, m.output, m.meta)
    at = quad_atlas(32)
    lp, lc = np.float32([[0.3, 0.4, 2.0]]), np.ones((1, 3))
    tl = (2.0, 2.0, 0, 0)
    for eye in (np.float32([0.2, 0.1, 1.5]), np.float32([2.5, -1.0, 0.4])):
        assert_moved_lookup_parity(at, m, plain, eye, lp, lc, tl, filtering)


@pytest.mark.gpu
def test_gpu_texture_space_offset_auto_march_follows_the_twin():
    """March "auto" of the offset module: once per block where the block spans at most a
    texel of the offset texture, per texel elsewhere, as the twin decides it."""
    from runtime_helpers import assert_auto_march_parity

    m = _offset_material("student", "texel")
    assert_auto_march_parity(m, NeuralMaterial(m.arch, m.networks, m.textures, m.output, m.meta))


@pytest.mark.gpu
@pytest.mark.parametrize("mode", ["texture", "screen", "reference"])
def test_run_renders_a_neural_offset_pack(tmp_path, mode):
    """``vrneural run --pack`` draws a neural-offset pack (it was refused before), and the
    reference mode its teacher with an offset; the frame differs from the same packs without
    their offsets."""
    import imageio.v3 as iio

    # --mode reference draws the teacher found beside the pack: one with its own offset
    for method, suffix in (("student", ""), ("teacher", ".teacher")):
        m = _offset_material(method, "texel", scale=1.0)
        write_vrnm(tmp_path / f"n{suffix}.vrnm", m)
        plain = NeuralMaterial(m.arch, m.networks, m.textures, m.output, m.meta)
        write_vrnm(tmp_path / f"p{suffix}.vrnm", plain)
    frames = {}
    for name in ("n", "p"):
        out = tmp_path / f"o-{name}"
        argv = ["run", "--pack", tmp_path / f"{name}.vrnm", "--frames", "1", "--eyes", "1",
                "--profile", "tiny", "--mode", mode, "--quiet", "--out", out]  # fmt: skip
        code, err = run_cli(*argv)
        assert code == 0, err
        frames[name] = iio.imread(out / "frame0000_eye0.png").astype(np.float32)
    assert frames["n"].std() > 2
    d = np.abs(frames["n"] - frames["p"])
    # llvmpipe, tiny profile: mean 0.53 / 0.73 / 0.13 and max 25 / 34 / 20 (texture, screen,
    # reference) of 255 between the packs with and without the offset
    assert d.max() >= 10 and d.mean() > 0.05, (d.max(), d.mean())


@pytest.mark.gpu
def test_gpu_screen_space_offset_agrees_with_the_texture_space_pass(tmp_path):
    """Per pixel (screen space) and per radiance texel the lookups move the same way: the two
    modes agree far better with each other than with the pack without its offset."""
    from runtime_helpers import mode_and_move_gaps

    m = _offset_material("student", "texel", scale=1.0)
    plain = NeuralMaterial(m.arch, m.networks, m.textures, m.output)
    d_modes, d_offset = mode_and_move_gaps(tmp_path, m, plain)
    # llvmpipe: 0.0011 between the modes, 0.038 between the offset and none
    assert d_offset > 5 * d_modes, (d_offset, d_modes)


@pytest.mark.gpu
def test_bench_frame_times_the_update_with_parallax_and_the_neural_offset(tmp_path):
    """``bench frame --neural-offset --parallax-steps S`` times the texture-space update of the
    benchmark's materials with the student's offset module and with height-field parallax,
    each marched per texel, per block and "auto", beside the update without it (the ratios
    of docs/parallax.md), and reports the share of blocks "auto" marches once."""
    import json

    from vrneural.bench.timing import parallax_materials
    from vrneural.cli import main

    for march in ("texel", "block"):
        mats = parallax_materials("neural", march=march)
        assert all(m.parallax_kind == "neural" and m.parallax_march == march for m in mats)
    argv = ["bench", "frame", "--quick", "--neural-offset", "--parallax-steps", "4", "--rounds",
            "1", "--no-progress", "--out", str(tmp_path / "b")]  # fmt: skip
    assert main(argv) == 0
    doc = json.loads((tmp_path / "b" / "results.json").read_text())
    sm = doc["summary"]
    assert set(doc["auto_block_share"]) == {"parallax", "offset"}
    assert all(0.0 <= v <= 1.0 for v in doc["auto_block_share"].values())
    assert "March auto (parallax)" in (tmp_path / "b" / "results.md").read_text()
    for name in ("parallax_vs_texture", "parallax_block_vs_texture", "parallax_auto_vs_texture"):
        assert np.isfinite(sm["ratios"][name]["median"]) and sm["ratios"][name]["median"] > 0
    for name in ("texture_full_offset", "texture_full_offset_block", "texture_slice_offset",
                 "texture_full_offset_auto"):  # fmt: skip
        assert sm["passes"][name]["wall_ms"] > 0
    for name in ("offset_vs_texture", "offset_block_vs_texture", "offset_auto_vs_texture"):
        assert np.isfinite(sm["ratios"][name]["median"]) and sm["ratios"][name]["median"] > 0


@pytest.mark.gpu
def test_gpu_texture_space_offset_in_f16_follows_the_f16_twin():
    """In f16 kernels the offset MLP runs in f16 like the twin's ``precision="f16"``; the
    kernel compiles and follows it within the f16 tolerance of tests/test_runtime_texture.py."""
    from runtime_helpers import quad_atlas

    from vrneural.runtime import reference as ref
    from vrneural.runtime.texture_pass import shade_texture_space

    m = _offset_material("student", "texel")
    args = (quad_atlas(32), m, np.eye(4, dtype=np.float32), np.float32([2.5, -1.0, 0.4]),
            np.float32([[0.3, 0.4, 2.0]]), np.ones((1, 3)), (2.0, 2.0, 0, 0), "f16")  # fmt: skip
    got, _ = shade_texture_space(*args)
    want, _ = ref.shade_texture_space(*args)
    w16 = want.astype(np.float16).astype(np.float32)
    err = np.abs(got[..., :3] - w16[..., :3]) / (np.abs(w16[..., :3]) + 1e-2)
    assert err.max() <= 0.25  # llvmpipe: 0.0027
