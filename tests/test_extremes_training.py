"""Extreme training inputs: all-zero BTF, HDR peaks of 1e4, NaN (rejected), lr floor, 1 epoch."""

import pytest
from extremes import training as trn

from vrneural.errors import VrnError


def test_nan_btf_is_rejected_by_distill_too(tmp_path):
    from vrneural.distill.data import SliceData

    btf = trn.write_kind(tmp_path / "n.btf", "nan")
    from vrneural.btf.format import read_btf

    with pytest.raises(VrnError, match="NaN/Inf"):
        SliceData(read_btf(btf), [0])
