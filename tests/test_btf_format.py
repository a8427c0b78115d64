"""The .btf file: round trip, one-slice reads, validation errors, streaming writer + resume."""

import struct

import numpy as np
import pytest

from vrneural.btf import BtfWriter, direction_set, read_btf, write_btf
from vrneural.btf.dirs import UBO_RING_COUNTS, UBO_THETA_DEG
from vrneural.errors import VrnError


def _small(rng, L=3, V=4, H=5, W=6):
    vals = rng.random((L, V, H, W, 3)).astype(np.float32) * 2.0
    return vals, direction_set(L), direction_set(V)


def test_round_trip_and_one_slice(tmp_path, rng):
    vals, ld, vd = _small(rng)
    p = write_btf(tmp_path / "a.btf", vals, ld, vd, {"name": "t", "seed": 7})
    b = read_btf(p)
    assert b.shape == (3, 4, 5, 6) and b.resolution == (5, 6)
    np.testing.assert_array_equal(b.values, vals.astype(np.float16))
    np.testing.assert_allclose(b.light_dirs, ld)
    assert b.meta["name"] == "t" and b.meta["seed"] == 7 and b.meta["convention"] == "cos_inside"
    s = b.slice(2, 1)
    assert s.dtype == np.float32 and s.shape == (5, 6, 3)
    np.testing.assert_array_equal(s, vals[2, 1].astype(np.float16).astype(np.float32))
    assert isinstance(b.values, np.memmap)  # nothing loaded until indexed


def test_values_are_clamped_into_float16(tmp_path, rng):
    vals, ld, vd = _small(rng)
    vals[0, 0, 0, 0] = (-1.0, 1e6, 0.5)
    b = read_btf(write_btf(tmp_path / "c.btf", vals, ld, vd, {}))
    assert list(b.values[0, 0, 0, 0].astype(float)) == [0.0, 65504.0, 0.5]
    vals[0, 0, 0, 0, 0] = np.nan
    with pytest.raises(VrnError, match="NaN"):
        write_btf(tmp_path / "d.btf", vals, ld, vd, {})


def test_bad_magic(tmp_path, rng):
    p = write_btf(tmp_path / "a.btf", *_small(rng), {})
    data = bytearray(p.read_bytes())
    data[:6] = b"NOTBTF"
    p.write_bytes(bytes(data))
    with pytest.raises(VrnError, match="wrong magic"):
        read_btf(p)


def test_bad_version(tmp_path, rng):
    p = write_btf(tmp_path / "a.btf", *_small(rng), {})
    data = bytearray(p.read_bytes())
    data[8:12] = struct.pack("<I", 99)
    p.write_bytes(bytes(data))
    with pytest.raises(VrnError, match="version 99"):
        read_btf(p)


@pytest.mark.parametrize("keep", [4, 100, -10])
def test_truncated(tmp_path, rng, keep):
    p = write_btf(tmp_path / "a.btf", *_small(rng), {})
    data = p.read_bytes()
    p.write_bytes(data[:keep])
    with pytest.raises(VrnError, match="truncated"):
        read_btf(p)


def test_shape_mismatch(tmp_path, rng):
    vals, ld, vd = _small(rng)
    with pytest.raises(VrnError, match="light_dirs has shape"):
        write_btf(tmp_path / "a.btf", vals, ld[:2], vd, {})
    with pytest.raises(VrnError, match="expected \\[L, V, H, W, 3\\]"):
        write_btf(tmp_path / "b.btf", vals[..., :2], ld, vd, {})
    with pytest.raises(VrnError, match="not unit vectors"):
        write_btf(tmp_path / "c.btf", vals, ld * 2, vd, {})


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(VrnError, match="no such file"):
        read_btf(tmp_path / "nope.btf")
    with pytest.raises(VrnError, match="directory"):
        read_btf(tmp_path)


def test_writer_streams_and_resumes(tmp_path, rng):
    vals, ld, vd = _small(rng)
    out = tmp_path / "s.btf"
    w = BtfWriter(out, ld, vd, (5, 6), {"name": "s"})
    w.values[:, 0] = vals[:, 0]
    w.mark_done(0)
    w.values.flush()
    del w  # "interrupted": only the partial file and its done-list exist
    assert not out.exists() and (tmp_path / "s.btf.partial").exists()
    w = BtfWriter(out, ld, vd, (5, 6), {"name": "s"}, resume=True)
    assert w.done == {0}
    for v in range(1, 4):
        w.values[:, v] = vals[:, v]
        w.mark_done(v)
    w.finalize()
    assert not (tmp_path / "s.btf.partial").exists()
    np.testing.assert_array_equal(read_btf(out).values, vals.astype(np.float16))
    # a different header is not resumed, and the interrupted write is not overwritten
    w = BtfWriter(out.with_name("t.btf"), ld, vd, (5, 6), {"name": "s"})
    w.mark_done(0)
    del w
    before = (tmp_path / "t.btf.partial").read_bytes()
    with pytest.raises(VrnError, match="cannot be continued"):
        BtfWriter(out.with_name("t.btf"), ld, vd, (5, 6), {"name": "other"}, resume=True)
    assert (tmp_path / "t.btf.partial").read_bytes() == before
    # without resume it starts over
    w = BtfWriter(out.with_name("t.btf"), ld, vd, (5, 6), {"name": "other"})
    assert w.done == set()


