"""Neural-texture filtering by the sampler (``Settings.neural_filter = "hardware"``, the
default) against the exact filter in the shader: generated code, bad values, and the frames of
both on the adapter at hand (on llvmpipe the sampler's weights are float: the same frames to
float rounding)."""

import re

import numpy as np
import pytest
from frame_refs import configs, render

from vrneural.errors import VrnError
from vrneural.material import random_material
from vrneural.runtime.codegen import material_spec, screen_space_wgsl, texture_space_wgsl
from vrneural.runtime.codegen_sample import FILTERS, hardware_sampler_fn


@pytest.mark.parametrize("channels", [1, 4, 5, 8, 12, 17])
@pytest.mark.parametrize("lod", [0, 3])
def test_the_sampler_reads_each_layer_once_and_returns_each_channel_once(channels, lod):
    code = "\n".join(hardware_sampler_fn("s", "tex", channels, lod))
    assert code.count("textureSampleLevel(tex, neural_samp, uv, ") == -(-channels // 4)
    assert "textureLoad" not in code and "unpack2x16float" not in code
    ret = re.search(r"return array<f32, (\d+)>\((.*)\);", code)
    assert int(ret[1]) == channels
    want = [f"v{c // 4}.{'xyzw'[c % 4]}" for c in range(channels)]
    assert ret[2].split(", ") == want
    if lod:  # trilinear at the clamped level, as material.sample_lod clamps it
        assert f"clamp(lod_in, 0.0, {lod}.0)" in code


def test_each_filter_generates_its_own_lookups_and_bindings():
    from test_neural_lod import pyramid_material
    from test_parallax import parallax_material

    for mat in (random_material(1), random_material(2, "single"), pyramid_material(3),
                parallax_material(16, amp=0.05)):  # fmt: skip
        for make in (texture_space_wgsl, screen_space_wgsl):
            exact = make(mat)
            hw = make(mat, filtering="hardware")
            assert "neural_samp" not in exact and "texture_2d_array<u32>" in exact
            assert "var neural_samp: sampler;" in hw
            assert "texture_2d_array<u32>" not in hw and "unpack2x16float" not in hw
            assert not re.search(r"textureLoad\((tex_a|tex_b|height_tex)", hw)
            assert "textureSampleLevel(tex_a, neural_samp" in hw
            if mat.parallax_steps:
                assert "textureSampleLevel(height_tex, neural_samp" in hw


def test_an_unknown_filter_is_a_one_line_error():
    from vrneural.runtime.renderer import Renderer, Settings
    from vrneural.runtime.scene import builtin_scene

    assert FILTERS == ("exact", "hardware")
    with pytest.raises(VrnError, match=r"neural filter = 'nearest' is not allowed"):
        material_spec(random_material(0), filtering="nearest")
    with pytest.raises(VrnError, match=r"neural_filter = 'nearest' is not allowed; choose exact"):
        Renderer(builtin_scene(1), Settings(neural_filter="nearest"))


def test_run_takes_the_filter_and_refuses_another(capsys):
    from runtime_helpers import assert_run_takes_choice

    match = r"--neural-filter = 'nearest' is not allowed"
    assert_run_takes_choice(capsys, "neural_filter", "hardware", "exact", "nearest", match)


@pytest.mark.gpu
@pytest.mark.parametrize("name", ["texture", "burst_f16", "screen"])
def test_frames_through_the_sampler_are_the_exact_filters(name, monkeypatch):
    """The frames of tests/frame_refs.py's configurations through the sampler against the same
    frames filtered in the shader: the same counters, and on a float-weight sampler (llvmpipe)
    the same images to float rounding (a few values in a thousand change, by under 0.3%; with
    the networks in f16 more, by under 3%). A GPU's 8-bit weights differ more (up to 1/512 of
    the difference between neighbouring latent texels)."""
    import frame_refs

    from vrneural.gpu.device import adapter_summary

    exact, ce = render(name)
    base = configs()
    kind, kw, frames, jitter = base[name]
    hw_cfg = (kind, {**kw, "neural_filter": "hardware"}, frames, jitter)
    monkeypatch.setattr(frame_refs, "configs", lambda: {**base, name: hw_cfg})
    hw, ch = render(name)
    np.testing.assert_array_equal(ch, ce)
    if not adapter_summary().is_cpu:
        pytest.skip("the frames are compared on a float-weight sampler (llvmpipe) only")
    e, h = exact.astype(np.float32), hw.astype(np.float32)
    rel = np.abs(h - e) / (np.abs(e) + 1e-2 * np.abs(e).max())
    changed = np.count_nonzero(h != e) / h.size
    if kw.get("precision") == "f16":  # the networks in f16 carry the rounding further
        # llvmpipe: 8% of the values change, by at most 0.9% of their size
        assert rel.max() <= 0.03 and changed <= 0.15 and rel.mean() <= 1e-3
    else:  # llvmpipe: 0.06% of the values change, by at most 0.08%
        assert rel.max() <= 3e-3 and changed <= 5e-3


@pytest.mark.gpu
def test_run_records_the_filter_and_says_when_it_is_not_the_default(tmp_path, capsys):
    import json

    from vrneural.cli import main

    for filt in ("exact", "hardware"):
        out = tmp_path / filt
        argv = ["run", "--frames", "1", "--eyes", "1", "--profile", "tiny", "--neural-filter",
                filt, "--no-video", "--save-frames", "none", "--out", str(out)]  # fmt: skip
        assert main(argv) == 0
        said = capsys.readouterr().out
        assert json.loads((out / "summary.json").read_text())["resolved"]["neural_filter"] == filt
        assert ("neural-filter=exact" in said) == (filt == "exact")
