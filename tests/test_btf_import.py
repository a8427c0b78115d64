"""UBO2014 import: a small file written in btf.hh's "!DFMF08FC" layout goes through the real
btf-extractor reader and into our format (skipped only where btf-extractor is not installed)."""

import sys

import numpy as np
import pytest
from btf_helpers import write_dfmf

from vrneural.btf import read_btf
from vrneural.btf.dirs import spherical
from vrneural.btf.ubo2014 import load_extractor, parse_header
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


def _with_angles(tmp_path, rng, name, light_deg=None, view_deg=None):
    """The fixture's file with some light/view angles replaced ({index: (theta, phi)} degrees,
    or radians where given as ``("rad", theta, phi)``)."""
    L, H, W = len(THETA), 3, 4
    vals = rng.uniform(0.05, 2.0, (L, L, H, W, 3)).astype(np.float32)
    ang = np.radians(np.stack([THETA, PHI], 1))
    la, va = ang.copy(), ang.copy()
    for arr, repl in ((la, light_deg or {}), (va, view_deg or {})):
        for i, a in repl.items():
            arr[i] = a[1:] if a[0] == "rad" else np.radians(a)
    src = tmp_path / name
    write_dfmf(src, vals, la.astype(np.float32), va.astype(np.float32))
    return src


def _import(src, out, *extra):
    return main(["btf", "import", str(src), "-o", str(out), "--no-progress", *extra])


@pytest.mark.parametrize(
    "kind, repl, shown",
    [
        ("view", {1: (23.5, 120.0)}, "theta 23.50 deg, phi 120.00 deg"),  # == view 2
        ("view", {1: (23.53, 120.02)}, "theta 23.53 deg, phi 120.02 deg"),  # < 0.1 deg apart
        ("light", {1: (23.5, 480.0)}, "theta 23.50 deg, phi 480.00 deg"),  # phi + 360
        ("light", {0: (0.0, 90.0), 1: (0.0, 0.0)}, "light direction 0 (theta 0.00 deg"),  # pole
    ],
)
def test_parse_header_rejects_directions_btf_extractor_cannot_tell_apart(
    tmp_path, rng, capsys, kind, repl, shown
):
    """Two directions with the same 0.1-degree key in btf-extractor's index: `import` crashed
    with `KeyError: 1`; now the header check names both, before any output exists."""
    args = {"light_deg": repl} if kind == "light" else {"view_deg": repl}
    src = _with_angles(tmp_path, rng, "dup.btf", **args)
    with pytest.raises(VrnError) as e:
        parse_header(src)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(f"{src}: ")
    assert f"{kind} direction " in msg and " and " in msg and "0.1 deg" in msg and shown in msg
    if repl == {1: (23.5, 120.0)}:
        assert "view direction 1 (theta 23.50 deg, phi 120.00 deg) and view direction 2" in msg
    out = tmp_path / "out.btf"
    assert _import(src, out) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "same direction" in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dup.btf"]


@pytest.mark.parametrize(
    "repl, needles",
    [
        ({0: ("rad", np.nan, np.nan)}, ["view direction 0 has a non-finite angle", "nan"]),
        ({2: ("rad", 0.5, np.inf)}, ["view direction 2 has a non-finite angle", "inf"]),
        ({3: ("rad", 3.0, 0.0)}, ["view direction 3 (theta 171.89 deg", "below the horizon"]),
        ({4: (90.5, 10.0)}, ["view direction 4 (theta 90.50 deg", "theta <= 90 deg"]),
        # degrees written where radians belong (857 deg is "below the horizon" too)
        ({1: ("rad", 15.0, 0.0)}, ["view direction 1 has theta 15, not an angle in radians"]),
    ],
)
def test_parse_header_rejects_bad_angles(tmp_path, rng, capsys, repl, needles):
    """A NaN angle crashed `import` inside btf-extractor (leaving OUT.partial); a view below the
    horizon was imported silently. Both are refused before any output file is created."""
    src = _with_angles(tmp_path, rng, "bad.btf", view_deg=repl)
    with pytest.raises(VrnError) as e:
        parse_header(src)
    assert "\n" not in str(e.value) and str(e.value).startswith(f"{src}: ")
    for n in needles:
        assert n in str(e.value), str(e.value)
    assert _import(src, tmp_path / "out.btf") == 2
    assert capsys.readouterr().err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.btf"]