def test_resume_validates_the_list_of_finished_views(tmp_path, rng):
    """The ``.partial.done`` sidecar: a line that is not a view index is a one-line error naming
    the file and line (the file is kept); a repeated index counts once; an unterminated last
    line (a write cut short) is dropped, so the next index cannot run into it."""
    vals, ld, vd = _small(rng)  # 4 views
    out = tmp_path / "s.btf"
    w = BtfWriter(out, ld, vd, (5, 6), {"name": "s"})
    for v in (0, 2):
        w.values[:, v] = vals[:, v]
        w.mark_done(v)
    del w
    done = tmp_path / "s.btf.partial.done"
    for bad, needles in (
        ("x\n", ["line 3:", "'x' is not a view index", "0..3"]),
        ("\n-1\n", ["line 4:", "'-1' is not a view index"]),
        ("1.5\n", ["line 3:", "'1.5' is not a view index"]),
        ("4\n", ["line 3:", "view index 4 is out of range", "has 4 views (0..3)"]),
        ("999\n1\n", ["line 3:", "view index 999 is out of range"]),
    ):
        done.write_text("0\n2\n" + bad)
        with pytest.raises(VrnError) as e:
            BtfWriter(out, ld, vd, (5, 6), {"name": "s"}, resume=True)
        msg = str(e.value)
        assert "\n" not in msg and msg.startswith(f"{done}, line ")
        for n in [*needles, "remove that line", "--force instead of --resume"]:
            assert n in msg, (bad, msg)
        assert done.read_text() == "0\n2\n" + bad  # left as it was
    done.write_text("0\n2\n\n2\n 0 \n3")  # duplicates, a blank line, "3" cut short
    w = BtfWriter(out, ld, vd, (5, 6), {"name": "s"}, resume=True)
    assert w.done == {0, 2}
    assert done.read_text() == "0\n2\n"  # the fragment is gone
    for v in (1, 3):
        w.values[:, v] = vals[:, v]
        w.mark_done(v)
    assert sorted(int(t) for t in done.read_text().split()) == [0, 1, 2, 3]
    w.finalize()
    np.testing.assert_array_equal(read_btf(out).values, vals.astype(np.float16))


def test_direction_sets():
    d = direction_set(151)
    assert d.shape == (151, 3)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1, atol=1e-6)
    theta = np.round(np.degrees(np.arccos(np.clip(d[:, 2], -1, 1))), 3)
    for t, n in zip(UBO_THETA_DEG, UBO_RING_COUNTS, strict=True):
        assert np.sum(np.isclose(theta, t, atol=1e-3)) == n
    q = direction_set(40)
    assert q.shape == (40, 3) and q[:, 2].min() >= np.cos(np.radians(75)) - 1e-6
    with pytest.raises(VrnError):
        direction_set(0)


