"""teach -> distill -> export -> reload: the pack's numpy forward equals the torch student."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from distill_helpers import FAST, run_cli, trained  # noqa: F401 (fixture)

from vrneural.btf.format import read_btf
from vrneural.distill.checkpoint import load_checkpoint, model_from_checkpoint, save_checkpoint
from vrneural.distill.data import SliceData, to_blocks
from vrneural.formats.vrnm import read_vrnm
from vrneural.material import material_forward


def _compare(ck_path, pack_path, jitter_seed=None):
    ck = load_checkpoint(ck_path)
    model = model_from_checkpoint(ck)
    mat = read_vrnm(pack_path)
    data = SliceData(read_btf(ck["btf"]["path"]), ck["split"]["test"])
    gen = None if jitter_seed is None else torch.Generator().manual_seed(jitter_seed)
    worst = 0.0
    for pair in range(0, data.values.shape[0] * data.n_view, 3):
        wi, wo = data.dirs(pair)
        uv = data.uv(gen, shard=False)
        n = uv.shape[0]
        ref = material_forward(
            mat, np.tile(wi.numpy(), (n, 1)), np.tile(wo.numpy(), (n, 1)), uv.numpy()
        )
        with torch.no_grad():
            got = model.predict(wi, wo, uv).numpy()
        worst = max(worst, float(np.abs(ref - got).max()))
    return worst, mat, ck


@pytest.mark.parametrize("which", ["student", "teacher"])
def test_pack_equals_torch(trained, which):  # noqa: F811
    ck = trained[which]
    for seed in (None, 7):  # texel centres, then jittered lookups
        worst, mat, _ = _compare(ck, ck.with_suffix(".vrnm"), seed)
        assert worst <= 1e-5, worst
    assert mat.arch == ("coarse_fine" if which == "student" else "single")


def test_pack_meta_and_config(trained):  # noqa: F811
    mat = read_vrnm(trained["student"].with_suffix(".vrnm"))
    meta = mat.meta
    assert (
        meta["provenance"]["btf"]["sha256"] == load_checkpoint(trained["teacher"])["btf"]["sha256"]
    )
    assert meta["provenance"]["epochs"] == 2
    assert np.isfinite(meta["metrics"]["test_l1"])
    assert meta["metrics"]["pack_vs_torch_max_abs"] <= 1e-5
    r = meta["ranges"]
    assert {"weight.coarse.0", "texture.fine", "act.coarse.1", "act.fine.1"} <= set(r)
    assert all(0 < v["max_abs"] < 65504 for v in r.values())
    # the BTF's direction range, from the checkpoint (docs/conventions.md section 2b)
    from vrneural.btf import read_btf
    from vrneural.grazing import directions_range

    btf = read_btf(meta["provenance"]["btf"]["path"])
    want = directions_range(btf.light_dirs, btf.view_dirs)
    assert mat.dir_range == want == tuple(load_checkpoint(trained["student"])["btf"]["dir_range"])
    assert read_vrnm(trained["teacher"].with_suffix(".vrnm")).dir_range == want
    cfg = json.loads((trained["dir"] / "student.pt.config.json").read_text())
    assert cfg["config"] == "DistillConfig" and cfg["sigma"] == 0.1 and cfg["epochs"] == 2
    assert len(cfg["history"]) == 2


def test_export_cli_rewrites_the_same_pack(trained, tmp_path):  # noqa: F811
    out = tmp_path / "again.vrnm"
    code, err = run_cli("export", trained["student"], "-o", out)
    assert code == 0, err
    a, b = read_vrnm(out), read_vrnm(trained["student"].with_suffix(".vrnm"))
    for k in a.textures:
        assert np.array_equal(a.textures[k], b.textures[k])
    for k in a.networks:
        for la, lb in zip(a.networks[k], b.networks[k], strict=True):
            assert np.array_equal(la.weight, lb.weight) and np.array_equal(la.bias, lb.bias)


def test_baselines_train_and_export(trained, tmp_path, capsys):  # noqa: F811
    for method, extra in (("neumip", ["--no-distill"]), ("single8", [])):
        out = tmp_path / f"{method}.pt"
        code, err = run_cli(
            "distill",
            trained["teacher"],
            "-o",
            out,
            "--method",
            method,
            "--epochs",
            1,
            *extra,
            *FAST,
        )
        assert code == 0, err
        label = "neumip (no distillation)" if method == "neumip" else method
        printed = capsys.readouterr().out
        assert f"{out}: {label} epochs 1  test L1" in printed
        worst, mat, ck = _compare(out, out.with_suffix(".vrnm"))
        assert worst <= 1e-5
        assert mat.output == ("log1p" if method == "neumip" else "linear")
        assert ck["config"]["distill"] == (method != "neumip")
        # the teacher's L1 on the same test slices is kept, and a 1-epoch network far above it
        # is warned about as likely undertrained (the ratio is printed on stdout)
        tl1, sl1 = ck["teacher_test_l1"], ck["history"][-1]["test_l1"]
        assert 0 < tl1 < sl1
        assert (f"test L1 {sl1 / tl1:.1f}x the teacher's" in err) == (sl1 / tl1 > 8), err
        # and the test slices' mean value (the L1 of predicting black) is the scale it reads on
        black = ck["test_mean"]
        assert 0 < black and f"test L1 {sl1:.5f} ({sl1 / black:.0%} of the mean value)" in printed
        assert ("predicting black would score better" in err) == (sl1 > black), err
        w = mat.networks["mlp"][0].weight
        if method == "neumip":  # NeuMIP's inputs: wi.xy, wo.xy; trained, the rest stay exactly 0
            assert np.all(w[:, [0, 1, 3, 4]] != 0) and not np.any(w[:, [2, 5, 6, 7, 8]])
            assert mat.macs_per_texel == (4 + 7) * 25 + 2 * 25 * 25 + 25 * 3
        else:
            assert np.all(w != 0)


def test_neumip_checkpoint_from_before_the_option_resumes_with_nine_inputs(trained, tmp_path):  # noqa: F811
    """A NeuMIP checkpoint without ``neumip_dirs`` read wi, wo and h; it resumes as such."""
    out = tmp_path / "nm.pt"
    args = ["--method", "neumip", "--no-distill", *FAST]
    code, err = run_cli(
        "distill", trained["teacher"], "-o", out, "--epochs", 1, *args, "--neumip-dirs", "full"
    )
    assert code == 0, err
    ck = load_checkpoint(out)
    del ck["config"]["neumip_dirs"]
    save_checkpoint(out, ck)
    code, err = run_cli("distill", trained["teacher"], "-o", out, "--epochs", 2, "--resume", *args)
    assert code == 0, err
    ck = load_checkpoint(out)
    assert ck["epoch"] == 2 and ck["config"]["neumip_dirs"] == "full"
    assert np.all(read_vrnm(out.with_suffix(".vrnm")).networks["mlp"][0].weight != 0)


def test_blocks_are_2x2():
    a = torch.arange(16).reshape(4, 4)
    assert to_blocks(a)[1].tolist() == [2, 3, 6, 7]


@pytest.mark.parametrize("l1", [0.004, 0.012])
def test_report_warns_when_predicting_black_would_score_better(l1, capsys):
    """The result line gives the test L1 as a share of the test slices' mean value, and an L1
    above it (worse than a network that outputs 0) is a warning on stderr."""
    from vrneural.cli.teach import _report

    ck = {"history": [{"test_l1": l1}], "method": "teacher", "epoch": 3, "test_mean": 0.01}
    assert _report(lambda: ck, "t.pt") == 0
    out, err = capsys.readouterr()
    assert f"t.pt: teacher epochs 3  test L1 {l1:.5f} ({l1 / 0.01:.0%} of the mean value)" in out
    warned = f"warning: t.pt: test L1 {l1:.5f} is above the test slices' mean value 0.01000"
    assert (warned in err) == (l1 > 0.01), err
