"""`vrneural btf import DIR`: a BTF given as a folder of images plus a direction table. Image
sets written here with OpenImageIO (EXR, PNG), imported, compared; every bad input a one-line
error (exit 2) that writes nothing; --resume after an interruption."""

import json
from pathlib import Path

import numpy as np
import pytest

from vrneural.btf import read_btf
from vrneural.btf.dirs import spherical
from vrneural.btf.imageset import srgb_to_linear
from vrneural.cli import main

LIGHTS = [(0.0, 0.0), (30.0, 90.0), (75.0, 200.0)]  # (theta, phi) degrees
VIEWS = [(10.0, 0.0), (60.0, 300.0)]
H, W = 4, 6


def _write(path, img):
    import OpenImageIO as oiio  # noqa: N813

    fmt = oiio.UINT8 if str(path).endswith(".png") else oiio.FLOAT
    buf = oiio.ImageBuf(oiio.ImageSpec(img.shape[1], img.shape[0], img.shape[2], fmt))
    buf.set_pixels(oiio.ROI(), np.ascontiguousarray(img, np.float32))
    assert buf.write(str(path)), oiio.geterror()


def _values(seed=0):
    """``[L, V, H, W, 3]`` with R != B and rows != columns (a transpose or BGR shows)."""
    rng = np.random.default_rng(seed)
    v = rng.uniform(0.0, 1.0, (len(LIGHTS), len(VIEWS), H, W, 3)).astype(np.float32)
    v[..., 0] *= 0.5
    return v


def make_set(folder, ext=".exr", table="csv", values=None, vectors=False):
    """Write an image set: one image per (light, view) pair and the direction table."""
    folder.mkdir(parents=True, exist_ok=True)
    values = _values() if values is None else values
    rows = []
    for li, (tl, pl) in enumerate(LIGHTS):
        for vi, (tv, pv) in enumerate(VIEWS):
            name = f"l{li}_v{vi}{ext}"
            _write(folder / name, values[li, vi])
            if vectors:
                wi = spherical(np.radians([tl]), np.radians([pl]))[0].tolist()
                wo = spherical(np.radians([tv]), np.radians([pv]))[0].tolist()
                rows.append({"file": name, "wi": wi, "wo": wo})
            else:
                rows.append(dict(file=name, theta_i=tl, phi_i=pl, theta_v=tv, phi_v=pv))
    if table == "json":
        (folder / "directions.json").write_text(json.dumps({"images": rows}))
    else:
        keys = list(rows[0])
        lines = [",".join(keys)] + [",".join(str(r[k]) for k in keys) for r in rows]
        (folder / "directions.csv").write_text("\n".join(lines) + "\n")
    return values


def _dirs(angles):
    a = np.radians(np.asarray(angles))
    return spherical(a[:, 0], a[:, 1])


@pytest.mark.parametrize("table, vectors", [("csv", False), ("json", True)])
def test_exr_set_round_trip(tmp_path, table, vectors):
    vals = make_set(tmp_path / "set", table=table, vectors=vectors)
    out = tmp_path / "set.btf"
    assert main(["btf", "import", str(tmp_path / "set"), "-o", str(out), "--no-progress"]) == 0
    b = read_btf(out)
    assert b.shape == (3, 2, H, W) and b.meta["name"] == "set"
    np.testing.assert_allclose(b.light_dirs, _dirs(LIGHTS), atol=1e-6)  # as given, in order
    np.testing.assert_allclose(b.view_dirs, _dirs(VIEWS), atol=1e-6)
    np.testing.assert_allclose(np.asarray(b.values, np.float32), vals, rtol=1e-3, atol=1e-4)
    assert b.meta["generator"]["images"] == 6 and b.height is None


