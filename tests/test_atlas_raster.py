"""The CPU rasterizer on hand-made UV layouts: exact coverage against a brute-force
reference, the top-left tie rule on shared edges, slivers, the gutter, barycentrics."""

from __future__ import annotations

import numpy as np
from atlas_helpers import bilinear_taps, gutter_failures, linf_distance

from vrneural.atlas import EMPTY, Atlas, texel_barycentrics
from vrneural.atlas.builtin import grid_faces
from vrneural.atlas.raster import rasterize_ids
from vrneural.atlas.types import Mesh


def _atlas(uv, faces, R, padding):
    ids, info = rasterize_ids(uv, faces, R, padding)
    n = len(uv)
    mesh = Mesh(
        "t",
        np.zeros((n, 3), np.float32),
        faces.astype(np.uint32),
        np.tile([0, 0, 1], (n, 1)).astype(np.float32),
        np.tile([1, 0, 0, 1], (n, 1)).astype(np.float32),
        np.zeros((n, 2), np.float32),
    )
    return Atlas(mesh, uv.astype(np.float32), ids, R, padding), info


def _grid_uv(n, lo, hi, rng=None, jitter=0.0):
    s, t = np.meshgrid(np.linspace(lo, hi, n + 1), np.linspace(lo, hi, n + 1), indexing="xy")
    uv = np.stack([s.reshape(-1), t.reshape(-1)], 1)
    if rng is not None:
        inner = (uv > lo) & (uv < hi)
        uv += inner * rng.uniform(-jitter, jitter, uv.shape)
    return uv.astype(np.float32), grid_faces(n, n)


def _brute_inside(uv, faces, R):
    """[F, R, R] bool: texel centre strictly inside each triangle (plain barycentrics, f64)."""
    c = (np.arange(R) + 0.5) / R
    X, Y = np.meshgrid(c, c, indexing="xy")
    out = []
    for f in faces:
        a, b, d = uv[f].astype(np.float64)
        den = (b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0])
        l1 = ((X - a[0]) * (d[1] - a[1]) - (Y - a[1]) * (d[0] - a[0])) / den
        l2 = ((b[0] - a[0]) * (Y - a[1]) - (b[1] - a[1]) * (X - a[0])) / den
        out.append((l1 > 1e-9) & (l2 > 1e-9) & (1 - l1 - l2 > 1e-9))
    return np.array(out)


def test_exact_coverage_matches_brute_force(rng):
    R = 64
    uv, faces = _grid_uv(6, 0.1, 0.9, rng, jitter=0.03)
    atlas, info = _atlas(uv, faces, R, padding=0)
    inside = _brute_inside(uv, faces, R)
    tri, ys, xs = np.nonzero(inside)
    np.testing.assert_array_equal(atlas.tri_ids[ys, xs], tri)
    assert info["overlap_texels"] == 0 and info["gutter_texels"] == 0


def test_shared_edges_through_centres_follow_top_left_rule():
    """Vertices on texel centres: diagonals and grid lines pass through many centres. Every
    centre of the square's interior is owned exactly once (no gap, no double claim), and the
    owner of a centre on an edge is the triangle for which that edge is a top or left edge."""
    R = 32
    uv, faces = _grid_uv(4, 4.5 / R, 28.5 / R)  # quads of 6x6 texels, corners on centres
    atlas, info = _atlas(uv, faces, R, padding=0)
    assert info["overlap_texels"] == 0
    ids = atlas.tri_ids
    interior = ids[5:28, 5:28]  # centres strictly inside the square
    assert np.all(interior != EMPTY)
    # the left column x=4 (centre 4.5) is a left edge: owned; the right column x=28 is not
    assert np.all(ids[5:28, 4] != EMPTY) and np.all(ids[5:28, 28] == EMPTY)
    # the top row y=4 is a top edge (y down): owned; the bottom row y=28 is not
    assert np.all(ids[4, 5:28] != EMPTY) and np.all(ids[28, 5:28] == EMPTY)


def test_winding_does_not_matter():
    R = 48
    uv, faces = _grid_uv(3, 0.2, 0.8)
    a, _ = _atlas(uv, faces, R, 1)
    b, _ = _atlas(uv, faces[:, [0, 2, 1]], R, 1)
    np.testing.assert_array_equal(a.tri_ids, b.tri_ids)


def test_slivers_each_get_a_texel():
    """Thin triangles between texel centres cover no centre; each still gets one texel."""
    R = 64
    tris = []
    for k in range(12):  # horizontal slivers 0.05 texel thick, lying between centre rows
        y = (10 + 2 * k + 0.0) / R
        x0 = (4 + 3 * (k % 4)) / R
        tris.append([[x0, y], [x0 + 20 / R, y + 0.02 / R], [x0 + 20 / R, y + 0.05 / R]])
    tris.append([[0.7, 0.7], [0.7 + 0.3 / R, 0.7], [0.7, 0.7 + 0.3 / R]])  # tiny, no centre
    uv = np.array(tris, np.float32).reshape(-1, 2)
    faces = np.arange(len(uv)).reshape(-1, 3)
    atlas, info = _atlas(uv, faces, R, padding=2)
    assert info["sliver_fixes"] == len(faces) and info["slivers_unfixed"] == 0
    d = linf_distance(atlas)
    owned = np.bincount(atlas.tri_ids[d <= 0.5], minlength=len(faces))
    assert owned.min() >= 1
    # the gutter keeps bilinear taps of points inside slivers valid too
    assert gutter_failures(atlas, np.random.default_rng(0), per_tri=50) == 0


