"""Extreme geometry: degenerate triangles (3D and UV), slivers, one triangle, non-manifold,
NaN/Inf vertices, objects 1e5 m from the origin."""

from contextlib import nullcontext

import numpy as np
import pytest
from extremes import geometry as geo
from hypothesis import given, settings
from hypothesis import strategies as st

from vrneural.atlas import MeshWarning, make_mesh
from vrneural.errors import VrnError
from vrneural.runtime import reference as ref


@given(
    n=st.integers(3, 12),
    seed=st.integers(0, 2**31),
    n_bad=st.integers(0, 4),
)
def test_make_mesh_drops_degenerate_triangles_and_keeps_frames_finite(n, seed, n_bad):
    rng = np.random.default_rng(seed)
    pos = rng.normal(size=(n, 3))
    faces = rng.integers(0, n, size=(n, 3))
    for i in range(min(n_bad, n)):  # repeated index or collinear third vertex
        faces[i, 2] = faces[i, 0] if i % 2 else faces[i, 2]
        if i % 2 == 0:
            pos = np.vstack([pos, (pos[faces[i, 0]] + pos[faces[i, 1]]) / 2])
            faces[i, 2] = len(pos) - 1
    try:
        with pytest.warns(MeshWarning) if _has_degenerate(pos, faces) else nullcontext():
            m = make_mesh("rand", pos, faces)
    except VrnError as e:
        assert "all" in str(e) and "\n" not in str(e)  # every triangle was degenerate
        return
    for a in (m.positions, m.normals, m.tangents, m.uv):
        assert np.isfinite(a).all()
    np.testing.assert_allclose(np.linalg.norm(m.normals, axis=1), 1, atol=1e-5)


def _has_degenerate(pos, faces):
    from vrneural.atlas.geometry import degenerate_faces

    return bool(degenerate_faces(np.asarray(pos, float), np.asarray(faces)).any())


@given(i=st.integers(0, 2), k=st.integers(0, 2), v=st.sampled_from([np.nan, np.inf, -np.inf]))
def test_nan_or_inf_vertices_are_rejected_in_one_line(i, k, v):
    pos = np.float64([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    pos[i, k] = v
    with pytest.raises(VrnError, match="NaN/Inf") as e:
        make_mesh("bad", pos, [[0, 1, 2]])
    assert "\n" not in str(e.value) and "bad" in str(e.value)


@settings(max_examples=10)
@given(o=st.tuples(*[st.floats(-1e5, 1e5)] * 3))
def test_twin_is_translation_invariant_far_from_origin(o):
    from extremes.fixtures import quad_atlas, translate

    from vrneural.material import random_material

    at, mat = quad_atlas(8), random_material(6)
    base, _ = ref.shade_texture_space(at, mat, np.eye(4), geo.EYE, geo.LIGHT, geo.LC)
    o = np.asarray(o)
    far, _ = ref.shade_texture_space(at, mat, translate(*o), geo.EYE + o, geo.LIGHT + o, geo.LC)
    # camera-relative in float64: only the f64 rounding of EYE + o - o (1e-11 m) remains
    np.testing.assert_allclose(far, base, rtol=1e-4, atol=1e-7)
