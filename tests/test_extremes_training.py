"""Extreme training inputs: all-zero BTF, HDR peaks of 1e4, NaN (rejected), lr floor, 1 epoch."""

import pytest

from vrneural.bench import extremes_training as trn
from vrneural.errors import VrnError


def test_nan_btf_is_rejected_in_one_line():
    with pytest.raises(VrnError, match=r"NaN/Inf entries \(first at .*\[1, 2, 3, 4, 0\]") as e:
        trn.teach("nan")
    assert "\n" not in str(e.value) and "nan.btf" in str(e.value)


def test_nan_btf_is_rejected_by_distill_too(tmp_path):
    from vrneural.distill.data import SliceData

    btf = trn.write_kind(tmp_path / "n.btf", "nan")
    from vrneural.btf.format import read_btf

    with pytest.raises(VrnError, match="NaN/Inf"):
        SliceData(read_btf(btf), [0])


@pytest.mark.parametrize("case", ["case_train_hdr", "case_train_lr_floor", "case_train_one_epoch"])
def test_training_cases(case):
    r = getattr(trn, case)(True)
    assert r["ok"], r


def test_all_zero_btf_trains_finite():
    r = trn.teach("zeros", epochs=3, lr=5e-3)
    assert r["finite"] and r["train_loss"][-1] < r["train_loss"][0]
