"""Directions beyond the data's range (vrneural/grazing.py): the extension rule, its twins
(numpy spec, torch model, WGSL passes), the recorded range in packs, and the terminator."""

import numpy as np
import pytest
from extremes.fixtures import direction
from hypothesis import given, settings
from hypothesis import strategies as st

from vrneural.errors import VrnError
from vrneural.formats.vrnm import VRNM_VERSION, read_vrnm, write_vrnm
from vrneural.grazing import (
    boundary_consts,
    check_dir_range,
    directions_range,
    extend,
    light_weight,
    to_range,
)
from vrneural.material import lambertian_material, material_forward, random_material

UV1 = np.full((1, 4, 2), 0.3, np.float32)


@given(t=st.floats(0.0, 180.0), p=st.floats(0.0, 360.0), tm=st.floats(5.0, 89.0))
def test_to_range_keeps_the_azimuth_and_moves_only_what_is_beyond(t, p, tm):
    c, s = boundary_consts(tm)
    w = direction(t, p)[None].astype(np.float32)
    got = to_range(w, c, s)[0]
    assert abs(np.linalg.norm(got) - 1) < 1e-5
    if w[0, 2] >= c:
        np.testing.assert_array_equal(got, w[0])
    else:
        assert got[2] == c
        if np.hypot(*w[0, :2]) > 1e-6:  # the same azimuth
            a = np.arctan2(w[0, 1], w[0, 0])
            assert abs(np.angle(np.exp(1j * (np.arctan2(got[1], got[0]) - a)))) < 1e-4


def test_light_weight_is_continuous_and_zero_at_the_horizon():
    c, _ = boundary_consts(75.0)
    z = np.float32([1.0, c, np.nextafter(c, 0), 0.5 * c, 1e-7, 0.0, -0.3])
    w = light_weight(z, c)
    assert w[0] == 1 and w[1] == 1 and abs(w[2] - 1) < 1e-6
    assert abs(w[3] - 0.5) < 1e-6 and 0 < w[4] < 1e-6 and w[5] == 0 and w[6] == 0


@given(t=st.floats(0.0, 89.999), p=st.floats(0.0, 360.0), to=st.floats(0.0, 89.9))
def test_extension_is_exact_for_a_lambertian_patch(t, p, to):
    """BTF = a/pi wi.z: the boundary value times wi.z / cos(theta_max) is the same formula."""
    mat = lambertian_material((0.8, 0.5, 0.2))
    wi = direction(t, p)[None].astype(np.float32)
    wo = direction(to, 180)[None].astype(np.float32)
    y = material_forward(mat, wi, wo, UV1)[0, 0]
    want = np.float32([0.8, 0.5, 0.2]) / np.pi * wi[0, 2]
    np.testing.assert_allclose(y, want, rtol=2e-5, atol=1e-9)


def test_inside_the_range_nothing_changes_bit_for_bit():
    """The extension is the identity on the data's own directions (L1 there unchanged)."""
    mat = random_material(3)
    rng = np.random.default_rng(0)
    th = np.radians(rng.uniform(0, 75, (64, 2)))
    ph = rng.uniform(0, 2 * np.pi, (64, 2))
    d = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1)
    wi, wo = d[:, 0].astype(np.float32), d[:, 1].astype(np.float32)
    wi_e, wo_e, w = extend(wi, wo, mat.dir_range)
    np.testing.assert_array_equal(wi_e, wi)
    np.testing.assert_array_equal(wo_e, wo)
    np.testing.assert_array_equal(w, 1)


def test_a_view_beyond_the_range_is_evaluated_at_its_boundary():
    mat = random_material(4, "single")
    wi = direction(30, 10)[None].astype(np.float32)
    far = material_forward(mat, wi, direction(88, 200)[None].astype(np.float32), UV1)
    edge = material_forward(mat, wi, direction(75, 200)[None].astype(np.float32), UV1)
    np.testing.assert_allclose(far, edge, rtol=1e-6)
    assert far.any()  # radiance does not vanish at grazing view


def test_torch_model_extends_like_the_numpy_spec():
    torch = pytest.importorskip("torch")
    from vrneural.distill.models import NeuralModel, make_spec

    for method in ("student", "teacher", "neumip"):
        model = NeuralModel(make_spec(method, (8, 8), width=8), seed=1)
        model.dir_range = (70.0, 60.0)
        mat = model.to_material()
        assert mat.dir_range == (70.0, 60.0)
        rng = np.random.default_rng(1)
        uv = rng.uniform(0, 1, (16, 4, 2)).astype(np.float32)
        for ti, to in ((30, 20), (80, 20), (30, 85), (89.9, 89.9), (95, 40)):
            wi = direction(ti, 40).astype(np.float32)
            wo = direction(to, 250).astype(np.float32)
            with torch.no_grad():
                got = model.predict(*(torch.from_numpy(a) for a in (wi, wo, uv)))
            n16 = (np.repeat(wi[None], 16, 0), np.repeat(wo[None], 16, 0))
            want = material_forward(mat, *n16, uv)
            np.testing.assert_allclose(got.numpy(), want, rtol=1e-4, atol=1e-6)


def test_directions_range_of_a_btf():
    from vrneural.btf.dirs import direction_set, ubo2014_directions

    # UBO2014's outer ring is at 75 degrees; the quasi-uniform set's last direction sits half
    # a step inside its cap: acos(1 - (1 - cos 75) (n - 0.5) / n) = 74.08 degrees for n = 24
    ti, to = directions_range(ubo2014_directions(), direction_set(24))
    assert ti == 75.0 and to == 74.0821
    d = direction_set(24)[:5]
    assert directions_range(d, d)[0] < 40.0
    # every direction of the data lies inside its recorded range, bit for bit
    for d in (ubo2014_directions(), *(direction_set(n) for n in (2, 24, 40, 1000))):
        c, s = boundary_consts(directions_range(d, d)[0])
        np.testing.assert_array_equal(to_range(d, c, s), d)