@pytest.mark.parametrize(
    "shape, shown",
    [
        ((0, 0, 5, 6), "0 lights x 0 views x 5x6 texels"),
        ((3, 4, 0, 6), "3 lights x 4 views x 0x6 texels"),
        ((3, 4, 5, 0), "3 lights x 4 views x 5x0 texels"),
    ],
)
def test_empty_btf_is_refused_by_writers_and_reader(tmp_path, rng, capsys, shape, shown):
    """An empty BTF was written and read; `btf info`/`show` then crashed on a zero-size min."""
    from vrneural.btf.format import BTF_MAGIC, BTF_VERSION
    from vrneural.cli import main
    from vrneural.formats.container import write_container

    L, V, H, W = shape
    vals = np.zeros((L, V, H, W, 3), np.float32)
    ld, vd = direction_set(max(L, 1))[:L], direction_set(max(V, 1))[:V]
    with pytest.raises(VrnError) as e:
        write_btf(tmp_path / "w.btf", vals, ld, vd, {})
    assert str(e.value) == (
        f"{tmp_path / 'w.btf'}: an empty BTF ({shown}); lights, views, height and width must "
        "each be at least 1"
    )
    with pytest.raises(VrnError, match="an empty BTF"):
        BtfWriter(tmp_path / "s.btf", ld, vd, (H, W), {})
    assert list(tmp_path.iterdir()) == []
    # a file written some other way (an older vrneural, a hand-made one)
    arrays = {"values": vals.astype(np.float16), "light_dirs": ld, "view_dirs": vd}
    f = write_container(tmp_path / "e.btf", BTF_MAGIC, BTF_VERSION, {"name": "e"}, arrays)
    with pytest.raises(VrnError, match=f"{f}: an empty BTF \\({shown}\\)"):
        read_btf(f)
    for cmd in (["info", str(f)], ["show", str(f), "-o", str(tmp_path / "s.png")]):
        capsys.readouterr()
        assert main(["btf", *cmd]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and "an empty BTF" in err, err
    assert not (tmp_path / "s.png").exists()


@pytest.mark.parametrize("key", ["partial", "arrays", "file_size", "array_crc32"])
def test_reserved_meta_keys_are_refused(tmp_path, rng, key):
    """`meta={"partial": True}` wrote a complete file that readers refused as unfinished;
    `arrays`/`file_size`/`array_crc32` vanished on read (or broke the container)."""
    vals, ld, vd = _small(rng)
    want = (
        f"{tmp_path / 'a.btf'}: meta key {key!r} is reserved by the BTF format (reserved: "
        "array_crc32, arrays, convention, file_size, partial); store it under another name"
    )
    with pytest.raises(VrnError) as e:
        write_btf(tmp_path / "a.btf", vals, ld, vd, {"name": "t", key: True})
    assert str(e.value) == want
    with pytest.raises(VrnError) as e:
        BtfWriter(tmp_path / "a.btf", ld, vd, (5, 6), {key: 1})
    assert str(e.value) == want
    assert list(tmp_path.iterdir()) == []


def test_meta_cannot_override_the_convention(tmp_path, rng):
    vals, ld, vd = _small(rng)
    with pytest.raises(VrnError) as e:
        write_btf(tmp_path / "a.btf", vals, ld, vd, {"convention": "cos_outside"})
    assert str(e.value) == (
        f"{tmp_path / 'a.btf'}: meta key 'convention' = 'cos_outside' is not allowed: BTF values "
        "are always 'cos_inside' (cos(theta_i) inside); drop the key"
    )
    with pytest.raises(VrnError, match="'convention' = 'cos_outside'"):
        BtfWriter(tmp_path / "a.btf", ld, vd, (5, 6), {"convention": "cos_outside"})
    assert list(tmp_path.iterdir()) == []
    # a read BTF's meta (which holds the convention) can be written again
    b = read_btf(write_btf(tmp_path / "b.btf", vals, ld, vd, {"name": "t"}))
    c = read_btf(write_btf(tmp_path / "c.btf", vals, ld, vd, b.meta))
    assert c.meta == b.meta


def _version(p) -> int:
    with open(p, "rb") as f:
        return struct.unpack("<I", f.read(12)[8:12])[0]


def test_height_field_travels_with_the_data_as_version_2(tmp_path, rng):
    """An optional height field [N, N] (UV units; issue #44's parallax needs it): a file with
    one is version 2, one without stays version 1 byte for byte (old readers refuse the new
    version by name instead of misreading it)."""
    vals, ld, vd = _small(rng)
    h = (rng.random((8, 8)) - 0.5).astype(np.float32) * 0.1
    p1 = write_btf(tmp_path / "v1.btf", vals, ld, vd, {"name": "t"})
    p2 = write_btf(tmp_path / "v2.btf", vals, ld, vd, {"name": "t"}, height=h)
    assert _version(p1) == 1 and _version(p2) == 2
    assert read_btf(p1).height is None
    b = read_btf(p2)
    np.testing.assert_array_equal(b.height, h)
    np.testing.assert_array_equal(b.values, read_btf(p1).values)
    # the streaming writer too, and its resume
    w = BtfWriter(tmp_path / "s.btf", ld, vd, (5, 6), {"name": "s"}, height=h)
    w.values[:, 0] = 1.0
    w.mark_done(0)
    del w
    w = BtfWriter(tmp_path / "s.btf", ld, vd, (5, 6), {"name": "s"}, resume=True, height=h)
    assert w.resumed and w.done == {0}
    w.values[:, 1:] = 2.0
    s = read_btf(w.finalize())
    np.testing.assert_array_equal(s.height, h)
    assert _version(s.path) == 2
    for bad in (np.zeros((4, 5), np.float32), np.full((4, 4), np.nan, np.float32)):
        with pytest.raises(VrnError, match="height"):
            write_btf(tmp_path / "bad.btf", vals, ld, vd, {}, height=bad)
