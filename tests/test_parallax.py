"""Height-field parallax (issue #44): the numpy spec (vrneural.parallax), its torch and WGSL
twins, the pack's height field, and the choice ``--parallax auto`` makes."""

import numpy as np
import pytest

from vrneural.errors import VrnError
from vrneural.material import NeuralMaterial, material_forward, random_material
from vrneural.parallax import (
    choose_kind,
    height_at_texels,
    parallax_uv,
    relief_texels,
)


def bumps(n: int = 16, amp: float = 0.05) -> np.ndarray:
    """A smooth periodic height field ``[n, n]`` float16 (UV units, mean 0)."""
    y, x = np.mgrid[0:n, 0:n] / n
    return (amp * np.sin(2 * np.pi * x) * np.cos(4 * np.pi * y)).astype(np.float16)


T75 = float(np.tan(np.radians(75.0)))


def parallax_material(
    steps: int = 16, seed: int = 0, amp: float = 0.05, march: str = "texel"
) -> NeuralMaterial:
    m = random_material(seed, tex_res=16)
    return NeuralMaterial(
        m.arch, m.networks, m.textures, m.output, m.meta, m.dir_range, {},
        {"kind": "height", "steps": steps, "march": march}, bumps(16, amp),
    )  # fmt: skip


def test_the_step_count_follows_the_view():
    """Full steps at the steepest view of the data, proportionally fewer below, at least 1."""
    from vrneural.parallax import ray_slope, step_count

    wo = np.concatenate([views(1, t) for t in (0.0, 30.0, 60.0, 75.0, 85.0)])
    n = step_count(ray_slope(wo, (16, 16)), 16, np.float32(T75))
    assert n.tolist() == [1, 3, 8, 16, 16]


def test_block_march_shifts_a_block_alike():
    rng = np.random.default_rng(4)
    uv = rng.uniform(0, 1, (6, 4, 2)).astype(np.float32)
    out = parallax_uv(bumps(), views(6, 60), uv, 16, T75, "block")
    shift = out - uv
    np.testing.assert_allclose(shift, np.repeat(shift[:, :1], 4, 1), atol=1e-6)
    centre = parallax_uv(bumps(), views(6, 60), uv.mean(1, keepdims=True).repeat(4, 1), 16, T75)
    np.testing.assert_allclose(shift[:, 0], (centre - uv.mean(1, keepdims=True))[:, 0], atol=1e-6)


