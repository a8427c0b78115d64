"""Property tests: any damage to a file gives a clear one-line VrnError or the same data back,
never a crash from inside numpy/json and never silently different arrays."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from vrneural.errors import VrnError
from vrneural.formats.vrnm import read_vrnm, write_vrnm
from vrneural.material import material_forward, random_material


@pytest.fixture(scope="module")
def pack_bytes(tmp_path_factory):
    p = tmp_path_factory.mktemp("pack") / "m.vrnm"
    write_vrnm(p, random_material(5))
    return p.read_bytes()


def _probe(mat):
    d = np.array([[0.0, 0.6, 0.8], [0.6, 0.0, 0.8]], np.float32)
    uv = np.full((2, 4, 2), 0.3, np.float32)
    return material_forward(mat, d, d[::-1].copy(), uv)


@given(pos=st.integers(0, 10**9), value=st.integers(0, 255))
def test_flipped_byte_is_rejected_or_harmless(tmp_path_factory, pack_bytes, pos, value):
    data = bytearray(pack_bytes)
    pos %= len(data)
    data[pos] = value
    p = tmp_path_factory.mktemp("flip") / "m.vrnm"
    p.write_bytes(bytes(data))
    try:
        mat = read_vrnm(p)
    except VrnError as e:
        assert "\n" not in str(e) and str(p) in str(e)
        return
    # Accepted: the byte must have been padding or an unchanged value, so shading is identical.
    ref = read_vrnm_bytes(tmp_path_factory, pack_bytes)
    np.testing.assert_array_equal(_probe(mat), _probe(ref))


@given(cut=st.integers(0, 10**9))
def test_truncation_is_rejected(tmp_path_factory, pack_bytes, cut):
    cut %= len(pack_bytes)
    p = tmp_path_factory.mktemp("cut") / "m.vrnm"
    p.write_bytes(pack_bytes[:cut])
    with pytest.raises(VrnError):
        read_vrnm(p)


def read_vrnm_bytes(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("ref") / "m.vrnm"
    p.write_bytes(data)
    return read_vrnm(p)
