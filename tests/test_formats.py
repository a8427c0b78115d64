"""The array container: round trips and clear errors on bad files (outputs: test_outputs)."""

import numpy as np
import pytest

from vrneural.errors import VrnError
from vrneural.formats import ContainerWriter, read_container, write_container

MAGIC = b"VRNTEST"


def _write(tmp_path, rng):
    arrays = {
        "a": rng.standard_normal((3, 5)).astype(np.float32),
        "b": (rng.random(17) * 10).astype(np.float16),
        "empty": np.zeros((0, 4), np.uint32),
    }
    p = write_container(tmp_path / "x.bin", MAGIC, 3, {"name": "t"}, arrays)
    return p, arrays


def test_round_trip(tmp_path, rng):
    p, arrays = _write(tmp_path, rng)
    header, got, version = read_container(p, MAGIC, (3,))
    assert version == 3 and header["name"] == "t"
    for k, v in arrays.items():
        np.testing.assert_array_equal(got[k], v)
        assert got[k].dtype == v.dtype
    for a in header["arrays"].values():
        assert a["offset"] % 64 == 0


@pytest.mark.parametrize(
    ("damage", "message"),
    [
        (lambda b: b"XXXXXXXX" + b[8:], "wrong magic"),
        (lambda b: b[:8] + (9).to_bytes(4, "little") + b[12:], "version 9 is not supported"),
        (lambda b: b[:-10], "truncated"),
        (lambda b: b[:10], "truncated"),
        (lambda b: b[:40] + b"#" + b[41:], "corrupt header"),
        (lambda b: b[:-70] + bytes([b[-70] ^ 0xFF]) + b[-69:], "checksum"),
    ],
    ids=["magic", "version", "truncated-data", "truncated-prefix", "header", "data"],
)
def test_damaged_files_give_clear_errors(tmp_path, rng, damage, message):
    p, _ = _write(tmp_path, rng)
    p.write_bytes(damage(p.read_bytes()))
    with pytest.raises(VrnError, match=message) as e:
        read_container(p, MAGIC, (3,))
    assert str(p) in str(e.value) and "\n" not in str(e.value)


def test_missing_file(tmp_path):
    with pytest.raises(VrnError, match="no such file"):
        read_container(tmp_path / "nope", MAGIC, (1,))


def test_streaming_writer_resume(tmp_path):
    specs = {"v": ((4, 8), "float16")}
    w = ContainerWriter(tmp_path / "s.bin", MAGIC, 1, {"k": 1}, specs)
    w.array("v")[0] = 1.0
    w.array("v").flush()
    assert not (tmp_path / "s.bin").exists()  # nothing visible before finalize
    w2 = ContainerWriter(tmp_path / "s.bin", MAGIC, 1, {"k": 1}, specs, resume=True)
    assert w2.resumed
    w2.array("v")[1:] = 2.0
    w2.finalize()
    _, got, _ = read_container(tmp_path / "s.bin", MAGIC, (1,))
    assert got["v"][0, 0] == 1.0 and got["v"][3, 7] == 2.0
    w3 = ContainerWriter(tmp_path / "t.bin", MAGIC, 1, {"k": 2}, specs, resume=True)
    assert not w3.resumed  # nothing to resume: a fresh write
    before = w3.partial.read_bytes()
    with pytest.raises(VrnError, match="cannot be continued"):  # another header: kept
        ContainerWriter(tmp_path / "t.bin", MAGIC, 1, {"k": 3}, specs, resume=True)
    assert w3.partial.read_bytes() == before
