"""Acceptance of the atlas stage at 1200^2 for every built-in mesh: coverage of every
triangle, the bilinear gutter property, the split mesh, conventions and stats."""

from __future__ import annotations

import numpy as np
import pytest
from atlas_helpers import (
    bilinear_taps,
    gutter_failures,
    linf_distance,
    random_points,
    texels_per_triangle,
    uv_area,
)

from vrneural.atlas import BUILTIN_MESHES, EMPTY, build_atlas, builtin_mesh, texel_barycentrics
from vrneural.atlas.visualize import chart_ids

R = 1200


@pytest.fixture(scope="module")
def atlases():
    """All built-in meshes at 1200^2 with padding 2, built once (no cache: a fresh build)."""
    return {
        n: (builtin_mesh(n), build_atlas(builtin_mesh(n), R, 2, cache=False))
        for n in BUILTIN_MESHES
    }


@pytest.fixture(scope="module")
def distances(atlases):
    """L-inf distance of each texel centre to its triangle, per mesh (computed once)."""
    return {n: linf_distance(a) for n, (_, a) in atlases.items()}


@pytest.mark.parametrize("name", BUILTIN_MESHES)
def test_every_triangle_owns_a_texel(atlases, distances, name):
    _, atlas = atlases[name]
    nonzero = uv_area(atlas) != 0
    assert nonzero.all(), "built-in meshes have no degenerate UV triangles"
    # "own": a texel with this ID whose square touches the triangle (centre within L-inf 0.5)
    dist = distances[name]
    owned = atlas.tri_ids[(dist <= 0.5 + 1e-9)]
    counts = np.bincount(owned, minlength=len(atlas.mesh.faces))
    assert np.count_nonzero(counts[nonzero] == 0) == 0
    assert atlas.stats["triangles_without_texels"] == 0
    assert texels_per_triangle(atlas).min() >= 1


@pytest.mark.parametrize("name", BUILTIN_MESHES)
def test_gutter_bilinear_taps_are_valid_and_do_not_bleed(atlases, name, rng):
    _, atlas = atlases[name]
    assert gutter_failures(atlas, rng, per_tri=4) == 0
    # stronger: every tap belongs to the point's own chart (no colour bleeding across charts)
    chart = chart_ids(atlas)
    tri, pts = random_points(atlas, rng, per_tri=2)
    xs, ys = bilinear_taps(pts, R)
    assert np.all(chart[atlas.tri_ids[ys, xs]] == chart[tri][:, None])
    assert chart.max() + 1 == atlas.stats["charts"]


@pytest.mark.parametrize("name", BUILTIN_MESHES)
def test_ids_stay_within_padding_and_centres_inside_are_exact(atlases, distances, name):
    _, atlas = atlases[name]
    dist = distances[name]
    filled = atlas.tri_ids != EMPTY
    assert np.nanmax(dist) <= atlas.padding + 1e-9
    # a texel centre strictly inside a triangle must carry exactly that triangle's ID
    bary = texel_barycentrics(atlas)
    inside = filled & (bary.min(axis=-1) > 1e-4)
    assert inside.sum() > 0.25 * R * R * atlas.stats["coverage_pct"] / 100
    assert np.all(dist[inside] == 0.0)


@pytest.mark.parametrize("name", BUILTIN_MESHES)
def test_split_mesh_and_conventions(atlases, name):
    mesh, atlas = atlases[name]
    m = atlas.mesh
    assert atlas.tri_ids.shape == (R, R) and atlas.tri_ids.dtype == np.uint32
    assert atlas.uv_atlas.dtype == np.float32 and atlas.uv_atlas.shape == (len(m.positions), 2)
    assert atlas.uv_atlas.min() >= 0.0 and atlas.uv_atlas.max() <= 1.0
    assert m.faces.shape == mesh.faces.shape and m.faces.dtype == np.uint32
    # faces keep input order: the same corners, vertex attributes copied
    for attr in ("positions", "normals", "tangents", "uv"):
        np.testing.assert_array_equal(getattr(m, attr)[m.faces], getattr(mesh, attr)[mesh.faces])
    s = atlas.stats
    assert s["charts"] >= 1 and s["triangles"] == len(mesh.faces)
    assert 10.0 < s["coverage_pct"] <= s["filled_pct"] <= 100.0
    assert s["texels_per_triangle_min"] >= 1
    assert s["overlap_texels"] == 0
    # gutter texels extrapolate mildly on these meshes (measured max 2.64, highpoly): no slivers
    assert 1.0 <= s["max_abs_barycentric"] < 4.0


def test_barycentrics_reproduce_texel_centres(atlases):
    """Interpolating the triangle's atlas UVs with texel_barycentrics gives the texel centre,
    inside triangles and extrapolated in the gutter (float32 output: 1e-6 abs in UV)."""
    _, atlas = atlases["torus"]
    bary = texel_barycentrics(atlas).astype(np.float64)
    ys, xs = np.nonzero(atlas.tri_ids != EMPTY)
    tri = atlas.mesh.faces[atlas.tri_ids[ys, xs]].astype(np.int64)
    uvt = atlas.uv_atlas.astype(np.float64)[tri]  # [N, 3, 2]
    got = np.einsum("nk,nkd->nd", bary[ys, xs], uvt)
    want = np.stack([(xs + 0.5) / R, (ys + 0.5) / R], 1)
    assert np.abs(got - want).max() < 1e-6
    assert np.all(bary[atlas.tri_ids == EMPTY] == 0)
    # the stat is the largest weight over texels outside their triangle (inside ones are <= 1)
    assert np.abs(bary).max() == pytest.approx(atlas.stats["max_abs_barycentric"], abs=1e-5)


def test_unwrap_child_works_from_an_unguarded_script(tmp_path):
    """xatlas runs in a forked child (unwrap.py): a user script without a __main__ guard, as
    well as `python -` from stdin, builds an atlas once, not recursively, and exits cleanly."""
    import subprocess
    import sys

    code = (
        "from vrneural.atlas import build_atlas, builtin_mesh\n"
        "a = build_atlas(builtin_mesh('plane'), 32, cache=False)\n"
        "print('built', a.resolution)\n"
    )
    script = tmp_path / "user_script.py"
    script.write_text(code)
    for args, stdin in (([str(script)], None), (["-"], code)):
        r = subprocess.run(
            [sys.executable, *args], input=stdin, capture_output=True, text=True, timeout=120
        )
        assert r.returncode == 0, r.stderr
        assert r.stdout.count("built 32") == 1
