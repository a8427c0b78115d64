"""UBO2014 import: a small file written in btf.hh's "!DFMF08FC" layout goes through the real
btf-extractor reader and into our format (skipped only where btf-extractor is not installed)."""

import sys

import numpy as np
import pytest

from vrneural.btf import read_btf
from vrneural.btf.dirs import spherical
from vrneural.btf.ubo2014 import load_extractor, parse_header, write_dfmf
from vrneural.cli import main
from vrneural.errors import VrnError

THETA = [0.0, 11.0, 23.5, 45.0, 60.0, 75.0]
PHI = [0.0, 60.0, 120.0, 90.0, 180.0, 270.0]


def _have_extractor():
    try:
        load_extractor()
        return True
    except VrnError:
        return False


needs_extractor = pytest.mark.skipif(not _have_extractor(), reason="btf-extractor not installed")


def _fixture(tmp_path, rng):
    L, H, W = len(THETA), 5, 7  # H != W: catches transposed or flipped images
    vals = rng.uniform(0.05, 2.0, (L, L, H, W, 3)).astype(np.float32)
    vals[..., 0] *= 0.25  # R << B: catches a missing BGR -> RGB swap
    ang = np.radians(np.stack([THETA, PHI], 1)).astype(np.float32)
    src = tmp_path / "tiny_ubo2014.btf"
    write_dfmf(src, vals, ang, ang)
    return src, vals, ang


def test_parse_header_of_written_file(tmp_path, rng):
    src, _, ang = _fixture(tmp_path, rng)
    h = parse_header(src)
    assert h["format"] == "DFMF" and (h["width"], h["height"]) == (7, 5)
    np.testing.assert_allclose(h["light_angles"], ang)


def test_parse_header_rejects_bad_files(tmp_path, rng):
    src, _, _ = _fixture(tmp_path, rng)
    data = src.read_bytes()
    (tmp_path / "t.btf").write_bytes(data[:-4])
    with pytest.raises(VrnError, match="data ends at byte"):
        parse_header(tmp_path / "t.btf")
    (tmp_path / "h.btf").write_bytes(data[:200])
    with pytest.raises(VrnError, match="truncated"):
        parse_header(tmp_path / "h.btf")
    (tmp_path / "m.btf").write_bytes(b"!XXXX" + data[5:])
    with pytest.raises(VrnError, match="not a UBO2014"):
        parse_header(tmp_path / "m.btf")


def test_missing_extractor_is_a_one_line_install_hint(monkeypatch):
    monkeypatch.setitem(sys.modules, "btf_extractor", None)  # import -> ImportError
    monkeypatch.setitem(sys.modules, "ubo2014_cy", None)
    with pytest.raises(VrnError, match="pip install") as e:
        load_extractor()
    assert "\n" not in str(e.value)


@needs_extractor
def test_import_end_to_end_through_btf_extractor(tmp_path, rng, capsys):
    src, vals, ang = _fixture(tmp_path, rng)
    out = tmp_path / "imported.btf"
    assert main(["btf", "import", str(src), "-o", str(out), "--no-progress"]) == 0
    b = read_btf(out)
    assert b.shape == (6, 6, 5, 7)
    want = spherical(ang[:, 0].astype(float), ang[:, 1].astype(float))
    # btf-extractor rounds angles to 0.1 degree (1.7e-3 rad)
    np.testing.assert_allclose(b.light_dirs, want, atol=2e-3)
    np.testing.assert_allclose(b.view_dirs, want, atol=2e-3)
    # float32 SVD reconstruction then float16 storage: ~1e-3 relative
    np.testing.assert_allclose(np.asarray(b.values, np.float32), vals, rtol=3e-3, atol=1e-3)
    assert b.meta["generator"]["tool"].startswith("btf-extractor")
    # existing output without --force: one-line error, file untouched
    before = out.read_bytes()
    assert main(["btf", "import", str(src), "-o", str(out), "--no-progress"]) == 2
    assert "exists" in capsys.readouterr().err and out.read_bytes() == before
