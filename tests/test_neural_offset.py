"""NeuMIP's neural offset module (issue #44): the numpy reference against the trained torch
model, the pack that carries it, its cost, the apparent-relief measure of ``auto`` (the
rendering: test_neural_offset_gpu.py)."""

import numpy as np
import pytest
import torch
from distill_helpers import analytic_btf, expect_one_line_error, run_cli

from vrneural.btf.format import read_btf, write_btf
from vrneural.distill.models import NeuralModel, make_spec
from vrneural.formats.vrnm import read_vrnm, write_vrnm
from vrneural.material import material_forward
from vrneural.neural_offset import offset_scale, offset_uv
from vrneural.relief import apparent_relief, pair_relief

FAST = ("--no-progress", "--max-test-slices", "4", "--epochs", "1")


def _model(method, march, res=16, seed=0, scale=0.5):
    spec = make_spec(method, (res, res))
    spec["parallax"] = {"kind": "neural", "march": march, "res": [res, res], "channels": 4,
                        "hidden": [8, 8]}  # fmt: skip
    m = NeuralModel(spec, seed)
    if not scale:
        return m
    g = torch.Generator().manual_seed(seed + 7)
    with torch.no_grad():  # a trained-looking module: offsets of a few texels
        for lay in m.offset_mlp.layers:
            lay.weight.copy_(torch.randn(lay.weight.shape, generator=g) * scale)
            lay.bias.copy_(torch.randn(lay.bias.shape, generator=g) * scale)
    return m.eval()


def _views(n=40, seed=1):
    rng = np.random.default_rng(seed)
    uv = rng.random((n, 4, 2)).astype(np.float32)
    wi = np.array([0.3, 0.1, 0.9487], np.float32)
    wo = np.array([0.7, -0.45, 0.55], np.float32)  # 57 degrees: the 0.6 clamp is active
    return uv, wi / np.linalg.norm(wi), wo / np.linalg.norm(wo)


@pytest.mark.parametrize("method", ["student", "neumip"])
@pytest.mark.parametrize("march", ["texel", "block"])
def test_numpy_twin_matches_torch_and_the_pack_round_trips(tmp_path, method, march):
    m = _model(method, march)
    uv, wi, wo = _views()
    with torch.no_grad():
        got = m.predict(torch.from_numpy(wi), torch.from_numpy(wo), torch.from_numpy(uv)).numpy()
    write_vrnm(tmp_path / "p.vrnm", m.to_material({"name": "n"}))
    mat = read_vrnm(tmp_path / "p.vrnm")
    assert mat.parallax == {"kind": "neural", "march": march}
    assert mat.offset_tex.shape == (16, 16, 4) and mat.offset_tex.dtype == np.float16
    n = len(uv)
    ref = material_forward(mat, np.repeat(wi[None], n, 0), np.repeat(wo[None], n, 0), uv)
    assert np.abs(ref - got).max() < 1e-5 * max(1.0, np.abs(got).max())
    # the module really moves the lookups: without it the values differ
    moved = offset_uv(mat.offset_net, mat.offset_tex, np.repeat(wo[None], n, 0), uv, march)
    shift = np.abs(moved - uv).max() * 16
    assert 0.1 < shift < 100, shift
    if march == "block":  # the block's four texels move alike
        d = moved - uv
        assert np.allclose(d, d[:, :1], atol=1e-6)


def test_depth_to_offset_stage_is_neumips_eq6():
    wo = np.array([[0.6, 0.0, 0.8], [0.0, 0.96, 0.28]], np.float32)  # 37 and 74 degrees
    s = offset_scale(wo, (16, 32))
    # r / max(wo.z, 0.6) * (wo.x, wo.y), in texels of a 16 x 32 grid
    assert np.allclose(s[0], [0.6 / 0.8 / 32, 0.0])
    assert np.allclose(s[1], [0.0, 0.96 / 0.6 / 16])


