"""`vrneural bench quality --btf A.btf[,B.btf]`: the five methods and the teacher on any BTF,
labelled by file name; its one-line errors."""

import json

import numpy as np
import pytest

from vrneural.btf import direction_set, write_btf
from vrneural.cli import main


def _btf(path, res=8, dirs=4, seed=0):
    """A small BTF with structure over texels and directions (not constant)."""
    rng = np.random.default_rng(seed)
    d = direction_set(dirs)
    tex = rng.uniform(0.1, 0.8, (res, res, 3))
    lobe = np.clip(d @ d.T, 0, 1) ** 4  # [L, V]
    vals = tex[None, None] * (0.2 + lobe[..., None, None, None]) * d[:, 2, None, None, None, None]
    return write_btf(path, vals.astype(np.float32), d, d, {"name": path.stem})


def test_bench_quality_on_a_given_btf(tmp_path, capsys):
    f = _btf(tmp_path / "tiny.btf")
    out = tmp_path / "bq"
    argv = ["bench", "quality", "--btf", str(f), "--quick", "--no-progress", "--out", str(out)]
    assert main(argv) == 0
    doc = json.loads((out / "results.json").read_text())
    assert list(doc["results"]) == ["tiny.btf"]  # --btf alone: no preset
    r = doc["results"]["tiny.btf"]
    assert set(r["methods"]) == {
        "teacher", "lafortune", "neumip", "single8", "student_nodistill", "student"
    }  # fmt: skip
    assert r["btf"]["shape"] == [4, 4, 8, 8] and r["btf"]["path"] == str(f.resolve())
    assert all(m["whole_l1"] > 0 for m in r["methods"].values())
    md = (out / "results.md").read_text()
    assert "| method | tiny.btf |" in md and "tiny.btf 8x8 texels, 4 x 4 (light, view)" in md
    assert not (out / "btf").exists()  # nothing synthesised
    assert (out / "tiny.btf" / "teacher.pt").is_file()
    # --resume reuses everything as it is
    assert main([*argv, "--resume"]) == 0
    assert "teacher  reused" in capsys.readouterr().out


def _one_line(capsys, argv):
    capsys.readouterr()
    code = main(argv)
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    return err


@pytest.mark.parametrize(
    "make, needle",
    [
        (lambda d: [str(d / "nope.btf")], "nope.btf: no such file"),
        (lambda d: [str(_btf(d / "a.btf")), str(_btf(d / "sub" / "a.btf"))], "two files called"),
        (lambda d: [str(_btf(d / "odd.btf", res=7))], "7x7 texels, odd"),
        (lambda d: [str((d / "x.txt").write_text("x") and d / "x.txt")], "expected a .btf file"),
        (lambda d: [str(_btf(d / "a.btf"))] * 2, "gives " + "{d}/a.btf twice"),
        # an empty --btf (an unset shell variable) benched the default presets without a word
        (lambda d: [""], "--btf = '' has an empty item"),
        (lambda d: [str(_btf(d / "a.btf")), ""], "has an empty item"),
    ],
)
def test_bad_btf_lists_are_one_line_errors(tmp_path, capsys, make, needle):
    (tmp_path / "sub").mkdir()
    files = make(tmp_path)
    out = tmp_path / "bq"
    argv = ["bench", "quality", "--btf", ",".join(files), "--quick", "--out", str(out)]
    err = _one_line(capsys, argv)
    assert needle.format(d=tmp_path) in err, err
    assert not out.exists()
