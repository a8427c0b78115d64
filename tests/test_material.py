"""Neural-material reference semantics and the .vrnm runtime pack."""

import numpy as np
import pytest

from vrneural.btf.dirs import direction_set
from vrneural.errors import VrnError
from vrneural.formats.vrnm import read_vrnm, write_vrnm
from vrneural.material import (
    half_vector,
    lambertian_material,
    material_forward,
    random_material,
    sample_bilinear_wrap,
)


def test_half_vector_degenerate_is_normal():
    wi = np.array([[0.6, 0.0, 0.8], [0.0, 0.0, 1.0]], np.float32)
    h = half_vector(wi, -wi)
    np.testing.assert_array_equal(h, [[0, 0, 1], [0, 0, 1]])
    h = half_vector(wi, wi)
    np.testing.assert_allclose(h, wi, atol=1e-6)


def test_bilinear_wrap_hits_texel_centres_and_wraps(rng):
    tex = rng.standard_normal((4, 6, 2)).astype(np.float16)
    ys, xs = np.mgrid[0:4, 0:6]
    uv = np.stack([(xs + 0.5) / 6, (ys + 0.5) / 4], -1)
    np.testing.assert_allclose(sample_bilinear_wrap(tex, uv), tex.astype(np.float32), atol=1e-6)
    # halfway across the wrap seam in x: mean of the last and first column
    got = sample_bilinear_wrap(tex, np.array([[0.0, 0.5 / 4]]))
    np.testing.assert_allclose(got[0], (tex[0, 0].astype(np.float32) + tex[0, 5]) / 2, atol=1e-3)
    np.testing.assert_allclose(sample_bilinear_wrap(tex, uv + 3.0), tex, atol=1e-3)


def test_lambertian_is_exact():
    d = direction_set(40)
    wi, wo = np.repeat(d, 40, 0), np.tile(d, (40, 1))
    uv = np.random.default_rng(0).random((len(wi), 4, 2)).astype(np.float32)
    mat = lambertian_material((0.8, 0.5, 0.2))
    y = material_forward(mat, wi, wo, uv)
    want = np.array([0.8, 0.5, 0.2], np.float32) / np.pi * wi[:, 2:3]
    np.testing.assert_allclose(y, np.repeat(want[:, None], 4, 1), rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("arch", ["coarse_fine", "single"])
def test_vrnm_round_trip(tmp_path, arch):
    mat = random_material(3, arch=arch)
    mat.meta["provenance"] = {"seed": 3}
    p = write_vrnm(tmp_path / "m.vrnm", mat)
    back = read_vrnm(p)
    assert back.arch == arch and back.meta["provenance"] == {"seed": 3}
    rng = np.random.default_rng(0)
    wi = direction_set(30)
    wo = direction_set(30)[::-1].copy()
    uv = rng.random((30, 4, 2)).astype(np.float32)
    np.testing.assert_array_equal(
        material_forward(mat, wi, wo, uv), material_forward(back, wi, wo, uv)
    )


def test_vrnm_refuses_nan(tmp_path):
    mat = random_material(1)
    mat.networks["fine"][0].weight[0, 0] = np.nan
    with pytest.raises(VrnError, match="non-finite"):
        write_vrnm(tmp_path / "bad.vrnm", mat)
    assert not (tmp_path / "bad.vrnm").exists()


def test_vrnm_rejects_other_formats(tmp_path):
    p = tmp_path / "x.vrnm"
    p.write_bytes(b"PK\x03\x04" + b"\0" * 100)  # a zip (e.g. a torch checkpoint)
    with pytest.raises(VrnError, match="wrong magic"):
        read_vrnm(p)


def test_macs_and_sizes():
    mat = random_material(0, width=8, channels=8, layers=3)
    # coarse: 17*8 + 8*8 + 8*8 = 264 per block -> 66 per texel; fine: 16*8 + 8*3 = 152
    assert mat.macs_per_texel == pytest.approx(264 / 4 + 152)
    assert mat.weight_bytes == 4 * (264 + 24 + 152 + 11)


def test_vrnm_names_our_other_formats(tmp_path):
    """A BTF given where a pack belongs (`run --pack x.btf`): say what it is and what to do."""
    from vrneural.btf.format import BTF_MAGIC

    p = tmp_path / "x.btf"
    p.write_bytes(BTF_MAGIC.ljust(8, b"\0") + b"\0" * 100)
    with pytest.raises(
        VrnError, match=r"x\.btf: is a BTF file, expected a runtime pack; `vrneural teach`"
    ):
        read_vrnm(p)