def test_pack_records_its_range_and_refuses_one_outside_0_90(tmp_path):
    mat = random_material(2)
    mat.dir_range = check_dir_range((80.0, 70.5))
    write_vrnm(tmp_path / "m.vrnm", mat)
    assert read_vrnm(tmp_path / "m.vrnm").dir_range == (80.0, 70.5)
    for bad in ((90.0, 70.0), (0.0, 70.0), (75.0, -3.0), (float("nan"), 75.0)):
        with pytest.raises(ValueError, match=r"allowed \(0, 90\)"):
            check_dir_range(bad)
    # a pack whose header says 95 degrees: one line naming the file, the field and the range
    from vrneural.formats.container import read_container, write_container

    header, arrays, _ = read_container(tmp_path / "m.vrnm", b"VRNM", (VRNM_VERSION,))
    header["dir_range"] = [95.0, 70.0]
    arrays = {k: np.array(v) for k, v in arrays.items()}
    write_container(tmp_path / "bad.vrnm", b"VRNM", VRNM_VERSION, header, arrays)
    with pytest.raises(VrnError) as e:
        read_vrnm(tmp_path / "bad.vrnm")
    msg = str(e.value)
    assert "bad.vrnm" in msg and "theta_i_max = 95.0" in msg and "(0, 90)" in msg
    assert "\n" not in msg


def test_a_version_1_pack_loads_with_the_default_and_says_so_once(tmp_path, capsys):
    from vrneural.formats.container import read_container, write_container

    write_vrnm(tmp_path / "m.vrnm", random_material(2))
    header, arrays, _ = read_container(tmp_path / "m.vrnm", b"VRNM", (VRNM_VERSION,))
    del header["dir_range"]
    old = tmp_path / "old.vrnm"
    write_container(old, b"VRNM", 1, header, {k: np.array(v) for k, v in arrays.items()})
    assert read_vrnm(old).dir_range == (75.0, 75.0)
    assert read_vrnm(old).dir_range == (75.0, 75.0)
    err = capsys.readouterr().err
    assert err.count("assuming the BTF's directions reach 75 degrees") == 1


def test_cli_names_a_pack_with_a_bad_range(tmp_path):
    from distill_helpers import expect_one_line_error

    from vrneural.formats.container import read_container, write_container

    write_vrnm(tmp_path / "m.vrnm", random_material(2))
    header, arrays, _ = read_container(tmp_path / "m.vrnm", b"VRNM", (VRNM_VERSION,))
    header["dir_range"] = [75.0, 90.0]
    bad = tmp_path / "bad.vrnm"
    write_container(bad, b"VRNM", VRNM_VERSION, header, {k: np.array(v) for k, v in arrays.items()})
    expect_one_line_error(["eval", bad], "bad.vrnm", "theta_o_max = 90.0", "(0, 90)")


@settings(max_examples=20, deadline=None)
@given(ti=st.floats(60.0, 100.0), to=st.floats(0.0, 89.9))
def test_the_shading_twin_tapers_the_light(ti, to):
    """shade_points: the light's value beyond the range is the boundary value times
    wi.z / cos(theta_max), and 0 below the horizon."""
    from vrneural.runtime import reference as ref

    mat = random_material(3)
    pos = np.zeros((1, 3), np.float32)
    n, t, b = np.float32([[0, 0, 1]]), np.float32([[1, 0, 0]]), np.float32([[0, 1, 0]])
    eye = direction(to, 180).astype(np.float32) * 1e3
    lp = direction(ti, 0)[None].astype(np.float32) * 1e3
    rad, _, _, _ = ref.shade_points(mat, pos, n, t, b, UV1, eye, lp, np.full((1, 3), 1e6))
    wi = direction(ti, 0)[None].astype(np.float32)
    wi_edge = direction(min(ti, 75), 0)[None].astype(np.float32)
    edge = material_forward(mat, wi_edge, direction(to, 180)[None].astype(np.float32), UV1)
    c, _ = boundary_consts(75)
    want = edge * max(min(wi[0, 2] / c, 1.0), 0.0)
    np.testing.assert_allclose(rad, want, rtol=2e-3, atol=1e-6)


@pytest.mark.gpu
@pytest.mark.parametrize("mode", ["texture", "screen"])
def test_a_low_poly_sphere_sets_smoothly_along_its_shading_normals(tmp_path, mode):
    """80 triangles with interpolated normals: lights are judged by the shading normal only
    (continuous across triangles), so the terminator is a smooth ramp with no line along the
    triangle edges where the geometric normal turns."""
    import trimesh
    from extremes import terminator as term

    mesh = tmp_path / "ico.obj"
    trimesh.creation.icosphere(subdivisions=1).export(mesh)
    desc = term.terminator_materials(quick=True)["lambert"]
    img = term.render_sphere(desc, mode, mesh=str(mesh))
    r = term.row_steps(img)
    assert r["max"] <= term.STEP_MAX, r["max"]
    y = img.max(-1)
    for row, k in zip(r["rows"], r["columns"], strict=True):
        ramp = y[row, k : k + 12]
        # into the light the value only grows (a seam would be a dip); 2e-3: f16 storage
        assert (np.diff(ramp) >= -2e-3 * r["peak"]).all(), (row, ramp)
