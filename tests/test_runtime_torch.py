"""GPU texture-space pass vs the torch student (vrneural.distill.models.NeuralModel)."""

import numpy as np
import pytest
from runtime_helpers import quad_atlas

torch = pytest.importorskip("torch")
models = pytest.importorskip("vrneural.distill.models")


def _local(v, t, b, n):
    return np.stack([(v * t).sum(-1), (v * b).sum(-1), (v * n).sum(-1)], -1)


@pytest.mark.gpu
def test_gpu_texture_pass_matches_torch_student():
    from vrneural.runtime import reference, texture_pass

    model_t = models.NeuralModel(models.make_spec("student", (16, 16)), seed=4)
    with torch.no_grad():
        for p in model_t.tex.values():
            p.mul_(10)  # tex_init 0.1 is too flat to exercise the sampling
    mat = model_t.to_material()
    at = quad_atlas(16)
    eye = np.float32([0.2, -0.1, 1.2])
    lp = np.float32([[-0.3, 0.4, 0.9]])
    lc = np.float32([[2.0, 1.5, 1.0]])
    tiling = (1.5, 1.5, 0.0, 0.0)
    got, _ = texture_pass.shade_texture_space(at, mat, np.eye(4), eye, lp, lc, tiling)
    g = reference.texture_blocks(at, np.eye(4), tiling)
    wo_w = eye - g["pos"]
    wo = _local(wo_w / np.linalg.norm(wo_w, axis=1, keepdims=True), g["t"], g["b"], g["n"])
    lv = lp[0] - g["pos"]
    d2 = (lv**2).sum(-1)
    wi = _local(lv / np.sqrt(d2)[:, None], g["t"], g["b"], g["n"])
    assert (wi[:, 2] > 0).all() and (wo[:, 2] > 0).all()
    want = np.zeros_like(got[..., :3])
    with torch.no_grad():
        for k in range(len(wi)):  # the torch student takes one angular condition per call
            y = model_t.predict(
                torch.from_numpy(wi[k]),
                torch.from_numpy(wo[k]),
                torch.from_numpy(g["uvs"][k : k + 1]),
            ).numpy()[0]
            want[g["ty"][k], g["tx"][k]] = y * lc[0] / d2[k]
    # f32 both sides, summation order differs; the GPU stores f16 (2^-11 relative)
    np.testing.assert_allclose(got[..., :3], want, rtol=2e-3, atol=1e-5)
