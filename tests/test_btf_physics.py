"""Physics of the synthetic BTFs: flat patches match analytic BRDF x cos(theta_i) (the
convention of docs/conventions.md section 2), energy stays below the white-furnace bound,
reciprocity holds, tiles continue across their edges."""

import numpy as np
import pytest
from btf_helpers import flat_maps

from vrneural.btf import direction_set
from vrneural.btf.brdf import brdf, params
from vrneural.btf.dirs import spherical
from vrneural.btf.presets import PRESETS
from vrneural.btf.render import make_scene, render_view
from vrneural.btf.synth import BtfConfig, build_maps, subsamples

RES = 8


def _render_all(maps, dirs, views=None, res=RES, spp=4, seed=0):
    cfg = BtfConfig(res=res, spp=spp, seed=seed)
    scene = make_scene(maps, dirs)
    vs = dirs if views is None else views
    return np.stack([render_view(scene, w, subsamples(cfg), (res, res)) for w in vs], 1)


def _ggx_reference(wi, wo, f0, at, ab, angle):
    """Closed-form anisotropic GGX x cos_i, float64, written independently of brdf.py."""
    c, s = np.cos(angle), np.sin(angle)
    rot = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])  # macro frame -> tangent frame
    i, o = rot @ np.asarray(wi, float), rot @ np.asarray(wo, float)
    h = (i + o) / np.linalg.norm(i + o)
    d = 1 / (np.pi * at * ab * (h[0] ** 2 / at**2 + h[1] ** 2 / ab**2 + h[2] ** 2) ** 2)

    def lam(w):
        return (np.sqrt(1 + (at**2 * w[0] ** 2 + ab**2 * w[1] ** 2) / w[2] ** 2) - 1) / 2

    g2 = 1 / (1 + lam(i) + lam(o))
    f = np.asarray(f0) + (1 - np.asarray(f0)) * (1 - i @ h) ** 5
    return f * d * g2 / (4 * i[2] * o[2]) * i[2]


def test_flat_lambert_matches_albedo_over_pi_times_cos():
    albedo = (0.2, 0.5, 0.8)
    dirs = direction_set(12)
    vals = _render_all(flat_maps(16, albedo=albedo, f0=(0, 0, 0)), dirs)  # [L, V, H, W, 3]
    want = np.asarray(albedo)[None] / np.pi * dirs[:, 2:3]  # [L, 3], analytic
    for v in range(len(dirs)):
        np.testing.assert_allclose(
            vals[:, v], np.broadcast_to(want[:, None, None], vals[:, v].shape), rtol=2e-5
        )


def test_flat_ggx_matches_closed_form_at_every_texel():
    f0, at, ab, angle = (0.9, 0.6, 0.3), 0.15, 0.4, 0.7
    dirs = direction_set(10)
    maps = flat_maps(16, albedo=(0, 0, 0), f0=f0, alpha=(at, ab), angle=angle)
    vals = _render_all(maps, dirs)
    for li in range(len(dirs)):
        for vi in range(len(dirs)):
            ref = _ggx_reference(dirs[li], dirs[vi], f0, at, ab, angle)
            got = vals[li, vi].reshape(-1, 3)
            # float32 evaluation of the same formulas: relative error ~1e-6; 1e-4 is generous
            np.testing.assert_allclose(got, np.broadcast_to(ref, got.shape), rtol=1e-4, atol=1e-7)
    assert vals.max() > 1.0  # the specular peak is really in there (not a vacuous compare)


def test_flat_patch_is_reciprocal():
    dirs = direction_set(14)
    maps = flat_maps(
        16,
        albedo=(0.5, 0.3, 0.2),
        f0=(0.04, 0.04, 0.04),
        alpha=(0.2, 0.5),
        angle=0.3,
        sheen=(0.4, 0.3, 0.2),
        sheen_rough=0.4,
    )
    vals = _render_all(maps, dirs)[:, :, 0, 0]  # homogeneous: one texel suffices
    cos = dirs[:, 2].astype(np.float64)
    a = vals / cos[:, None, None]  # BTF(wi, wo) / cos_i  = f(wi, wo)
    b = np.transpose(vals, (1, 0, 2)) / cos[None, :, None]  # BTF(wo, wi) / cos_o = f(wo, wi)
    np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-8)


def _hemisphere(n_mu=256, n_phi=512):
    mu = (np.arange(n_mu) + 0.5) / n_mu  # midpoint rule in cos(theta): dw = dmu dphi
    phi = (np.arange(n_phi) + 0.5) / n_phi * 2 * np.pi
    M, P = np.meshgrid(mu, phi, indexing="ij")
    st = np.sqrt(1 - M**2)
    w = np.stack([st * np.cos(P), st * np.sin(P), M], -1).reshape(-1, 3)
    return w.astype(np.float32), (1.0 / n_mu) * (2 * np.pi / n_phi)