def test_parse_header_accepts_grazing_and_distinct_close_directions(tmp_path, rng):
    """theta = 90 deg (float32 pi/2 has z = -4e-8) is on the horizon, not below it; 0.2 deg
    apart is two directions to btf-extractor."""
    src = _with_angles(tmp_path, rng, "ok.btf", view_deg={5: (90.0, 270.0), 1: (23.5, 120.2)})
    h = parse_header(src)
    assert len(h["view_angles"]) == 6
    if _have_extractor():  # and btf-extractor does tell them apart
        assert _import(src, tmp_path / "out.btf") == 0
        assert read_btf(tmp_path / "out.btf").shape == (6, 6, 3, 4)


@needs_extractor
def test_import_checks_btf_extractor_index_too(tmp_path, rng, monkeypatch, capsys):
    """Should the header check and btf-extractor ever disagree on which directions coincide,
    `import` still refuses in one line instead of a KeyError."""
    import vrneural.btf.ubo2014 as ubo

    src = _with_angles(tmp_path, rng, "dup.btf", view_deg={1: (23.5, 120.0)})
    monkeypatch.setattr(ubo, "_check_directions", lambda *a: None)
    with pytest.raises(VrnError, match="tells apart only 5 of the 6 view directions"):
        ubo.import_ubo(src, tmp_path / "out.btf", progress=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dup.btf"]


@needs_extractor
def test_resume_from_another_source_names_it(tmp_path, rng, capsys, monkeypatch):
    """`import --resume` with another source said only "a different header or size"; now it
    names what differs, as `synth --resume` does, and leaves the partial file alone."""
    from vrneural.btf import ubo2014

    a, _, _ = _fixture(tmp_path, rng)
    b = tmp_path / "other_ubo2014.btf"
    b.write_bytes(a.read_bytes())
    out = tmp_path / "out.btf"

    class StopError(Exception):
        pass

    real = ubo2014.BtfWriter.mark_done

    def stop(self, v):  # an import of `a` interrupted after its first view
        real(self, v)
        raise StopError

    with monkeypatch.context() as m:
        m.setattr(ubo2014.BtfWriter, "mark_done", stop)
        with pytest.raises(StopError):
            ubo2014.import_ubo(a, out, progress=False)
    partial = tmp_path / "out.btf.partial"
    before = partial.read_bytes()
    assert _import(b, out, "--resume") == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and f"{partial}: the interrupted run used other settings" in err
    assert f"source: '{a}' there, '{b}' here" in err and "--force" in err
    assert partial.read_bytes() == before
    assert _import(a, out, "--resume") == 0  # the same source continues it
    assert read_btf(out).shape == (6, 6, 5, 7)


@needs_extractor
def test_bad_values_odd_sizes_and_output_names(tmp_path, rng, capsys):
    """From a user's trial: a source with a NaN left a .partial that the next run called "an
    interrupted run" (and --resume stopped at the same slice again); values clamped to the
    float16 maximum went unmentioned; an odd size imported silently and only eval refused it;
    `-o out.png` wrote a BTF named out.png; a raw UBO2014 file given to a reader got no hint."""
    import struct

    src, _, _ = _fixture(tmp_path, rng)  # 5 x 7 texels
    data = bytearray(src.read_bytes())
    assert _import(src, tmp_path / "o.png") == 2
    assert "o.png: output BTF must end in .btf" in capsys.readouterr().err
    assert not (tmp_path / "o.png").exists()
    data[-4:] = struct.pack("<f", 1e30)  # the last stored float: some texels far above 65504
    (tmp_path / "huge_ubo.btf").write_bytes(data)
    assert _import(tmp_path / "huge_ubo.btf", tmp_path / "h.btf") == 0
    err = capsys.readouterr().err
    assert "values above 65504 (the float16 maximum) to 65504" in err, err
    assert "h.btf: 5x7 texels, odd: packs shade 2x2 blocks" in err
    data[-4:] = struct.pack("<f", float("nan"))
    (tmp_path / "nan_ubo.btf").write_bytes(data)
    assert _import(tmp_path / "nan_ubo.btf", tmp_path / "n.btf") == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "non-finite values at light" in err
    assert "nothing was written (no .partial; n.btf not created)" in err
    assert sorted(p.name for p in tmp_path.glob("n.btf*")) == []
    with pytest.raises(VrnError, match=r"is a UBO2014 BTF .*`vrneural btf import UBO.btf"):
        read_btf(src)
