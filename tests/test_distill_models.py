"""The torch models are twins of vrneural.material: same lookup, same half vector, same MLP."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from vrneural import material as npm
from vrneural.distill import lookups, models
from vrneural.distill.lafortune import (
    N_PARAMS,
    fit_lafortune,
    lafortune_eval,
    lafortune_jacobian,
)


def test_bilinear_wrap_matches_numpy(rng):
    tex = rng.standard_normal((6, 10, 3)).astype(np.float32)
    uv = rng.uniform(-1.5, 2.5, (200, 2)).astype(np.float32)  # wraps in both directions
    ref = npm.sample_bilinear_wrap(tex, uv)
    got = lookups.sample_bilinear_wrap(torch.from_numpy(tex), torch.from_numpy(uv)).numpy()
    # both use float64 coordinates and float32 weights: only summation order can differ
    np.testing.assert_allclose(got, ref, atol=1e-6)


def test_half_vector_matches_numpy(rng):
    wi = rng.standard_normal((50, 3)).astype(np.float32)
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo = rng.standard_normal((50, 3)).astype(np.float32)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wo[:5] = -wi[:5]  # opposite directions -> (0, 0, 1)
    got = lookups.half_vector(torch.from_numpy(wi), torch.from_numpy(wo)).numpy()
    np.testing.assert_allclose(got, npm.half_vector(wi, wo), atol=1e-7)
    assert np.array_equal(got[:5], np.tile([0, 0, 1], (5, 1)).astype(np.float32))


@pytest.mark.parametrize("method", ["student", "single8", "neumip", "teacher"])
def test_model_equals_its_pack(method, rng):
    spec = models.make_spec(method, (8, 12), width=16)
    m = models.NeuralModel(spec, seed=3)
    with torch.no_grad():  # non-trivial textures and biases, so every path matters
        for t in m.tex.values():
            t.normal_(0, 1)
        for p in m.parameters():
            p.add_(0.05)
    mat = m.to_material()
    wi = np.array([0.3, -0.2, 0.93], np.float32)
    wi /= np.linalg.norm(wi)
    wo = np.array([-0.5, 0.1, 0.86], np.float32)
    wo /= np.linalg.norm(wo)
    uv = rng.uniform(-0.2, 1.2, (40, 4, 2)).astype(np.float32)
    ref = npm.material_forward(mat, np.tile(wi, (40, 1)), np.tile(wo, (40, 1)), uv)
    got = m.predict(torch.from_numpy(wi), torch.from_numpy(wo), torch.from_numpy(uv))
    # float32 both sides; the only differences are summation orders (measured < 2e-7)
    np.testing.assert_allclose(got.detach().numpy(), ref, atol=1e-5, rtol=1e-5)
    assert mat.output == ("log1p" if method == "neumip" else "linear")


@pytest.mark.parametrize(("method", "arch"), [("student", "coarse_fine"), ("single8", "single")])
def test_random_material_has_the_trained_shape(method, arch):
    """The frame benchmarks time ``random_material`` networks: their layer shapes (hence the
    generated shader and its multiply-adds) must be what ``vrneural distill`` trains."""
    trained = models.NeuralModel(models.make_spec(method, (32, 32))).to_material()
    rand = npm.random_material(0, arch)
    shapes = {k: [lay.weight.shape for lay in v] for k, v in trained.networks.items()}
    assert {k: [lay.weight.shape for lay in v] for k, v in rand.networks.items()} == shapes
    assert [lay.act for v in rand.networks.values() for lay in v] == [
        lay.act for v in trained.networks.values() for lay in v
    ]
    assert rand.macs_per_texel == trained.macs_per_texel


def test_sizes_match_the_paper_scale():
    mats = {
        k: models.NeuralModel(models.make_spec(k, (32, 32))).to_material()
        for k in ("student", "single8", "neumip", "teacher")
    }
    assert 1400 <= mats["student"].weight_bytes <= 1700  # paper: about 1.6 KB
    assert mats["student"].macs_per_texel < mats["single8"].macs_per_texel
    assert 6000 <= mats["neumip"].weight_bytes <= 7500  # paper: 6.6 KB
    assert mats["neumip"].textures["features"].shape[2] == 7


def test_lafortune_jacobian_matches_autograd():
    g = torch.Generator().manual_seed(0)
    wi = torch.nn.functional.normalize(torch.rand(7, 3, generator=g) + 0.2, dim=-1).double()
    wo = torch.nn.functional.normalize(torch.rand(7, 3, generator=g) + 0.1, dim=-1).double()
    p = torch.randn(1, N_PARAMS, generator=g).double() * 0.3
    p[0, [15, 28, 41, 54]] = 0.5  # exponents e^0.5

    def f(q):
        return lafortune_eval(q[None], wi, wo)[0].reshape(-1)

    ref = torch.autograd.functional.jacobian(f, p[0])
    got = lafortune_jacobian(p, wi, wo)[0]
    torch.testing.assert_close(got, ref, atol=1e-10, rtol=1e-8)


def test_lafortune_fit_reduces_error():
    g = torch.Generator().manual_seed(1)
    d = torch.nn.functional.normalize(
        torch.rand(40, 3, generator=g) * torch.tensor([2, 2, 1]) - torch.tensor([1, 1, -0.3]),
        dim=-1,
    )
    wi, wo = d[:20].repeat(20, 1), d[20:].repeat_interleave(20, 0)
    truth = torch.zeros(3, N_PARAMS)
    truth[:, :3] = torch.tensor([0.2, 0.3, 0.1])
    truth[:, 3:6] = 0.6
    truth[:, 6:15] = torch.diag(torch.tensor([-1.0, -1.0, 1.0])).reshape(9)
    truth[:, 15] = torch.tensor([2.0, 2.5, 3.0])
    y = lafortune_eval(truth, wi, wo)
    p = fit_lafortune(y, wi, wo, iters=30)
    err0 = (lafortune_eval(fit_lafortune(y, wi, wo, iters=0), wi, wo) - y).abs().mean()
    err = (lafortune_eval(p, wi, wo) - y).abs().mean()
    assert err < 0.2 * err0 and err < 5e-3