@pytest.mark.parametrize(
    "kw",
    [
        dict(albedo=(0.9, 0.9, 0.9), f0=(0.04,) * 3, alpha=(0.1, 0.1)),
        dict(albedo=(0.9, 0.9, 0.9), f0=(0.04,) * 3, alpha=(0.9, 0.9)),
        dict(albedo=(0.0,) * 3, f0=(0.95, 0.95, 0.95), alpha=(0.1, 0.5)),
        dict(
            albedo=(0.9, 0.9, 0.9),
            f0=(0.04,) * 3,
            alpha=(0.6, 0.6),
            sheen=(1, 1, 1),
            sheen_rough=0.1,
        ),
        dict(
            albedo=(0.9, 0.9, 0.9),
            f0=(0.04,) * 3,
            alpha=(0.18, 0.6),
            sheen=(1, 1, 1),
            sheen_rough=1.0,
        ),
    ],
)
def test_brdf_white_furnace_bound(kw):
    """Per unit irradiance: integral over wo of BTF * cos_o <= cos_i (<= 1), every wi."""
    wo, dw = _hemisphere()
    p = params(**kw)
    for theta in (0.0, 30.0, 60.0, 75.0, 85.0):
        wi = spherical(np.radians([theta]), np.radians([20.0]))[0]
        ix = tuple(np.full(len(wo), c, np.float32) for c in wi)
        val = brdf(ix, tuple(wo.T), p) * wi[2]  # BTF values [K, 3]
        e = (val * wo[:, 2:3]).sum(0) * dw
        assert np.all(e <= wi[2] * 1.001), (theta, e, wi[2])


def test_furnace_quadrature_is_tight():
    """The quadrature above is accurate: a white Lambertian patch integrates to cos_i."""
    wo, dw = _hemisphere()
    wi = spherical(np.radians([40.0]), np.radians([0.0]))[0]
    ix = tuple(np.full(len(wo), c, np.float32) for c in wi)
    val = brdf(ix, tuple(wo.T), params(albedo=(1, 1, 1), f0=(0, 0, 0))) * wi[2]
    np.testing.assert_allclose((val * wo[:, 2:3]).sum(0) * dw, wi[2], rtol=1e-3)


@pytest.mark.parametrize("preset", sorted(PRESETS))
def test_rendered_presets_conserve_energy(preset):
    """Tile-averaged reflected flux <= incident flux (cos_i per unit irradiance), for every
    preset, with views over the hemisphere up to 85 degrees (omitting the rest only lowers it).
    Single scattering with geometric shadowing and masking cannot create energy."""
    cfg = BtfConfig(preset=preset, res=12, grid=64, spp=4)
    lights = spherical(np.radians([0.0, 45.0, 75.0]), np.radians([0.0, 100.0, 200.0]))
    n = 160
    cos_max = np.cos(np.radians(85))
    mu = 1 - (1 - cos_max) * (np.arange(n) + 0.5) / n
    views = spherical(np.arccos(mu), np.pi * (3 - np.sqrt(5)) * np.arange(n))
    dw = 2 * np.pi * (1 - cos_max) / n
    scene = make_scene(build_maps(cfg), lights)
    samples = subsamples(cfg)
    e = np.zeros((3, 3))
    for w in views:
        e += render_view(scene, w, samples, (12, 12)).mean((1, 2)) * w[2] * dw
    assert np.all(np.isfinite(e)) and e.min() > 0
    assert np.all(e <= lights[:, 2:3] * 1.02), (e, lights[:, 2])


def _edge_ratio(img):
    """Mean |difference| across the wrap seam, divided by the largest mean |difference| across
    any interior column (row) boundary. A seamless tile's seam is just one more boundary (ratio
    <= about 1); a real seam stands out above every interior boundary (ratio >> 1)."""
    col = np.abs(np.diff(img, axis=1)).mean(0)
    row = np.abs(np.diff(img, axis=0)).mean(1)
    seam_x = np.abs(img[:, 0] - img[:, -1]).mean()
    seam_y = np.abs(img[0] - img[-1]).mean()
    return max(seam_x / col.max(), seam_y / row.max())


@pytest.mark.parametrize("preset", sorted(PRESETS))
def test_tiles_continue_across_edges(preset):
    cfg = BtfConfig(preset=preset, res=32, grid=64, spp=4)
    maps = build_maps(cfg)
    assert _edge_ratio(maps.height) < 1.1
    assert _edge_ratio(maps.albedo.sum(-1) + maps.f0.sum(-1)) < 1.1
    dirs = spherical(np.radians([0.0, 60.0]), np.radians([0.0, 130.0]))
    scene = make_scene(maps, dirs)
    for w in dirs:
        for sl in render_view(scene, w, subsamples(cfg), (32, 32)):
            assert _edge_ratio(sl.sum(-1)) < 1.1


@pytest.mark.parametrize("preset", ["wood", "stone"])
def test_seam_statistic_detects_a_seam(preset):
    """Negative control: a crop that is not a whole period has a visible seam."""
    maps = build_maps(BtfConfig(preset=preset, grid=64))
    assert _edge_ratio(maps.height) < 1.1
    assert _edge_ratio(maps.height[:, :41]) > 2.0
