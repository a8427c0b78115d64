"""Bad checkpoints, mismatched BTFs and existing outputs: one line, exit code 2, nothing
existing is overwritten."""

from __future__ import annotations

import pytest
import torch
from distill_helpers import FAST, analytic_btf, run_cli, trained  # noqa: F401 (fixture)

from vrneural.distill.checkpoint import load_checkpoint


class Payload:  # pickled inside a .pt: weights_only=True must refuse to rebuild it
    def __reduce__(self):
        return (print, ("arbitrary code ran",))


def _expect_error(argv, *needles):
    code, err = run_cli(*argv)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    for n in needles:
        assert n in lines[0], lines[0]


@pytest.fixture
def bad_checkpoints(tmp_path, trained):  # noqa: F811
    evil = tmp_path / "evil.pt"
    torch.save({"format": "vrneural-checkpoint", "x": Payload()}, evil)
    corrupt = tmp_path / "corrupt.pt"
    corrupt.write_bytes(trained["teacher"].read_bytes()[:5000])
    junk = tmp_path / "junk.pt"
    junk.write_bytes(b"not a checkpoint at all")
    plain = tmp_path / "plain.pt"
    torch.save({"weights": torch.zeros(3)}, plain)
    text = tmp_path / "text.pt"  # the unpickler fails with KeyError on these two
    text.write_text("hello world\n")
    short = tmp_path / "short.pt"  # ... and with IndexError on this one
    short.write_text("abc")
    return {
        "evil": evil,
        "corrupt": corrupt,
        "junk": junk,
        "plain": plain,
        "text": text,
        "short": short,
    }


@pytest.mark.parametrize(
    ("name", "needle"),
    [
        ("missing", "no such checkpoint"),
        ("evil", "arbitrary objects"),
        ("corrupt", "corrupt"),
        ("junk", "corrupt"),
        ("text", "corrupt or not a torch checkpoint (KeyError"),
        ("short", "corrupt or not a torch checkpoint (IndexError"),
        ("plain", "not a vrneural checkpoint"),
        ("student", "expected a 'teacher'"),
    ],
)
def test_bad_teacher(trained, bad_checkpoints, tmp_path, name, needle):  # noqa: F811
    src = {**bad_checkpoints, "missing": tmp_path / "nope.pt", "student": trained["student"]}
    out = tmp_path / "out.pt"
    _expect_error(["distill", src[name], "-o", out, *FAST], needle)
    assert not out.exists() and not out.with_suffix(".vrnm").exists()


def test_evil_checkpoint_never_runs_code(bad_checkpoints, tmp_path, capsys):
    _expect_error(["export", bad_checkpoints["evil"], "-o", tmp_path / "x.vrnm"], "forbids")
    assert "arbitrary code ran" not in capsys.readouterr().out


@pytest.mark.parametrize("change", ["resolution", "name", "content"])
def test_btf_mismatch(trained, tmp_path, change):  # noqa: F811
    kw = {"res": 32, "n_dirs": 5, "seed": 0, "name": "analytic"}
    kw.update(
        {"resolution": {"res": 16}, "name": {"name": "other"}, "content": {"seed": 1}}[change]
    )
    other = analytic_btf(tmp_path / "other.btf", **kw)
    out = tmp_path / "s.pt"
    _expect_error(
        ["distill", trained["teacher"], "--btf", other, "-o", out, *FAST],
        "does not match the teacher",
    )
    assert not out.exists()


def test_existing_output_is_kept(trained, tmp_path):  # noqa: F811
    out = tmp_path / "s.pt"
    out.write_bytes(b"precious")
    _expect_error(["distill", trained["teacher"], "-o", out, *FAST], "--force")
    _expect_error(["teach", trained["btf"], "-o", out, *FAST], "--force")
    assert out.read_bytes() == b"precious"
    pack = tmp_path / "p.vrnm"
    pack.write_bytes(b"precious")
    _expect_error(["export", trained["student"], "-o", pack], "--force")
    assert pack.read_bytes() == b"precious"
    # the pack beside the checkpoint counts as an output too
    out2 = tmp_path / "p.pt"
    _expect_error(["distill", trained["teacher"], "-o", out2, *FAST], "p.vrnm", "--force")
    assert not out2.exists() and pack.read_bytes() == b"precious"


def test_export_refuses_nan(trained, tmp_path):  # noqa: F811
    ck = load_checkpoint(trained["student"])
    key = next(k for k in ck["net"] if k.endswith("weight"))
    ck["net"][key][0, 0] = float("nan")
    bad = tmp_path / "nan.pt"
    torch.save(ck, bad)
    out = tmp_path / "nan.vrnm"
    _expect_error(["export", bad, "-o", out], "NaN")
    assert not out.exists()


def test_bad_values_are_one_line(trained, tmp_path):  # noqa: F811
    _expect_error(
        ["distill", trained["teacher"], "-o", tmp_path / "x.pt", "--epochs", "0"], "--epochs"
    )
    _expect_error(["teach", tmp_path / "none.btf", "-o", tmp_path / "t.pt"], "no such file")
    _expect_error(["teach", trained["btf"], "-o", tmp_path / "t.txt", *FAST], "must end in .pt")
    _expect_error(["export", trained["student"], "-o", tmp_path / "m.txt"], "end in .vrnm")
    assert not (tmp_path / "t.vrnm").exists() and not (tmp_path / "m.txt").exists()


@pytest.mark.parametrize(
    ("flag", "value"),
    [
        ("--coarse-channels", "0"),
        ("--fine-channels", "0"),
        ("--tex-lr-scale", "-1"),
        ("--lr-min", "1"),
        ("--lr-patience", "-1"),
        ("--max-test-slices", "-1"),
        ("--threads", "0"),
        ("--test-fraction", "0"),
    ],
)
def test_bad_training_options_are_one_line(trained, tmp_path, flag, value):  # noqa: F811
    out = tmp_path / "x.pt"
    _expect_error(["distill", trained["teacher"], "-o", out, flag, value], flag, "out of range")
    assert not out.exists()