def test_depth_distillation_pulls_the_students_depth_to_the_teachers():
    from types import SimpleNamespace

    from vrneural.distill.core import DistillNet

    teacher = _model("neumip", "texel", seed=3)
    student = _model("student", "texel", seed=0)
    uv, wi, wo = _views(16)
    wi, wo, uv = torch.from_numpy(wi), torch.from_numpy(wo), torch.from_numpy(uv)
    data = SimpleNamespace(target=lambda pair: torch.zeros(16, 4, 3))
    base = dict(distill=True, space="linear", sigma=0.1, lambda1=0.1, lambda2=0.1, lod_weight=1)
    cfg = SimpleNamespace(**base, offset_weight=1.0)
    torch.manual_seed(0)  # the same T maps in both nets
    net = DistillNet(student, teacher, data, cfg)
    loss, parts = net(wi, wo, uv, 0)
    gap = (student.depth(wi, wo, uv) - teacher.depth(wi, wo, uv)).abs().mean().detach()
    assert float(parts["depth"]) == pytest.approx(float(gap)) and float(gap) > 0
    torch.manual_seed(0)
    off = DistillNet(student, teacher, data, SimpleNamespace(**base, offset_weight=0.0))
    loss0, parts0 = off(wi, wo, uv, 0)
    assert "depth" not in parts0
    assert float((loss - loss0).detach()) == pytest.approx(float(gap), rel=1e-5)


def test_offset_trains_from_zero_and_costs_macs():
    torch.manual_seed(0)
    m = _model("neumip", "texel", scale=0.0)  # starts as no offset
    opt = torch.optim.Adam(m.parameters(), lr=1e-2)
    uv, wi, wo = _views(64)
    target = torch.rand(64, 4, 3)
    before = m.offset_mlp.layers[-1].weight.detach().clone()
    assert not before.any()
    m.train()
    for _ in range(3):
        raw, _ = m(torch.from_numpy(wi), torch.from_numpy(wo), torch.from_numpy(uv))
        loss = (raw - target).abs().mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
    assert not torch.equal(before, m.offset_mlp.layers[-1].weight)  # the depth gets a gradient
    assert m.offset_tex.grad is not None and m.offset_tex.grad.abs().sum() > 0
    assert any(p is m.offset_tex for p in m.texture_parameters())  # at the texture lr
    plain = NeuralModel(make_spec("neumip", (16, 16)), 0).to_material()
    mat = m.to_material()
    from vrneural.mlp import macs

    assert 100 < macs(mat.offset_net) <= 6 * 8 + 8 * 8 + 8  # its non-zero weights
    assert mat.macs_per_texel == plain.macs_per_texel + macs(mat.offset_net)
    assert mat.texture_bytes == plain.texture_bytes + 16 * 16 * 4 * 2


def test_pack_without_its_offset_is_refused(tmp_path):
    mat = _model("student", "texel").to_material()
    mat.offset_tex = mat.offset_tex[:8]
    with pytest.raises(ValueError, match=r"offset texture has shape \[8, 16, 4\]"):
        mat.__post_init__()
    mat = _model("student", "texel").to_material()
    mat.offset_net = None
    with pytest.raises(ValueError, match="parallax kind 'neural' needs the offset MLP"):
        mat.__post_init__()


def test_apparent_relief_sees_a_shifted_pattern_and_not_a_flat_one():
    rng = np.random.default_rng(0)
    from scipy.ndimage import gaussian_filter, map_coordinates

    base = gaussian_filter(rng.random((32, 32)), 1.0, mode="wrap")
    y, x = np.mgrid[0:32, 0:32].astype(np.float64)
    height = 2.0 * np.sin(2 * np.pi * x / 32) * np.cos(2 * np.pi * y / 16)  # texels, +-2
    d = np.array([2.0, 1.0])  # tan 66 degrees
    moved = map_coordinates(base, [y + height * d[1], x + height * d[0]], order=1, mode="wrap")
    r = pair_relief(base, moved, d)
    assert 2.5 < r < 4.5, r  # the 5-95% range of +-2 texels, smoothed by the window
    assert pair_relief(base, base, d) < 0.6