def test_png_set_is_linearised_and_says_so(tmp_path, capsys):
    lin = _values(1)
    enc = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * lin ** (1 / 2.4) - 0.055)
    make_set(tmp_path / "png", ext=".png", values=enc)
    out = tmp_path / "png.btf"
    assert main(["btf", "import", str(tmp_path / "png"), "-o", str(out), "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert "6 of the 6 images are 8/16-bit" in err and "linearised" in err
    got = np.asarray(read_btf(out).values, np.float32)
    q = srgb_to_linear(np.round(enc * 255) / 255)  # what 8 bits can hold
    np.testing.assert_allclose(got, q, rtol=2e-3, atol=2e-4)
    assert np.abs(got - lin).max() < 0.02  # and close to the linear values before 8 bits
    raw = tmp_path / "raw.btf"
    argv = ["btf", "import", str(tmp_path / "png"), "-o", str(raw), "--png-linear"]
    assert main([*argv, "--no-progress"]) == 0
    np.testing.assert_allclose(
        np.asarray(read_btf(raw).values, np.float32), np.round(enc * 255) / 255, atol=1e-3
    )


def _err(capsys, argv):
    capsys.readouterr()
    code = main(argv)
    err = capsys.readouterr().err.strip()
    return code, err


def _breakers():
    def csv_edit(old, new):
        def f(d):
            t = d / "directions.csv"
            t.write_text(t.read_text().replace(old, new, 1))

        return f

    def move(name):
        return lambda d: (d / name).rename(d.parent / name)

    def extra(d):
        (d / "stray.exr").write_bytes((d / "l0_v0.exr").read_bytes())

    def small(d):
        _write(d / "l1_v1.exr", np.zeros((H, W - 2, 3), np.float32))

    def garbage(d):
        (d / "l2_v0.exr").write_bytes(b"not an image at all")

    def twice(d):
        t = d / "directions.csv"
        lines = t.read_text().splitlines()
        t.write_text("\n".join([*lines, lines[1]]) + "\n")

    def pair_twice(d):
        t = d / "directions.csv"
        lines = t.read_text().splitlines()
        (d / "again.exr").write_bytes((d / "l0_v0.exr").read_bytes())
        t.write_text("\n".join([*lines, "again.exr" + lines[1][len("l0_v0.exr") :]]) + "\n")

    def no_table(d):
        (d / "directions.csv").unlink()

    def json_field(value):  # one angle of the JSON table set to value
        def f(d):
            (d / "directions.csv").unlink()
            rows = [
                dict(file=f"l{li}_v{vi}.exr", theta_i=tl, phi_i=pl, theta_v=tv, phi_v=pv)
                for li, (tl, pl) in enumerate(LIGHTS)
                for vi, (tv, pv) in enumerate(VIEWS)
            ]
            rows[2]["theta_v"] = value
            (d / "directions.json").write_text(json.dumps(rows))

        return f

    return {
        "missing image": (move("l1_v0.exr"), ["l1_v0.exr", "missing image", "line 4"]),
        "extra image": (extra, ["1 image(s)", "stray.exr", "does not name"]),
        "size": (small, ["l1_v1.exr", "4x4 pixels", "6x4", "same size"]),
        "unreadable": (garbage, ["l2_v0.exr", "cannot read it as an image"]),
        "theta range": (csv_edit(",30.0,90.0,", ",95.0,90.0,"), ["theta_i = 95", "horizon"]),
        "negative theta": (csv_edit(",30.0,90.0,", ",-5,90.0,"), ["theta_i = -5", "[0, 90]"]),
        "phi range": (csv_edit(",30.0,90.0,", ",30.0,400,"), ["phi_i = 400", "[-360, 360]"]),
        "nan": (csv_edit(",30.0,90.0,", ",nan,90.0,"), ["theta_i = 'nan'", "finite"]),
        "not a number": (csv_edit(",30.0,90.0,", ",x,90.0,"), ["theta_i = 'x'", "not a number"]),
        "file twice": (twice, ["both name l0_v0.exr"]),
        "pair twice": (pair_twice, ["same (light, view) pair", "again.exr"]),
        "no table": (no_table, ["no direction table", "--table"]),
        # a new user's finds: a traceback, blame on the wrong line, true taken as 1 degree
        "extra field": (
            csv_edit(",30.0,90.0,10.0,0.0\n", ",30.0,90.0,10.0,0.0,7\n"),
            ["line 4", "1 more field than the header's 5 columns ('7')"],
        ),
        "header": (
            csv_edit("file,theta_i,phi_i,theta_v,phi_v", "file,ti,pi,tv,pv"),
            ["line 1", "the columns are file, ti, pi, tv, pv", "must be file, theta_i"],
        ),
        "empty cell": (
            csv_edit(",30.0,90.0,10.0,0.0\n", ",30.0,,10.0,0.0\n"),
            ["no value for phi_i"],
        ),
        "json true": (json_field(True), ["image 3", "theta_v = True is not a number"]),
        "json null": (json_field(None), ["image 3", "no value for theta_v"]),
        "json text": (json_field("ten"), ["image 3", "theta_v = 'ten' is not a number"]),
        "pair missing": (
            lambda d: (
                move("l2_v1.exr")(d),
                csv_edit("l2_v1.exr,75.0,200.0,60.0,300.0\n", "")(d),
            ),
            ["1 of the 3 x 2 (light, view) pairs have no image", "light 2", "view 1"],
        ),
    }


@pytest.mark.parametrize("case", list(_breakers()))
def test_bad_image_sets_are_one_line_errors_and_write_nothing(tmp_path, capsys, case):
    d = tmp_path / "set"
    make_set(d)
    brk, needles = _breakers()[case]
    brk(d)
    out = tmp_path / "out.btf"
    code, err = _err(capsys, ["btf", "import", str(d), "-o", str(out), "--no-progress"])
    assert code == 2 and len(err.splitlines()) == 1, err
    assert all(n in err for n in needles), err
    assert not out.exists() and not (tmp_path / "out.btf.partial").exists()


def test_table_is_looked_up_from_the_working_folder_then_the_image_folder(
    tmp_path, capsys, monkeypatch
):
    d = tmp_path / "set"
    make_set(d)
    (d / "directions.csv").rename(d / "dirs.csv")
    monkeypatch.chdir(tmp_path)
    args = ["btf", "import", "set", "--no-progress", "--table"]
    code, err = _err(capsys, [*args, "dirs.csv", "-o", "a.btf"])  # found in the folder
    assert code == 0 and (tmp_path / "a.btf").exists(), err
    code, err = _err(capsys, [*args, "set/dirs.csv", "-o", "b.btf"])  # from the working folder
    assert code == 0 and (tmp_path / "b.btf").exists(), err
    code, err = _err(capsys, [*args, "nosuch.csv", "-o", "c.btf"])  # both places are named
    assert code == 2 and len(err.splitlines()) == 1, err
    assert "neither nosuch.csv" in err and f"nor {Path('set') / 'nosuch.csv'}" in err, err
    assert not (tmp_path / "c.btf").exists()


def test_vectors_below_the_horizon_and_not_unit(tmp_path, capsys):
    d = tmp_path / "set"
    make_set(d, table="json", vectors=True)
    doc = json.loads((d / "directions.json").read_text())
    doc["images"][2]["wo"] = [0.6, 0.0, -0.8]
    (d / "directions.json").write_text(json.dumps(doc))
    code, err = _err(capsys, ["btf", "import", str(d), "-o", str(tmp_path / "o.btf")])
    assert code == 2 and "image 3: wo" in err and "below the horizon" in err, err
    doc["images"][2]["wo"] = [0.6, 0.0, 0.9]
    (d / "directions.json").write_text(json.dumps(doc))
    code, err = _err(capsys, ["btf", "import", str(d), "-o", str(tmp_path / "o.btf")])
    assert code == 2 and "is not a unit vector" in err, err


def test_nan_pixels_stop_the_import_and_leave_nothing(tmp_path, capsys):
    vals = _values()
    vals[1, 1, 2, 3, 1] = np.nan
    make_set(tmp_path / "set", values=vals)
    out = tmp_path / "o.btf"
    code, err = _err(capsys, ["btf", "import", str(tmp_path / "set"), "-o", str(out)])
    assert code == 2 and "l1_v1.exr: 1 non-finite values" in err.splitlines()[-1], err
    assert not out.exists() and not (tmp_path / "o.btf.partial").exists()
    assert "nothing was written (no .partial; o.btf not created)" in err, err
    out.write_bytes(b"an earlier import")  # --force: it is kept, and the line says so
    code, err = _err(capsys, ["btf", "import", str(tmp_path / "set"), "-o", str(out), "--force"])
    assert code == 2 and "(no .partial; o.btf left as it was)" in err, err
    assert out.read_bytes() == b"an earlier import"


def test_existing_output_kept_and_interrupted_import_resumes(tmp_path, capsys, monkeypatch):
    from vrneural.btf import imageset

    vals = make_set(tmp_path / "set")
    out = tmp_path / "o.btf"
    out.write_bytes(b"precious")
    code, err = _err(capsys, ["btf", "import", str(tmp_path / "set"), "-o", str(out)])
    assert code == 2 and "--force" in err and out.read_bytes() == b"precious"
    out.unlink()
    real, calls = imageset.read_rgb, {"n": 0}

    def stop_in_second_view(*a, **k):
        calls["n"] += 1
        if calls["n"] > 4:
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(imageset, "read_rgb", stop_in_second_view)
    assert main(["btf", "import", str(tmp_path / "set"), "-o", str(out), "--no-progress"]) == 130
    assert (tmp_path / "o.btf.partial").exists() and not out.exists()
    monkeypatch.setattr(imageset, "read_rgb", real)
    code, err = _err(capsys, ["btf", "import", str(tmp_path / "set"), "-o", str(out)])
    assert code == 2 and "--resume" in err  # never thrown away silently
    argv = ["btf", "import", str(tmp_path / "set"), "-o", str(out), "--resume", "--no-progress"]
    assert main(argv) == 0
    np.testing.assert_allclose(np.asarray(read_btf(out).values, np.float32), vals, rtol=1e-3)
    code, err = _err(
        capsys, ["btf", "import", str(out), "-o", str(tmp_path / "x.btf"), "--table", "t.csv"]
    )
    assert code == 2 and "--table is for a folder of images" in err


def _square_set(folder):
    """An image set of 4x4 texels (a height field needs square texels)."""
    return make_set(folder, values=_values()[:, :, :, :4])


def test_a_measured_height_field_travels_into_the_btf(tmp_path):
    """``--height`` (a one-channel EXR in the folder, or a .npy outside it) with
    ``--height-scale``: stored mean-free in UV units, resampled to a multiple of the texels
    where it is not one, recorded in the header; ``distill --parallax auto`` can then see the
    relief (docs/parallax.md)."""
    from vrneural.parallax import height_at_texels

    d = tmp_path / "set"
    _square_set(d)
    rng = np.random.default_rng(3)
    h = rng.uniform(0.0, 2.0, (8, 8, 1)).astype(np.float32)  # e.g. millimetres
    _write(d / "height.exr", h)  # in the folder, without a row in the table
    out = tmp_path / "a.btf"
    argv = ["btf", "import", str(d), "-o", str(out), "--no-progress", "--height"]
    assert main([*argv, str(d / "height.exr"), "--height-scale", "0.05"]) == 0
    b = read_btf(out)
    np.testing.assert_allclose(b.height, (h[..., 0] - h.mean()) * 0.05, atol=1e-6)
    rec = b.meta["generator"]["height"]
    assert (
        rec["scale"] == 0.05 and rec["source"].endswith("height.exr") and len(rec["sha256"]) == 64
    )
    assert height_at_texels(b.height, b.resolution).shape == (4, 4)
    (d / "height.exr").unlink()  # without --height naming it, an image without a row again
    np.save(tmp_path / "h6.npy", rng.normal(size=(6, 6)))  # 6 is not a multiple of 4: 8
    assert main([*argv, str(tmp_path / "h6.npy"), "-o", str(tmp_path / "b.btf")]) == 0
    b6 = read_btf(tmp_path / "b.btf")
    assert b6.height.shape == (8, 8) and abs(float(b6.height.mean())) < 0.05


@pytest.mark.parametrize(
    "make, extra, needles",
    [
        (lambda p: np.save(p, np.zeros((4, 6))), [], ["height field 4x6", "square"]),
        (lambda p: np.save(p, np.full((4, 4), np.nan)), [], ["16 NaN/Inf"]),
        (lambda p: np.save(p, np.zeros((4, 4))), ["--height-scale", "0"], ["--height-scale = 0.0"]),
        (lambda p: None, [], ["does not exist"]),
        (lambda p: p.write_text("not an array"), [], ["cannot read it as a .npy array"]),
    ],
)
def test_bad_height_fields_are_one_line_errors(tmp_path, capsys, make, extra, needles):
    d = tmp_path / "set"
    _square_set(d)
    hp = tmp_path / "h.npy"
    make(hp)
    out = tmp_path / "o.btf"
    code, err = _err(capsys, ["btf", "import", str(d), "-o", str(out), "--height", str(hp), *extra])
    assert code == 2 and len(err.splitlines()) == 1 and all(n in err for n in needles), err
    assert not out.exists()


def test_a_height_field_needs_square_texels(tmp_path, capsys):
    make_set(tmp_path / "set")  # 4x6 texels
    np.save(tmp_path / "h.npy", np.zeros((8, 8)))
    argv = ["btf", "import", str(tmp_path / "set"), "-o", str(tmp_path / "o.btf"), "--height"]
    code, err = _err(capsys, [*argv, str(tmp_path / "h.npy")])
    assert code == 2 and "texels are 4x6; a height field needs square texels" in err, err
