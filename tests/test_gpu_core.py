"""The GPU layer on the real adapter (lavapipe in CI)."""

import numpy as np
import pytest

pytestmark = pytest.mark.gpu


def test_adapter_summary_has_what_info_needs():
    from vrneural.gpu import adapter_summary
    from vrneural.gpu.device import BACKENDS

    s = adapter_summary()
    assert s.name and s.backend in BACKENDS  # never OpenGL, where our kernels are wrong
    assert set(s.features) == {"shader-f16", "timestamp-query", "subgroup"}
    assert s.limits["max_texture_dimension_2d"] >= 2048


def test_device_is_shared():
    from vrneural.gpu import get_device

    assert get_device() is get_device()


def test_texture_round_trip_unaligned_rows(rng):
    import wgpu

    from vrneural.gpu import read_texture, upload_texture

    for fmt, dt in [
        ("rgba16float", np.float16),
        ("r32uint", np.uint32),
        ("rgba32float", np.float32),
    ]:
        shape = (13, 37, 4) if fmt != "r32uint" else (13, 37)
        data = (rng.random(shape) * 100).astype(dt)
        tex = upload_texture(data, fmt, wgpu.TextureUsage.COPY_SRC)
        np.testing.assert_array_equal(read_texture(tex), data)


def test_buffer_round_trip(rng):
    import wgpu

    from vrneural.gpu import read_buffer, upload_buffer

    data = rng.standard_normal(1001).astype(np.float32)
    buf = upload_buffer(data, wgpu.BufferUsage.STORAGE | wgpu.BufferUsage.COPY_SRC)
    np.testing.assert_array_equal(read_buffer(buf, np.float32, 1001), data)


def test_load_wgsl_and_cache():
    from vrneural.gpu import load_wgsl
    from vrneural.gpu.mlp_kernel import mlp_wgsl
    from vrneural.gpu.pipelines import PIPELINES
    from vrneural.mlp import random_mlp

    assert "macro material_fns" in load_wgsl("neural_material")
    assert load_wgsl("neural_material") == load_wgsl("neural_material.wgsl")
    cache = PIPELINES
    code = mlp_wgsl(random_mlp([3, 4, 2], seed=0))
    c = {"N": 16, "WIDTH": 16, "STRIDE": 64}
    p1 = cache.compute(code, constants=c)
    hits = cache.hits
    p2 = cache.compute(code, constants=c)
    assert p1 is p2 and cache.hits == hits + 1


def test_timer_reports_positive_ms(rng):
    from vrneural.gpu import GpuTimer, has_feature
    from vrneural.gpu.mlp_kernel import MlpKernel
    from vrneural.mlp import random_mlp

    if not has_feature("timestamp-query"):
        pytest.skip("adapter has no timestamp-query")
    timer = GpuTimer(max_passes=4)
    k = MlpKernel(random_mlp([8, 8, 8, 3], seed=0))
    k.run(rng.standard_normal((65536, 8)).astype(np.float32), repeats=3, timer=timer)
    ms = timer.read()
    assert set(ms) == {"mlp"} and 0 < ms["mlp"] < 60_000
    assert timer.read() == {}  # reset after read