def views(n: int, theta_deg: float, phi_deg: float = 30.0) -> np.ndarray:
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    w = np.float32([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
    return np.tile(w, (n, 1))


def test_flat_field_and_normal_view_leave_lookups_alone():
    rng = np.random.default_rng(0)
    uv = rng.uniform(0, 1, (8, 4, 2)).astype(np.float32)
    flat = np.zeros((16, 16), np.float16)
    np.testing.assert_array_equal(parallax_uv(flat, views(8, 70), uv, 16, T75), uv)
    np.testing.assert_allclose(parallax_uv(bumps(), views(8, 0), uv, 16, T75), uv, atol=0)


def test_the_corrected_lookup_lies_on_the_relief():
    """Where the march ends, the ray's height equals the field's (to the refinement's error),
    and the shift grows with the view angle."""
    from vrneural.material import sample_bilinear_wrap

    h = bumps(32, 0.03)
    rng = np.random.default_rng(1)
    uv = rng.uniform(0, 1, (64, 4, 2)).astype(np.float32)
    shifts = []
    for theta in (20.0, 45.0, 70.0):
        wo = views(64, theta)
        out = parallax_uv(h, wo, uv, 64, 0.1)  # every view at the full 64 steps
        d = np.float32([wo[0, 0] / wo[0, 2], wo[0, 1] / wo[0, 2]])
        z = ((out - uv) @ d / (d @ d)).reshape(-1)  # the ray height of the hit
        field = sample_bilinear_wrap(h.astype(np.float32)[..., None], out.reshape(-1, 2))[:, 0]
        assert np.abs(z - field).max() < 2e-3  # 64 steps over 0.06: the chord error
        shifts.append(np.abs(out - uv).max())
    assert shifts[0] < shifts[1] < shifts[2]


def test_torch_twin_equals_the_numpy_spec():
    torch = pytest.importorskip("torch")
    from vrneural.distill.lookups import parallax_uv as parallax_uv_t

    rng = np.random.default_rng(2)
    uv = rng.uniform(-1, 2, (40, 4, 2)).astype(np.float32)
    h = bumps(16, 0.08)
    for theta in (10.0, 50.0, 74.0):
        wo = views(1, theta, 200.0)
        for march in ("texel", "block"):
            want = parallax_uv(h, np.repeat(wo, 40, 0), uv, 12, T75, march)
            got = parallax_uv_t(
                torch.from_numpy(h.astype(np.float32)), torch.from_numpy(wo[0]),
                torch.from_numpy(uv), 12, T75, march,
            ).numpy()  # fmt: skip
            np.testing.assert_array_equal(got, want)


def test_torch_model_with_parallax_is_the_pack():
    torch = pytest.importorskip("torch")
    from vrneural.distill.models import NeuralModel, make_spec

    for method, march in (("student", "texel"), ("neumip", "texel"), ("student", "block")):
        spec = make_spec(method, (16, 16))
        spec["parallax"] = {"kind": "height", "steps": 8, "res": [16, 16], "march": march,
                            "theta_o_max": 75.0}  # fmt: skip
        model = NeuralModel(spec, 3)
        model.set_height(bumps(16, 0.1))
        model.dir_range = (75.0, 75.0)
        mat = model.to_material()
        assert mat.parallax_steps == 8
        rng = np.random.default_rng(3)
        uv = rng.uniform(0, 1, (20, 4, 2)).astype(np.float32)
        for theta in (30.0, 72.0, 85.0):  # 85: beyond the range, marched at its edge
            wi, wo = views(1, 40.0, 10.0)[0], views(1, theta, 120.0)[0]
            with torch.no_grad():
                got = model.predict(
                    torch.from_numpy(wi), torch.from_numpy(wo), torch.from_numpy(uv)
                )
            want = material_forward(mat, np.tile(wi, (20, 1)), np.tile(wo, (20, 1)), uv)
            np.testing.assert_allclose(got.numpy(), want, rtol=1e-5, atol=1e-6)


def test_pack_round_trip_and_old_packs_load_without_parallax(tmp_path, capsys):
    from vrneural.formats.container import read_container, write_container
    from vrneural.formats.vrnm import VRNM_VERSION, read_vrnm, write_vrnm

    m = parallax_material(12)
    write_vrnm(tmp_path / "p.vrnm", m)
    back = read_vrnm(tmp_path / "p.vrnm")
    assert back.parallax == {"kind": "height", "steps": 12, "march": "texel"}
    np.testing.assert_array_equal(back.height, m.height)
    assert back.height.dtype == np.float16
    # a version-3 pack (before height fields): parallax off, said once per file
    header, arrays, _ = read_container(tmp_path / "p.vrnm", b"VRNM", (VRNM_VERSION,))
    arrays = {k: np.array(v) for k, v in arrays.items() if k != "height"}
    del header["parallax"]
    write_container(tmp_path / "old.vrnm", b"VRNM", 3, header, arrays)
    capsys.readouterr()
    for _ in range(2):
        old = read_vrnm(tmp_path / "old.vrnm")
        assert old.parallax_kind == "off" and old.height is None
    err = capsys.readouterr().err
    assert err.count("parallax off") == 1 and "old.vrnm" in err


def _bad_pack(tmp_path, name, edit):
    from vrneural.formats.container import read_container, write_container
    from vrneural.formats.vrnm import VRNM_VERSION, read_vrnm, write_vrnm

    write_vrnm(tmp_path / "p.vrnm", parallax_material(8))
    header, arrays, _ = read_container(tmp_path / "p.vrnm", b"VRNM", (VRNM_VERSION,))
    arrays = {k: np.array(v) for k, v in arrays.items()}
    edit(header, arrays)
    write_container(tmp_path / name, b"VRNM", VRNM_VERSION, header, arrays)
    with pytest.raises(VrnError) as e:
        read_vrnm(tmp_path / name)
    return str(e.value)


def test_bad_packs_are_one_line_errors(tmp_path):
    def small(h, a):
        a["height"] = a["height"][:8]

    msg = _bad_pack(tmp_path, "size.vrnm", small)
    assert "size.vrnm" in msg and "height field has shape [8, 16]" in msg and "[16, 16]" in msg

    def nan(h, a):
        a["height"][3, 4] = np.nan

    assert "'height' contains NaN/Inf" in _bad_pack(tmp_path, "nan.vrnm", nan)

    def missing(h, a):
        del a["height"]

    msg = _bad_pack(tmp_path, "none.vrnm", missing)
    assert "parallax kind 'height' needs a height field" in msg

    def steps(h, a):
        h["parallax"]["steps"] = 0

    assert "parallax steps = 0; allowed [1, 64]" in _bad_pack(tmp_path, "steps.vrnm", steps)

    def kind(h, a):
        h["parallax"]["kind"] = "magic"

    assert "parallax kind 'magic'" in _bad_pack(tmp_path, "kind.vrnm", kind)

    def auto(h, a):  # the renderer's march, not one a pack trains with
        h["parallax"]["march"] = "auto"

    assert "parallax march 'auto' not in ('texel', 'block')" in _bad_pack(tmp_path, "a.vrnm", auto)


def test_relief_measure_and_the_auto_choice():
    flat = height_at_texels(np.zeros((64, 64)), (32, 32))
    assert choose_kind("auto", flat, "f.btf")[0] == "off"
    rough = height_at_texels(np.asarray(bumps(64, 0.05), np.float32), (32, 32))
    assert relief_texels(rough) == pytest.approx(0.1 * 32, rel=0.05)
    assert choose_kind("auto", rough, "r.btf")[0] == "height"
    assert choose_kind("off", rough, "r.btf")[0] == "off"
    assert choose_kind("auto", None, "v1.btf") == ("off", "v1.btf has no height field")
    with pytest.raises(VrnError, match=r"--parallax height: v1\.btf has no height field"):
        choose_kind("height", None, "v1.btf")
    # the neural offset needs no height field; auto gives it only where there is none and the
    # views show relief (the measure is called only then)
    assert choose_kind("neural", None, "v1.btf")[0] == "neural"
    assert choose_kind("neural", rough, "r.btf")[0] == "neural"
    kind, why = choose_kind("auto", None, "v1.btf", lambda: 3.0)
    assert kind == "neural" and "apparent relief 3.00 texels >= 2 (neural offset)" in why
    kind, why = choose_kind("auto", None, "v1.btf", lambda: 1.5)
    assert kind == "off" and "apparent relief 1.50 texels < 2" in why
    assert choose_kind("auto", rough, "r.btf", lambda: 1 / 0)[0] == "height"
    assert choose_kind("auto", flat, "f.btf", lambda: 1 / 0)[0] == "off"
    with pytest.raises(VrnError, match=r"height field 48x48 does not fit the 32x32 texels"):
        height_at_texels(np.zeros((48, 48)), (32, 32))
    bad = np.zeros((64, 64))
    bad[1, 2] = np.inf
    with pytest.raises(VrnError, match="height field contains NaN or Inf"):
        height_at_texels(bad, (32, 32))


@pytest.mark.gpu
@pytest.mark.parametrize(
    "mesh,march,filtering",
    [("quad", "texel", "exact"), ("sphere", "texel", "exact"), ("quad", "block", "exact"),
     ("sphere", "texel", "hardware"), ("quad", "block", "hardware")],
)  # fmt: skip
def test_gpu_texture_space_parallax_follows_the_twin(mesh, march, filtering):
    """The texture-space kernel marches each texel's view ray through the height field as the
    numpy twin does (per eye: two eye positions), at a grazing and a near-normal view; with
    filtering "hardware" the height field and the neural textures through the sampler."""
    from runtime_helpers import assert_moved_lookup_parity, quad_atlas

    from vrneural.atlas import build_atlas
    from vrneural.runtime.assets import get_mesh

    m = parallax_material(16, amp=0.06, march=march)
    if mesh == "quad":
        at = quad_atlas(32)
        eyes = [np.float32([0.2, 0.1, 1.5]), np.float32([2.5, -1.0, 0.4])]
    else:
        at = build_atlas(get_mesh("sphere"), 64)
        eyes = [np.float32([0.0, 1.5, 0.8]), np.float32([1.2, 0.3, 0.5])]
    lp, lc = np.float32([[0.3, 0.4, 2.0]]), np.ones((1, 3))
    tl = (2.0, 2.0, 0, 0)
    flat = random_material(0, tex_res=16)
    for eye in eyes:
        assert_moved_lookup_parity(at, m, flat, eye, lp, lc, tl, filtering)


@pytest.mark.gpu
@pytest.mark.parametrize("filtering", ["exact", "hardware"])
def test_gpu_texture_space_auto_march_follows_the_twin(filtering):
    """March "auto": per block where a block spans at most a texel of the height field, per
    texel elsewhere, decided per block in the kernel as the twin decides it."""
    from runtime_helpers import assert_auto_march_parity

    flat = random_material(0, tex_res=16)
    assert_auto_march_parity(parallax_material(16, amp=0.06), flat, filtering)


def test_flat_packs_generate_the_same_kernels_as_before():
    """Parallax off: no height binding, no march; the kernels are what they were."""
    from vrneural.runtime.codegen import screen_space_wgsl, texture_space_wgsl

    flat = random_material(0, tex_res=16)
    for code in (texture_space_wgsl(flat), screen_space_wgsl(flat)):
        assert "height_tex" not in code and "parallax_uv" not in code
    par = parallax_material(16)
    for code in (texture_space_wgsl(par), screen_space_wgsl(par)):
        assert "var height_tex: texture_2d<f32>" in code and "clamp(i32(n), 1, 16)" in code


@pytest.mark.gpu
def test_gpu_screen_space_parallax_agrees_with_the_texture_space_pass(tmp_path):
    """Per pixel (screen space) and per texel of the radiance texture the lookups move the
    same way: the two modes agree far better with each other than with the pack without
    parallax (the texture-space twin is checked texel for texel above)."""
    from runtime_helpers import mode_and_move_gaps

    par = parallax_material(16, amp=0.08)
    flat = NeuralMaterial(par.arch, par.networks, par.textures, par.output, par.meta)
    d_modes, d_parallax = mode_and_move_gaps(tmp_path, par, flat)
    # llvmpipe: 0.0042 between the modes, 0.0485 between parallax and none
    assert d_parallax > 5 * d_modes, (d_parallax, d_modes)


def test_a_mixed_march_is_the_pure_marches_row_by_row():
    """``march`` as a per-block mask: blocks marked True are the block march's, the others
    the per-texel march's; ``auto_blocks`` marks blocks whose atlas texel spans at most half
    a texel of the grid; the offset module follows the same rule."""
    from vrneural.mlp import Layer
    from vrneural.neural_offset import offset_uv
    from vrneural.parallax import AUTO_BLOCK_FOOT_TEXELS, auto_blocks

    rng = np.random.default_rng(7)
    uv = rng.uniform(0, 1, (8, 4, 2)).astype(np.float32)
    wo = views(8, 70)
    mask = np.array([1, 0, 0, 1, 1, 0, 1, 0], bool)
    mixed = parallax_uv(bumps(), wo, uv, 16, T75, mask)
    texel = parallax_uv(bumps(), wo, uv, 16, T75, "texel")
    block = parallax_uv(bumps(), wo, uv, 16, T75, "block")
    np.testing.assert_array_equal(mixed[mask], block[mask])
    np.testing.assert_array_equal(mixed[~mask], texel[~mask])
    assert np.abs(block - texel).max() > 1e-3  # the two routes differ here
    foot = np.float32([0.25, 0.5, 0.5001, 2.0]) / 16
    assert auto_blocks(foot, (16, 16)).tolist() == [True, True, False, False]
    assert AUTO_BLOCK_FOOT_TEXELS == 0.5
    tex = random_material(2, tex_res=16).textures["coarse"]  # an offset texture
    net = [Layer(rng.normal(size=(1, tex.shape[2] + 2)).astype(np.float32), np.ones(1, np.float32))]
    got = offset_uv(net, tex, wo, uv, mask)
    np.testing.assert_array_equal(got[mask], offset_uv(net, tex, wo, uv, "block")[mask])
    np.testing.assert_array_equal(got[~mask], offset_uv(net, tex, wo, uv, "texel")[~mask])
    with pytest.raises(ValueError, match="resolve 'auto' first"):
        parallax_uv(bumps(), wo, uv, 16, T75, "auto")


def test_the_render_march_applies_in_texture_mode_only():
    """``--parallax-march``: auto (default) / texel / block replace a parallax pack's march in
    the texture-space pass; pack keeps it; screen space and flat packs are left alone; the
    twin of march auto needs each block's footprint."""
    from vrneural.runtime.settings import Settings, shaded_material

    par, flat = parallax_material(16), random_material(0, tex_res=16)
    assert shaded_material(par, Settings(), {}).parallax_march == "auto"
    assert shaded_material(par, Settings(parallax_march="block"), {}).parallax_march == "block"
    assert shaded_material(par, Settings(parallax_march="pack"), {}) is par
    assert shaded_material(par, Settings(mode="screen"), {}) is par
    assert shaded_material(flat, Settings(), {}) is flat
    cache: dict = {}
    assert shaded_material(par, Settings(), cache) is shaded_material(par, Settings(), cache)
    auto = shaded_material(par, Settings(), {})
    wi, wo = views(2, 20), views(2, 70)
    uv = np.full((2, 4, 2), 0.3, np.float32)
    with pytest.raises(VrnError, match="march 'auto' needs each block's foot"):
        material_forward(auto, wi, wo, uv)
    fine = material_forward(auto, wi, wo, uv, foot=np.float32([0.01, 0.01]))  # 0.16 texels
    block = parallax_material(16, march="block")
    np.testing.assert_array_equal(fine, material_forward(block, wi, wo, uv))
