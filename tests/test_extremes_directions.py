"""Extreme directions: grazing (to 89.99 deg and beyond), along the normal, wi = -wo, below the
horizon, unnormalized frames. Numpy reference (property-based) and the GPU kernel."""

import numpy as np
import pytest
from extremes import shading as shd
from extremes.fixtures import direction, quad_atlas, step_bounds
from hypothesis import given, settings
from hypothesis import strategies as st
from runtime_helpers import f16_rel_err

from vrneural.material import half_vector, material_forward, random_material

MATS = [random_material(3, "coarse_fine"), random_material(4, "single")]
theta = st.floats(0.0, 89.99)
phi = st.floats(0.0, 360.0)
UV = np.full((2, 4, 2), 0.41, np.float32)


@given(ti=theta, to=theta, pi=phi, po=phi, k=st.integers(0, 1), dt=st.floats(1e-6, 0.5))
def test_reference_finite_nonnegative_and_continuous(ti, to, pi, po, k, dt):
    mat = MATS[k]
    wi = np.stack([direction(ti, pi), direction(min(ti + dt, 89.9999), pi)]).astype(np.float32)
    wo = np.stack([direction(to, po), direction(to, po)]).astype(np.float32)
    y = material_forward(mat, wi, wo, UV)
    assert np.isfinite(y).all() and (y >= 0).all()
    # continuity: the change is within its bound (the network's Lipschitz bound on the
    # directions it sees, plus the light weight's change beyond the range; 1e-5: f32 rounding)
    dy = np.abs(y[1] - y[0]).max()
    assert dy <= step_bounds(mat, wi, wo, UV)[0] + 1e-5


@given(t=st.floats(0.0, 180.0), p=phi)
def test_opposite_directions_use_the_normal_as_half_vector(t, p):
    wi = direction(t, p)[None].astype(np.float32)
    h = half_vector(wi, -wi)
    np.testing.assert_array_equal(h, [[0, 0, 1]])
    for mat in MATS:
        y = material_forward(mat, wi, -wi, UV[:1])
        assert np.isfinite(y).all() and (y >= 0).all()


@given(sn=st.floats(1e-3, 1e3), st_=st.floats(1e-3, 1e3))
@settings(max_examples=10)
def test_reference_unnormalized_frames_shade_like_unit_frames(sn, st_):
    from extremes.fixtures import quad_mesh

    from vrneural.runtime import reference as ref

    mat = MATS[0]
    eye, lp, lc = np.float32([0.2, -0.3, 1.2]), np.float32([[0.4, 0.3, 0.9]]), np.ones((1, 3))
    a, _ = ref.shade_texture_space(quad_atlas(8), mat, np.eye(4), eye, lp, lc)
    b_at = quad_atlas(8, mesh=quad_mesh(normal_scale=sn, tangent_scale=st_))
    b, _ = ref.shade_texture_space(b_at, mat, np.eye(4), eye, lp, lc)
    np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-7)


@pytest.fixture(scope="module")
def gpu32():
    return shd.GpuShade(quad_atlas(8, mesh=shd.quad_mesh(0.1)), MATS[0], "f32")


@pytest.mark.gpu
@given(te=st.floats(0.0, 89.99), tl=st.floats(0.0, 100.0), pl=phi)
@settings(max_examples=8)
def test_gpu_matches_twin_over_directions(gpu32, te, tl, pl):
    from vrneural.runtime import reference as ref

    at = quad_atlas(8, mesh=shd.quad_mesh(0.1))
    eye = direction(te, 180) * 100
    lp = direction(tl, pl)[None] * 100
    lc = np.full((1, 3), 1e4)
    got = gpu32.shade(np.eye(4), eye, lp, lc)
    want, _ = ref.shade_texture_space(at, MATS[0], np.eye(4), eye, lp, lc)
    assert np.isfinite(got).all() and (got >= 0).all()
    if tl > 90:
        assert not got[..., :3].any()  # light below the horizon adds exactly nothing
    # f32 math in another order, f16 storage on both sides: 2 f16 ulps (see test_runtime_texture)
    assert f16_rel_err(got, want) <= 2 * 2.0**-10
