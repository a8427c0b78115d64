"""`bench quality --parallax height`: the parallax variants on a tiny BTF with a height field,
L1 by view-angle bins for every method, and the one-line errors before any work."""

import json

import numpy as np
from test_bench_quality_btf import _btf, _one_line

from vrneural.btf.format import read_btf, write_btf
from vrneural.cli import main


def _with_height(src, dst):
    b = read_btf(src)
    y, x = np.mgrid[0:16, 0:16] / 16
    h = (0.2 * np.sin(2 * np.pi * x) * np.cos(2 * np.pi * y)).astype(np.float32)
    return write_btf(dst, np.asarray(b.values, np.float32), b.light_dirs, b.view_dirs,
                     {"name": dst.stem}, h)  # fmt: skip


def test_parallax_variants_and_view_bins(tmp_path):
    f = _with_height(_btf(tmp_path / "flat.btf"), tmp_path / "bumpy.btf")
    out = tmp_path / "bq"
    argv = ["bench", "quality", "--btf", str(f), "--parallax", "height", "--quick",
            "--no-progress", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    doc = json.loads((out / "results.json").read_text())
    r = doc["results"]["bumpy.btf"]
    assert {"teacher_parallax", "student_parallax", "neumip_parallax"} <= set(r["methods"])
    assert r["view_bins"] == [[0, 30], [30, 50], [50, 65], [65, 76]]
    for name, m in r["methods"].items():
        assert len(m["view_bins_l1"]) == 4, name
        par = name.endswith("_parallax")
        if name != "lafortune":
            assert m["parallax"]["kind"] == ("height" if par else "off"), name
            assert (m["fetches_per_texel"] > 50) == par  # the march's loads
    # the variants read their own teacher; the plain networks train without parallax
    ck = json.loads((out / "bumpy.btf" / "student_parallax.pt.config.json").read_text())
    assert ck["teacher"].endswith("teacher_parallax.pt") and ck["parallax"] == "height"
    ck = json.loads((out / "bumpy.btf" / "student.pt.config.json").read_text())
    assert ck["parallax"] == "off"
    md = (out / "results.md").read_text()
    assert "## L1 by view angle" in md and "| 65-76 deg |" in md
    assert "Ours (distilled) + height parallax / Ours (coarse-to-fine, distilled)" in md
    assert (out / "view_bins.png").stat().st_size > 1000


def test_parallax_needs_height_fields(tmp_path, capsys):
    f = _btf(tmp_path / "v1.btf")
    out = tmp_path / "bq"
    base = ["bench", "quality", "--parallax", "height", "--quick", "--out", str(out)]
    err = _one_line(capsys, [*base, "--btf", str(f)])
    assert "--parallax height: --btf" in err and "v1.btf has no height field" in err
    err = _one_line(capsys, [*base, "--presets", "leather"])
    assert "synthetic presets (leather) carry no height field" in err
    assert not out.exists()


def test_neural_offset_variants_need_no_height_field(tmp_path):
    f = _btf(tmp_path / "plain.btf", res=16)  # no height field: NeuMIP's module needs none
    out = tmp_path / "bq"
    argv = ["bench", "quality", "--btf", str(f), "--parallax", "neural", "--quick",
            "--no-progress", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    r = json.loads((out / "results.json").read_text())["results"]["plain.btf"]
    assert {"teacher_neural", "student_neural", "neumip_neural"} <= set(r["methods"])
    assert not {"teacher_parallax", "neumip_parallax"} & set(r["methods"])
    for name, m in r["methods"].items():
        if name != "lafortune":
            assert m["parallax"]["kind"] == ("neural" if name.endswith("_neural") else "off")
    neu, plain = r["methods"]["neumip_neural"], r["methods"]["neumip"]
    assert neu["macs_per_texel"] > plain["macs_per_texel"]  # the offset MLP's share
    assert neu["fetches_per_texel"] == plain["fetches_per_texel"] + 4  # the offset texture
    ck = json.loads((out / "plain.btf" / "student_neural.pt.config.json").read_text())
    assert ck["teacher"].endswith("teacher_neural.pt") and ck["parallax"] == "neural"
    md = (out / "results.md").read_text()
    assert "| NeuMIP with offset (4x25) / NeuMIP (4x25) |" in md
    assert "Against NeuMIP with offset (4x25)" in md
    assert "| Ours (distilled) + neural offset | " in md.split("Against NeuMIP with offset")[1]