def test_sliver_between_neighbours_steals_a_spare_texel():
    """A sliver inside a quad (between three big triangles) touches only texels the big
    triangles own: it takes one from an owner that keeps others, and everyone keeps >= 1."""
    R = 32
    pts = np.array([[4, 4.3], [28, 4.3], [28, 28.3], [4, 28.3], [16, 16.42]]) / R
    faces = np.array([[0, 1, 2], [0, 2, 4], [0, 4, 3], [4, 2, 3]])
    atlas, info = _atlas(pts.astype(np.float32), faces, R, padding=1)
    assert info["sliver_fixes"] == 1 and info["slivers_unfixed"] == 0
    d = linf_distance(atlas)
    owned = np.bincount(atlas.tri_ids[d <= 0.5], minlength=4)
    assert owned.min() >= 1 and owned[1] == 1


def test_impossible_crowding_is_counted_not_hidden():
    """Six thin triangles in one texel's square (a fan around its centre) share one texel:
    the top-left rule gives the centre (a shared vertex) to one, the other five cannot get a
    texel of their own and are reported as unfixed, not hidden."""
    R = 16
    c = np.array([8.5, 8.5]) / R
    ang = np.linspace(0, 2 * np.pi, 7)[:-1]
    r = 0.45 / R
    tris = [
        [
            c,
            c + r * np.array([np.cos(a), np.sin(a)]),
            c + r * np.array([np.cos(a + 0.1), np.sin(a + 0.1)]),
        ]
        for a in ang
    ]
    uv = np.array(tris, np.float32).reshape(-1, 2)
    atlas, info = _atlas(uv, np.arange(len(uv)).reshape(-1, 3), R, padding=1)
    assert atlas.tri_ids[8, 8] != EMPTY
    assert info["sliver_fixes"] == 0 and info["slivers_unfixed"] == 5


def test_gutter_width_and_bilinear_taps(rng):
    R = 96
    uv, faces = _grid_uv(5, 0.3, 0.6, rng, jitter=0.01)
    for pad in (1, 2, 4):
        atlas, _ = _atlas(uv, faces, R, padding=pad)
        d = linf_distance(atlas)
        assert np.nanmax(d) <= pad + 1e-9
        # every texel within L-inf `pad` of the chart is filled (the dilation is complete)
        lo, hi = 0.3 * R, 0.6 * R
        c = np.arange(R) + 0.5
        ring = (c[None, :] >= lo - pad) & (c[None, :] <= hi + pad)
        ring = ring & ((c[:, None] >= lo - pad) & (c[:, None] <= hi + pad))
        assert np.all(atlas.tri_ids[ring] != EMPTY)
        assert np.all(atlas.tri_ids[~ring] == EMPTY)
        assert gutter_failures(atlas, rng, per_tri=20) == 0
    atlas0, _ = _atlas(uv, faces, R, padding=0)
    assert gutter_failures(atlas0, rng, per_tri=20) > 0  # the property needs the gutter


def test_bilinear_taps_rule():
    xs, ys = bilinear_taps(np.array([[0.5 / 8, 0.5 / 8], [0.55 / 8, 1.49 / 8]]), 8)
    assert xs[0].tolist() == [0, 1, 0, 1] and ys[0].tolist() == [0, 0, 1, 1]
    assert xs[1].tolist() == [0, 1, 0, 1] and ys[1].tolist() == [0, 0, 1, 1]


def test_zero_area_triangles_are_skipped():
    uv = np.array([[0.1, 0.1], [0.9, 0.1], [0.1, 0.9], [0.5, 0.5]], np.float32)
    faces = np.array([[0, 1, 2], [0, 3, 3], [0, 0, 0]])
    atlas, info = _atlas(uv, faces, 32, 1)
    assert info["zero_area_triangles"] == 2
    assert set(np.unique(atlas.tri_ids)) == {0, int(EMPTY)}


def test_texel_barycentrics_are_exact_in_the_gutter(rng):
    R = 40
    uv, faces = _grid_uv(3, 0.25, 0.75, rng, jitter=0.02)
    atlas, _ = _atlas(uv, faces, R, 2)
    bary = texel_barycentrics(atlas)
    assert bary.dtype == np.float32 and bary.shape == (R, R, 3)
    ys, xs = np.nonzero(atlas.tri_ids != EMPTY)
    got = np.einsum("nk,nkd->nd", bary[ys, xs], uv[faces[atlas.tri_ids[ys, xs]]])
    np.testing.assert_allclose(got, np.stack([(xs + 0.5) / R, (ys + 0.5) / R], 1), atol=1e-6)
    np.testing.assert_allclose(bary[ys, xs].sum(axis=1), 1.0, atol=1e-6)
