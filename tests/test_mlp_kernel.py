"""The kernel pattern: generated WGSL MLP vs its numpy twin on seeded inputs."""

import numpy as np
import pytest

from vrneural.mlp import Layer, macs, mlp_forward, pack_weights, random_mlp

SIZES = [24, 8, 8, 8, 3]


def test_reference_matches_explicit_math(rng):
    layers = random_mlp([5, 4, 2], seed=3)
    x = rng.standard_normal((7, 5)).astype(np.float32)
    h = np.maximum(x @ layers[0].weight.T + layers[0].bias, 0)
    want = h @ layers[1].weight.T + layers[1].bias
    np.testing.assert_allclose(mlp_forward(x, layers), want, rtol=1e-6, atol=1e-6)
    assert macs(layers) == 5 * 4 + 4 * 2
    assert pack_weights(layers).size == 5 * 4 + 4 + 4 * 2 + 2


def test_layer_validation():
    with pytest.raises(ValueError, match="do not match"):
        Layer(np.zeros((3, 2), np.float32), np.zeros(2, np.float32))
    with pytest.raises(ValueError, match="activation"):
        Layer(np.zeros((3, 2), np.float32), np.zeros(3, np.float32), act="tanh")


def test_wgsl_float_literals_round_trip():
    from vrneural.gpu.shaders import wgsl_float

    for v in [0.0, -1.5, 1e-30, 3.4e38, 0.1, -7.0]:
        s = wgsl_float(v)
        assert float(s.rstrip("f")) == float(np.float32(v))
    assert wgsl_float(1.0, "h") == "1.0h"
    with pytest.raises(ValueError, match="non-finite"):
        wgsl_float(float("inf"))


@pytest.mark.gpu
@pytest.mark.parametrize("buffer_weights", [False, True], ids=["constants", "buffer"])
@pytest.mark.parametrize("precision", ["f32", "f16"])
def test_gpu_mlp_parity(rng, precision, buffer_weights):
    from vrneural.gpu.mlp_kernel import mlp_forward as gpu_forward

    layers = random_mlp(SIZES, seed=11)
    layers[1].weight[0, :3] = 0.0  # skipped terms must not change the result
    x = rng.standard_normal((5000, SIZES[0])).astype(np.float32)
    got = gpu_forward(x, layers, precision, buffer_weights)
    want = mlp_forward(x, layers, precision)
    assert got.shape == want.shape == (5000, 3)
    assert np.isfinite(got).all()
    err = np.abs(got - want)
    scale = np.abs(want).max()
    if precision == "f32":
        # Only summation order differs: llvmpipe measured max 9.5e-7 on outputs of size ~4.
        assert err.max() <= 1e-5 * max(1.0, scale)
    else:
        # The GPU accumulates in f16, the twin rounds per layer: llvmpipe measured 5.9e-3 on
        # outputs of size ~4 (1.5 f16 ulps there). Allow 4 layers x 1 ulp at the output scale.
        assert err.max() <= 4 * 2.0 ** (np.floor(np.log2(scale)) - 10)


@pytest.mark.gpu
def test_gpu_mlp_multi_row_dispatch(rng):
    """More evaluations than one dispatch row holds (2-D dispatch indexing)."""
    from vrneural.gpu import mlp_kernel

    layers = random_mlp([4, 8, 4], seed=2)
    x = rng.standard_normal((3000, 4)).astype(np.float32)
    old = mlp_kernel.MAX_GROUPS_X
    mlp_kernel.MAX_GROUPS_X = 7  # force gy > 1
    try:
        got = mlp_kernel.mlp_forward(x, layers)
    finally:
        mlp_kernel.MAX_GROUPS_X = old
    np.testing.assert_allclose(got, mlp_forward(x, layers), rtol=1e-5, atol=1e-5)
