"""`vrneural eval`: scoring runtime packs against a BTF with numpy alone."""

from __future__ import annotations

import json

import numpy as np
import pytest
from distill_helpers import expect_one_line_error, run_cli, trained  # noqa: F401 (fixture)

from vrneural.btf.dirs import direction_set
from vrneural.btf.format import read_btf, write_btf
from vrneural.btf.identity import btf_fingerprint, split_pairs
from vrneural.errors import VrnError
from vrneural.formats.vrnm import read_vrnm, write_vrnm
from vrneural.material import material_forward, random_material
from vrneural.scoring.config import EvalConfig
from vrneural.scoring.run import evaluate, labels, trainer_test
from vrneural.scoring.score import from_blocks, pick_slices, score, texel_blocks, to_blocks


def _own_btf(path, mat, res=8, n_dirs=4, offset=0.0):
    """A BTF whose values are ``mat``'s own slices (+ ``offset``), computed texel by texel
    (one block per texel call, not the slice-wide batches eval uses)."""
    d = direction_set(n_dirs)
    vals = np.zeros((n_dirs, n_dirs, res, res, 3), np.float32)
    uv = texel_blocks(res, res)
    for li in range(n_dirs):
        for vi in range(n_dirs):
            for b in range(uv.shape[0]):
                y = material_forward(mat, d[li][None], d[vi][None], uv[b : b + 1])  # [1, 4, 3]
                by, bx = divmod(b, res // 2)
                vals[li, vi, 2 * by : 2 * by + 2, 2 * bx : 2 * bx + 2] = y[0].reshape(2, 2, 3)
    return write_btf(path, vals + offset, d, d, {"name": "own"})


def _pack(tmp_path, name="m.vrnm", seed=0, arch="coarse_fine", meta=None):
    mat = random_material(seed, arch=arch)
    mat.meta.update(meta or {})
    write_vrnm(tmp_path / name, mat)
    return tmp_path / name, read_vrnm(tmp_path / name)  # float16 textures, as shipped


def test_blocks_round_trip_and_match_training():
    torch_blocks = pytest.importorskip("vrneural.distill.data").to_blocks
    import torch

    a = np.arange(6 * 4 * 2, dtype=np.float32).reshape(6, 4, 2)
    assert np.array_equal(from_blocks(to_blocks(a), 6, 4), a)
    assert np.array_equal(to_blocks(a), torch_blocks(torch.from_numpy(a)).numpy())
    uv = texel_blocks(4, 4)
    assert uv.shape == (4, 4, 2)
    assert np.allclose(uv[1, 2], [(2 + 0.5) / 4, (0 + 1 + 0.5) / 4])  # block (0, 1), texel (1, 2)


def test_pick_slices():
    assert pick_slices("all", 10, 64) == list(range(10))
    assert pick_slices("auto", 10, 64) == list(range(10))
    three = pick_slices("3", 10, 64)
    assert len(set(three)) == 3 and three == sorted(three) and three == pick_slices("3", 10, 64)
    views = {p % 40 for p in pick_slices("40", 1600, 64)}  # not a few views: drawn, not strided
    assert len(views) > 20
    assert len(pick_slices("auto", 10**6, 400 * 400)) < 10**6
    for bad, msg in (("0", "out of range"), ("11", "out of range"), ("x", "whole number")):
        with pytest.raises(VrnError, match=msg):
            pick_slices(bad, 10, 64)


@pytest.mark.parametrize("arch", ["coarse_fine", "single"])
def test_a_btf_of_the_packs_own_slices_scores_zero(tmp_path, arch):
    _, mat = _pack(tmp_path, arch=arch)
    btf = read_btf(_own_btf(tmp_path / "own.btf", mat))
    res = score([mat], btf, list(range(16)), ["f32"])
    s = res["scores"][0][0]
    assert s["l1"] < 2e-3 * res["slices"]["btf_mean"]  # only the BTF's float16 rounding
    assert s["psnr_db"] > 50 and s["ssim"] > 0.999
    # the same BTF + 0.05 everywhere: L1 and RMSE are the offset (to float16 rounding)
    btf2 = read_btf(_own_btf(tmp_path / "off.btf", mat, offset=0.05))
    s2 = score([mat], btf2, list(range(16)), ["f32", "f16"])["scores"][0]
    for r in s2:
        assert r["l1"] == pytest.approx(0.05, rel=0.02)
        assert r["rmse"] == pytest.approx(0.05, rel=0.02)
        assert r["l1_held_out"] is None  # no split known
    assert s2[1]["precision"] == "f16"


def test_held_out_split_and_another_btf(tmp_path, capsys):
    own = tmp_path / "own.btf"
    _, mat0 = _pack(tmp_path, name="tmp.vrnm")
    _own_btf(own, mat0, offset=0.01)
    fp = btf_fingerprint(read_btf(own))
    prov = {"provenance": {"btf": fp, "split_seed": 3, "config": {"test_fraction": 0.25}}}
    path, _ = _pack(tmp_path, meta=prov)
    doc = evaluate(EvalConfig(packs=(str(path),)), progress=False)  # the recorded BTF
    s = doc["packs"][0]["scores"][0]
    test = split_pairs(4, 4, 0.25, 3)[1]
    assert s["held_out_slices"] == len(test) == 4
    assert s["l1_held_out"] is not None and s["l1_train"] is not None
    assert (4 * s["l1_held_out"] + 12 * s["l1_train"]) / 16 == pytest.approx(s["l1"])
    assert doc["warnings"] == []
    # another BTF (other values): scored with a warning and without the split
    other = _own_btf(tmp_path / "other.btf", mat0, offset=0.02)
    doc = evaluate(EvalConfig(packs=(str(path),), btf=str(other)), progress=False)
    assert "trained on another BTF" in doc["warnings"][0]
    assert doc["packs"][0]["scores"][0]["l1_held_out"] is None
    assert "trained on another BTF" in capsys.readouterr().err
    # results.md gives them a section (they were bullets under "Worst slices")
    from vrneural.scoring.run import markdown

    md = markdown(doc)
    assert md.index("## Worst slices") < md.index("## Warnings\n\n- ") < md.index("another BTF")


def test_cli_writes_results_and_refuses_to_overwrite(tmp_path, capsys):
    path, mat = _pack(tmp_path)
    path2, _ = _pack(tmp_path, name="other.vrnm", seed=1)
    btf = _own_btf(tmp_path / "own.btf", mat)
    out = tmp_path / "res"
    argv = ["eval", path, path2, "--btf", btf, "-o", out, "--precision", "both", "--no-progress"]
    code, err = run_cli(*argv)
    assert code == 0, err
    text = capsys.readouterr().out
    assert "m.vrnm" in text and "other.vrnm" in text and "f16 (" in text
    doc = json.loads((out / "results.json").read_text())
    assert [p["name"] for p in doc["packs"]] == ["m.vrnm", "other.vrnm"]
    assert doc["packs"][0]["scores"][0]["l1"] < doc["packs"][1]["scores"][0]["l1"]
    assert doc["packs"][0]["macs_per_texel"] == mat.macs_per_texel
    assert (out / "slices.png").stat().st_size > 10_000
    assert "| m.vrnm |" in (out / "results.md").read_text()
    before = (out / "results.json").read_bytes()
    expect_one_line_error(argv, str(out), "--force")
    assert (out / "results.json").read_bytes() == before
    code, err = run_cli(*argv, "--force", "--slices", "2")
    assert code == 0, err
    assert json.loads((out / "results.json").read_text())["slices"]["scored"] == 2
    capsys.readouterr()
    code, _ = run_cli("eval", path, "--btf", btf, "--json", "--no-progress")
    assert code == 0
    assert json.loads(capsys.readouterr().out)["packs"][0]["name"] == "m.vrnm"


def test_cli_errors(tmp_path):
    path, mat = _pack(tmp_path)
    btf = _own_btf(tmp_path / "own.btf", mat)
    expect_one_line_error(["eval", tmp_path / "nope.vrnm", "--btf", btf], "nope.vrnm", "no such")
    expect_one_line_error(["eval", btf, "--btf", btf], "own.btf", "BTF file")
    expect_one_line_error(["eval", path], "m.vrnm", "records no BTF", "--btf")
    expect_one_line_error(["eval", path, path, "--btf", btf], "named twice")
    expect_one_line_error(["eval", path, "--btf", btf, "--slices", "0"], "--slices", "range")
    expect_one_line_error(["eval", path, "--btf", tmp_path / "no.btf"], "no.btf")
    gone = {"btf": {"path": str(tmp_path / "gone.btf"), "sha256": "x"}}
    cmd = "vrneural btf synth --preset wood -o /x --no-progress --force"
    build = {"steps": [{"step": "btf synth", "command": cmd}]}
    p2, _ = _pack(tmp_path, name="g.vrnm", meta={"provenance": gone, "build": build})
    expect_one_line_error(
        ["eval", p2], "gone.btf", "does not exist", "--btf", "btf synth --preset wood -o BTF`"
    )  # the recipe without --force (a pasted command never overwrites) or --no-progress
    cfg = tmp_path / "m.vrnm.config.json"
    cfg.write_text('{"config": "export"}')
    expect_one_line_error(["eval", cfg, "--btf", btf], "JSON file", "not a runtime pack")
    expect_one_line_error(["eval", tmp_path, "--btf", btf], "is a directory", "runtime pack")
    other = {"btf": {"path": str(btf), "sha256": "y"}}
    p3, _ = _pack(tmp_path, name="h.vrnm", meta={"provenance": other})
    expect_one_line_error(["eval", p2, p3], "record different BTFs", "--btf")
    odd = write_btf(
        tmp_path / "odd.btf",
        np.ones((2, 2, 3, 3, 3), np.float32),
        direction_set(2),
        direction_set(2),
        {"name": "odd"},
    )
    expect_one_line_error(["eval", path, "--btf", odd, "--no-progress"], "3x3", "even")


def test_trained_pack_scores_as_its_checkpoint(trained, tmp_path):  # noqa: F811
    """The student pack's held-out L1 is the test L1 torch measured at export (all the held-out
    slices; float16 textures are the only difference)."""
    pack = trained["student"].with_suffix(".vrnm")
    mat = read_vrnm(pack)
    doc = evaluate(EvalConfig(packs=(str(pack),)), progress=False)
    s = doc["packs"][0]["scores"][0]
    assert doc["warnings"] == []
    assert s["held_out_slices"] >= 1
    assert s["l1_held_out"] == pytest.approx(mat.meta["metrics"]["test_l1"], rel=0.01)
    # the trainer's own subset of the held-out slices gives its number (float16 textures are
    # rounded in training too, so the pack is the trained model)
    assert s["l1_trainer_test"] == pytest.approx(mat.meta["metrics"]["test_l1"], rel=1e-4)
    assert doc["packs"][0]["method"] == "student"


def test_eval_needs_no_torch(tmp_path):
    """The pack is readable and scorable with numpy alone: `vrneural eval` never imports torch."""
    import subprocess
    import sys

    path, mat = _pack(tmp_path)
    btf = _own_btf(tmp_path / "own.btf", mat)
    code = (
        "import sys; from vrneural.cli import main; "
        f"rc = main(['eval', {str(path)!r}, '--btf', {str(btf)!r}, '--no-progress']); "
        "assert rc == 0, rc; assert 'torch' not in sys.modules, 'torch imported'"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr


def test_trainer_subset_is_the_trainers():
    """The held-out slices the trainer measures (``--max-test-slices``) are picked as
    :func:`vrneural.distill.evaluate.test_pairs` picks them."""
    ev = pytest.importorskip("vrneural.distill.evaluate")
    for n, m in ((160, 64), (1000, 64), (7, 64), (50, 3), (2265, 64)):
        test = sorted(np.random.default_rng(n).choice(10 * n, n, replace=False).tolist())

        class Mat:
            meta = {"provenance": {"config": {"max_test_slices": m}}}  # noqa: RUF012

        class Data:
            pass

        Data.test = test
        assert trainer_test(Mat, test) == ev.test_pairs(Data, m), (n, m)
    assert trainer_test(Mat, None) is None


def test_labels_tell_packs_apart():
    assert labels(["a/p.vrnm", "b/p.vrnm", "c/q.vrnm"]) == ["a/p.vrnm", "b/p.vrnm", "q.vrnm"]
    assert labels(["x/run/s.vrnm", "y/run/s.vrnm"]) == ["x/run/s.vrnm", "y/run/s.vrnm"]


def test_another_shape_is_named_in_the_warning(tmp_path):
    _, mat0 = _pack(tmp_path, name="tmp.vrnm")
    small = _own_btf(tmp_path / "small.btf", mat0, res=4)
    fp = btf_fingerprint(read_btf(small))
    path, _ = _pack(tmp_path, meta={"provenance": {"btf": fp}})
    big = _own_btf(tmp_path / "big.btf", mat0, res=8)
    doc = evaluate(EvalConfig(packs=(str(path),), btf=str(big)), progress=False)
    assert "shape 4x4x4x4, not 4x4x8x8" in doc["warnings"][0]


def test_ctrl_c_while_writing_keeps_the_old_output(tmp_path, monkeypatch):
    """Everything is computed before the old output is replaced: Ctrl-C in the figure (the
    slow part) leaves the old output whole."""
    import vrneural.scoring.figure as figure

    path, mat = _pack(tmp_path)
    btf = _own_btf(tmp_path / "own.btf", mat)
    out = tmp_path / "res"
    assert evaluate(EvalConfig(packs=(str(path),), btf=str(btf), out=str(out)), progress=False)
    before = {f.name: f.read_bytes() for f in out.iterdir()}

    def stop(*_):
        raise KeyboardInterrupt

    monkeypatch.setattr(figure, "slices_png", stop)
    with pytest.raises(KeyboardInterrupt):
        evaluate(
            EvalConfig(packs=(str(path),), btf=str(btf), out=str(out), force=True, slices="2"),
            progress=False,
        )
    assert {f.name: f.read_bytes() for f in out.iterdir()} == before
