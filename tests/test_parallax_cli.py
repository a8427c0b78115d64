"""`teach` / `distill --parallax`: the relief measure's choice, packs that carry the height
field and match torch, and the one-line errors of issue #44."""

import json

import numpy as np
import pytest
from distill_helpers import analytic_btf, expect_one_line_error, run_cli

from vrneural.btf.format import read_btf, write_btf
from vrneural.formats.vrnm import read_vrnm

FAST = ("--no-progress", "--max-test-slices", "4", "--epochs", "1")


def with_height(src, dst, height):
    b = read_btf(src)
    return write_btf(dst, np.asarray(b.values, np.float32), b.light_dirs, b.view_dirs,
                     {"name": "h", "seed": 0}, height)  # fmt: skip


def bumps(n: int, amp: float) -> np.ndarray:
    y, x = np.mgrid[0:n, 0:n] / n
    return (amp * np.sin(2 * np.pi * x) * np.cos(2 * np.pi * y)).astype(np.float32)


@pytest.fixture(scope="module")
def btfs(tmp_path_factory):
    d = tmp_path_factory.mktemp("parallax")
    plain = analytic_btf(d / "plain.btf", res=16, n_dirs=4)
    return {
        "dir": d,
        "plain": plain,
        "relief": with_height(plain, d / "relief.btf", bumps(32, 0.1)),  # 3.2 texels
        "flat": with_height(plain, d / "flat.btf", bumps(32, 0.01)),  # 0.3 texels
        "odd": with_height(plain, d / "odd.btf", bumps(24, 0.1)),
    }


def test_auto_gives_relief_parallax_and_flat_none(btfs):
    d = btfs["dir"]
    t, s = d / "t.pt", d / "s.pt"
    code, err = run_cli("teach", btfs["relief"], "-o", t, *FAST)
    assert code == 0, err
    code, err = run_cli("distill", t, "-o", s, *FAST)
    assert code == 0, err
    for pack in (d / "t.vrnm", d / "s.vrnm"):
        mat = read_vrnm(pack)
        assert mat.parallax == {"kind": "height", "steps": 16, "march": "texel"}
        assert mat.height.shape == (16, 16) and mat.height.dtype == np.float16
        rec = mat.meta["parallax"]
        assert rec["kind"] == "height" and rec["relief_texels"] > 1.0
        assert mat.meta["metrics"]["pack_vs_torch_max_abs"] < 1e-4  # the twins agree
    # a flat field and a BTF without one: off, the same pack as before the option
    code, err = run_cli("teach", btfs["flat"], "-o", d / "f.pt", *FAST)
    assert code == 0, err
    flat = read_vrnm(d / "f.vrnm")
    assert flat.parallax_kind == "off" and flat.height is None
    assert "(flat)" in flat.meta["parallax"]["why"]
    code, err = run_cli("teach", btfs["plain"], "-o", d / "p.pt", *FAST)
    assert code == 0, err
    plain = read_vrnm(d / "p.vrnm")
    assert plain.parallax_kind == "off" and "no height field" in plain.meta["parallax"]["why"]
    assert json.loads((d / "p.pt.config.json").read_text())["parallax"] == "auto"


def test_bad_parallax_input_is_one_line(btfs):
    d = btfs["dir"]
    expect_one_line_error(
        ["teach", btfs["plain"], "-o", d / "e1.pt", "--parallax", "height", *FAST],
        "--parallax height", "plain.btf has no height field",
    )  # fmt: skip
    expect_one_line_error(
        ["teach", btfs["odd"], "-o", d / "e3.pt", *FAST],
        "odd.btf: height", "height field 24x24 does not fit the 16x16 texels",
    )  # fmt: skip
    expect_one_line_error(
        ["teach", btfs["relief"], "-o", d / "e4.pt", "--parallax-steps", "0", *FAST],
        "--parallax-steps = 0", "allowed [1, 64]",
    )  # fmt: skip
    assert not any((d / f"e{i}.pt").exists() for i in range(1, 5))


def test_btf_info_shows_the_relief_and_the_auto_choice(btfs, capsys):
    for name, kind in (("relief", "height"), ("flat", "off")):
        capsys.readouterr()
        code, _ = run_cli("btf", "info", btfs[name])
        assert code == 0
        line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("relief"))
        assert line.endswith(f"distill --parallax auto gives it {kind}"), line