def test_auto_neural_only_without_a_height_field_and_with_relief(tmp_path):
    plain = analytic_btf(tmp_path / "plain.btf", res=16, n_dirs=6)
    assert apparent_relief(read_btf(plain)) < 2.0  # a flat texture: off
    code, err = run_cli("teach", plain, "-o", tmp_path / "t.pt", *FAST)
    assert code == 0, err
    assert read_vrnm(tmp_path / "t.vrnm").parallax_kind == "off"
    # the same data with --parallax neural: the offset module in the pack, twins agree
    code, err = run_cli("teach", plain, "-o", tmp_path / "n.pt", "--parallax", "neural", *FAST)
    assert code == 0, err
    code, err = run_cli("distill", tmp_path / "n.pt", "-o", tmp_path / "s.pt",
                        "--parallax", "neural", "--offset-weight", "0.1", *FAST)  # fmt: skip
    assert code == 0, err
    expect_one_line_error(
        ["distill", tmp_path / "n.pt", "-o", tmp_path / "e.pt", "--offset-weight", "-1", *FAST],
        "--offset-weight",
    )  # fmt: skip
    for p in ("n.vrnm", "s.vrnm"):
        mat = read_vrnm(tmp_path / p)
        assert mat.parallax_kind == "neural" and mat.offset_net is not None
        assert mat.meta["parallax"]["why"] == "--parallax neural"
        assert mat.meta["metrics"]["pack_vs_torch_max_abs"] < 1e-4


def test_old_packs_still_load(tmp_path):
    """A pack written by the height route (version 4, no offset) reads as it was."""
    from vrneural.formats.container import read_container, write_container

    m = NeuralModel(make_spec("student", (16, 16)))
    write_vrnm(tmp_path / "p.vrnm", m.to_material({"name": "p"}))
    header, arrays, version = read_container(tmp_path / "p.vrnm", b"VRNM", (5,))
    assert version == 5 and "offset" not in header
    write_container(tmp_path / "v4.vrnm", b"VRNM", 4, header, dict(arrays))
    mat = read_vrnm(tmp_path / "v4.vrnm")
    assert mat.parallax_kind == "off" and mat.offset_net is None


def test_bad_neural_input_is_one_line(tmp_path):
    b = read_btf(analytic_btf(tmp_path / "p.btf", res=16, n_dirs=4))
    h = write_btf(tmp_path / "h.btf", np.asarray(b.values, np.float32), b.light_dirs,
                  b.view_dirs, {"name": "h"}, np.zeros((24, 24), np.float32))  # fmt: skip
    expect_one_line_error(
        ["teach", h, "-o", tmp_path / "e.pt", "--parallax", "neural", *FAST],
        "h.btf: height", "height field 24x24 does not fit the 16x16 texels",
    )  # fmt: skip


def test_resume_keeps_what_auto_chose(tmp_path, monkeypatch):
    """A run resumed after auto's rule changed (or its measure moved) keeps its own choice."""
    import vrneural.parallax
    import vrneural.relief

    plain = analytic_btf(tmp_path / "plain.btf", res=16, n_dirs=4)
    fast = ("--no-progress", "--max-test-slices", "4")
    code, err = run_cli("teach", plain, "-o", tmp_path / "t.pt", "--epochs", "1", *fast)
    assert code == 0, err
    assert read_vrnm(tmp_path / "t.vrnm").parallax_kind == "off"
    monkeypatch.setattr(vrneural.relief, "apparent_relief", lambda btf: 5.0)
    monkeypatch.setattr(vrneural.parallax, "choose_kind", lambda *a: ("neural", "a new rule"))
    code, err = run_cli("teach", plain, "-o", tmp_path / "t.pt", "--epochs", "2", "--resume",
                        *fast)  # fmt: skip
    assert code == 0, err
    assert read_vrnm(tmp_path / "t.vrnm").parallax_kind == "off"
    code, err = run_cli("teach", plain, "-o", tmp_path / "n.pt", "--epochs", "1", *fast)
    assert code == 0, err  # a new run follows the (patched) rule
    assert read_vrnm(tmp_path / "n.vrnm").parallax_kind == "neural"
