"""Bad checkpoints, mismatched BTFs and existing outputs: one line, exit code 2, nothing
existing is overwritten."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch
from distill_helpers import (  # noqa: F401 (fixture)
    FAST,
    analytic_btf,
    expect_one_line_error,
    run_cli,
    trained,
)

from vrneural.distill.checkpoint import load_checkpoint


class Payload:  # pickled inside a .pt: weights_only=True must refuse to rebuild it
    def __reduce__(self):
        return (print, ("arbitrary code ran",))


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
    flipped = tmp_path / "flipped.pt"  # one byte of a weight changed: torch.load would take it
    flipped.write_bytes(_flip_in_largest_entry(trained["teacher"].read_bytes()))
    nan = tmp_path / "nan.pt"  # a valid file with NaN in the Adam moments
    ck = load_checkpoint(trained["teacher"])
    next(iter(ck["optimizer"]["state"].values()))["exp_avg"].view(-1)[0] = float("nan")
    _save_like(ck, nan)
    return {
        "evil": evil,
        "corrupt": corrupt,
        "junk": junk,
        "plain": plain,
        "text": text,
        "short": short,
        "flipped": flipped,
        "nan": nan,
    }


def _flip_in_largest_entry(data: bytes) -> bytes:
    """Change one byte in the middle of the largest tensor entry of a checkpoint's zip."""
    import io
    import zipfile

    with zipfile.ZipFile(io.BytesIO(data)) as z:
        info = max(z.infolist(), key=lambda i: i.compress_size)
    h = info.header_offset  # local header: 30 bytes, then the name and the extra field
    start = h + 30 + int.from_bytes(data[h + 26 : h + 28], "little")
    start += int.from_bytes(data[h + 28 : h + 30], "little")
    at = start + info.compress_size // 2
    return data[:at] + bytes([data[at] ^ 0x40]) + data[at + 1 :]


@pytest.mark.parametrize(
    ("name", "needle"),
    [
        ("missing", "no such checkpoint"),
        ("evil", "arbitrary objects"),
        ("corrupt", "corrupt"),
        ("junk", "corrupt"),
        ("text", "not a PyTorch checkpoint"),
        ("short", "not a PyTorch checkpoint"),
        ("plain", "not a vrneural checkpoint"),
        ("flipped", "fails its CRC-32 check"),
        ("nan", "tensor 'optimizer.state.0.exp_avg' holds NaN or Inf"),
        ("student", "expected a 'teacher'"),
        ("btf", "is a BTF file, expected a checkpoint (.pt); train one with `vrneural teach"),
        ("pack", "is a runtime pack (.vrnm), expected a checkpoint"),
    ],
)
def test_bad_teacher(trained, bad_checkpoints, tmp_path, name, needle):  # noqa: F811
    src = {**bad_checkpoints, "missing": tmp_path / "nope.pt", "student": trained["student"]}
    src["btf"] = trained["btf"]
    src["pack"] = Path(trained["teacher"]).with_suffix(".vrnm")
    out = tmp_path / "out.pt"
    expect_one_line_error(["distill", src[name], "-o", out, *FAST], needle)
    assert not out.exists() and not out.with_suffix(".vrnm").exists()


def test_resume_without_a_checkpoint_says_there_is_nothing_to_resume(trained, tmp_path):  # noqa: F811
    out = tmp_path / "nothere.pt"
    expect_one_line_error(
        ["distill", trained["teacher"], "-o", out, "--resume", *FAST], "nothing to resume"
    )
    assert not out.exists()


def test_evil_checkpoint_never_runs_code(bad_checkpoints, tmp_path, capsys):
    expect_one_line_error(["export", bad_checkpoints["evil"], "-o", tmp_path / "x.vrnm"], "forbids")
    assert "arbitrary code ran" not in capsys.readouterr().out


@pytest.mark.parametrize("change", ["resolution", "name", "content"])
def test_btf_mismatch(trained, tmp_path, change):  # noqa: F811
    kw = {"res": 32, "n_dirs": 5, "seed": 0, "name": "analytic"}
    kw.update(
        {"resolution": {"res": 16}, "name": {"name": "other"}, "content": {"seed": 1}}[change]
    )
    other = analytic_btf(tmp_path / "other.btf", **kw)
    out = tmp_path / "s.pt"
    expect_one_line_error(
        ["distill", trained["teacher"], "--btf", other, "-o", out, *FAST],
        "does not match the teacher",
    )
    assert not out.exists()


def test_existing_output_is_kept(trained, tmp_path):  # noqa: F811
    out = tmp_path / "s.pt"
    out.write_bytes(b"precious")
    expect_one_line_error(["distill", trained["teacher"], "-o", out, *FAST], "--force")
    expect_one_line_error(["teach", trained["btf"], "-o", out, *FAST], "--force")
    assert out.read_bytes() == b"precious"
    pack = tmp_path / "p.vrnm"
    pack.write_bytes(b"precious")
    expect_one_line_error(["export", trained["student"], "-o", pack], "--force")
    assert pack.read_bytes() == b"precious"
    # the pack beside the checkpoint counts as an output too
    out2 = tmp_path / "p.pt"
    expect_one_line_error(["distill", trained["teacher"], "-o", out2, *FAST], "p.vrnm", "--force")
    assert not out2.exists() and pack.read_bytes() == b"precious"


def test_export_refuses_nan(trained, tmp_path):  # noqa: F811
    ck = load_checkpoint(trained["student"])
    key = next(k for k in ck["net"] if k.endswith("weight"))
    ck["net"][key][0, 0] = float("nan")
    bad = tmp_path / "nan.pt"
    torch.save(ck, bad)
    out = tmp_path / "nan.vrnm"
    expect_one_line_error(["export", bad, "-o", out], "NaN")
    assert not out.exists()


def test_bad_values_are_one_line(trained, tmp_path):  # noqa: F811
    expect_one_line_error(
        ["distill", trained["teacher"], "-o", tmp_path / "x.pt", "--epochs", "0"], "--epochs"
    )
    expect_one_line_error(["teach", tmp_path / "none.btf", "-o", tmp_path / "t.pt"], "no such file")
    expect_one_line_error(
        ["teach", trained["btf"], "-o", tmp_path / "t.txt", *FAST], "must end in .pt"
    )
    expect_one_line_error(["export", trained["student"], "-o", tmp_path / "m.txt"], "end in .vrnm")
    expect_one_line_error(["teach", trained["btf"], "-o", "", *FAST], "-o is empty")
    g = tmp_path / "g.pt"  # missing, and the output too: named as missing, not as overwritten
    expect_one_line_error(["distill", trained["teacher"], "-o", g, "--init-from", g], "no such")
    expect_one_line_error(["distill", trained["teacher"], "-o", tmp_path / ".pt"], "a name before")
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
    expect_one_line_error(
        ["distill", trained["teacher"], "-o", out, flag, value], flag, "out of range"
    )
    assert not out.exists()


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (
            ["--method", "neumip", "--no-distill", "--coarse-channels", "4"],
            "--coarse-channels sets",
        ),
        (["--method", "single8", "--fine-channels", "4"], "nothing for --method single8"),
        (["--neumip-dirs", "full"], "--neumip-dirs sets NeuMIP's direction inputs"),
        (["--no-distill", "--sigma", "0.5", "--lambda2", "1"], "--sigma, --lambda2 weigh"),
    ],
)
def test_options_the_method_does_not_use_are_one_line(trained, tmp_path, args, needle):  # noqa: F811
    """They were recorded in the config as if used, and changed nothing."""
    out = tmp_path / "x.pt"
    expect_one_line_error(
        ["distill", trained["teacher"], "-o", out, "--epochs", "1", *args], needle
    )
    assert not out.exists()


def test_a_resume_judges_the_flags_by_the_runs_own_method(trained, tmp_path):  # noqa: F811
    """`--resume` without `--method` continues the checkpoint's method: a NeuMIP run resumed
    with its own `--neumip-dirs` goes on, a single8 run resumed with `--coarse-channels` (its
    stored 8, so a no-op) is refused (both were judged as the default student before)."""
    base = ["distill", trained["teacher"], "--epochs", "1", *FAST]
    nm, s8 = tmp_path / "nm.pt", tmp_path / "s8.pt"
    code, err = run_cli(
        *base, "-o", nm, "--method", "neumip", "--no-distill", "--neumip-dirs", "full"
    )
    assert code == 0, err
    code, err = run_cli(*base, "-o", s8, "--method", "single8")
    assert code == 0, err
    more = ["distill", trained["teacher"], "--epochs", "2", "--resume", *FAST]
    code, err = run_cli(*more, "-o", nm, "--neumip-dirs", "full")
    assert code == 0, err
    expect_one_line_error(
        [*more, "-o", s8, "--coarse-channels", "8"], "nothing for --method single8"
    )


def _save_like(ck: dict, path) -> None:
    from vrneural.distill.checkpoint import save_checkpoint

    save_checkpoint(path, {k: v for k, v in ck.items() if k not in ("format", "version")})


@pytest.mark.parametrize(
    ("change", "needle"),
    [
        ("arch", "spec.arch 'weird' unknown"),
        ("kind", "checkpoint kind 'weird' unknown"),
        ("shape", "has shape [3, 3] in the file, the spec needs"),
    ],
)
def test_export_validates_kind_arch_and_shapes(trained, tmp_path, change, needle):  # noqa: F811
    ck = load_checkpoint(trained["student"])
    if change == "arch":
        ck["spec"]["arch"] = "weird"
    elif change == "kind":
        ck["kind"] = "weird"
    else:
        key = next(k for k in ck["net"] if k.endswith("weight"))
        ck["net"][key] = torch.zeros(3, 3)
    bad = tmp_path / "bad.pt"
    _save_like(ck, bad)
    expect_one_line_error(["export", bad, "-o", tmp_path / "b.vrnm"], str(bad), needle)
    assert not (tmp_path / "b.vrnm").exists()


def test_foreign_pickle_loads_without_torch_warnings(tmp_path, recwarn):
    import pickle

    f = tmp_path / "p.pt"
    f.write_bytes(pickle.dumps({"x": 1}))
    with pytest.raises(Exception, match="torch checkpoint"):
        load_checkpoint(f)
    assert not [w for w in recwarn if "torch" in str(w.filename)], [str(w) for w in recwarn]


def _flip_one_value(btf) -> None:
    """Flip one bit of one value in the middle of a BTF, in place: the header stays as it was."""
    from vrneural.btf.format import read_btf

    values = read_btf(btf).values
    off = values.offset + values.nbytes // 2
    del values
    with open(btf, "r+b") as f:
        f.seek(off)
        b = f.read(1)
        f.seek(off)
        f.write(bytes([b[0] ^ 0x10]))


def test_corrupted_values_do_not_match_the_teacher(trained, tmp_path):  # noqa: F811
    """The header of a BTF does not cover its values; the fingerprint samples them."""
    import shutil

    btf = tmp_path / "m.btf"
    shutil.copy(trained["btf"], btf)
    _flip_one_value(btf)
    out = tmp_path / "s.pt"
    expect_one_line_error(
        ["distill", trained["teacher"], "--btf", btf, "-o", out, *FAST],
        "does not match the teacher",
        "values_sha256",
    )
    assert not out.exists()


def test_teacher_from_before_the_value_hash_still_works(trained, tmp_path):  # noqa: F811
    ck = load_checkpoint(trained["teacher"])
    del ck["btf"]["values_sha256"]
    old = tmp_path / "old.pt"
    _save_like(ck, old)
    code, err = run_cli("distill", old, "-o", tmp_path / "s.pt", "--epochs", 1, *FAST)
    assert code == 0, err


def test_resume_on_other_values_is_an_error_even_when_the_teacher_cannot_tell(trained, tmp_path):  # noqa: F811
    """A teacher from before the value hash matches any BTF with its header; the resumed
    checkpoint's own record still tells that the values changed (a BTF synthesised again on
    another machine differed in its last bits: a run must not continue on other data)."""
    import shutil

    ck = load_checkpoint(trained["teacher"])
    del ck["btf"]["values_sha256"]
    old = tmp_path / "old.pt"
    _save_like(ck, old)
    btf = tmp_path / "m.btf"
    shutil.copy(trained["btf"], btf)
    out = tmp_path / "s.pt"
    code, err = run_cli("distill", old, "--btf", btf, "-o", out, "--epochs", 1, *FAST)
    assert code == 0, err
    _flip_one_value(btf)
    kept = out.read_bytes()
    expect_one_line_error(
        ["distill", old, "--btf", btf, "-o", out, "--resume", "--epochs", 2, *FAST],
        "differs from the one",
        "values_sha256",
        "--btf",
    )
    assert out.read_bytes() == kept


@pytest.mark.parametrize("flag", ["--split-seed", "--test-fraction"])
def test_distill_split_options_other_than_the_teachers_are_errors(trained, tmp_path, flag):  # noqa: F811
    out = tmp_path / "s.pt"
    value = {"--split-seed": "3", "--test-fraction": "0.5"}[flag]
    expect_one_line_error(
        ["distill", trained["teacher"], "-o", out, flag, value, *FAST], flag, "teacher"
    )
    assert not out.exists()
    same = {"--split-seed": "0", "--test-fraction": "0.1"}[flag]  # the teacher's: accepted
    code, err = run_cli("distill", trained["teacher"], "-o", out, flag, same, "--epochs", 1, *FAST)
    assert code == 0, err
    import json

    cfg = json.loads((tmp_path / "s.pt.config.json").read_text())
    assert cfg["split_seed"] == 0 and cfg["test_fraction"] == 0.1


def test_neumip_with_an_explicit_linear_space_is_an_error(trained, tmp_path):  # noqa: F811
    out = tmp_path / "n.pt"
    argv = ["distill", trained["teacher"], "-o", out, "--method", "neumip", *FAST]
    expect_one_line_error([*argv, "--space", "linear"], "--space linear", "neumip")
    assert not out.exists()


@pytest.mark.parametrize(
    ("cmd", "flag", "value"),
    [
        ("teach", "--seed", "-1"),
        ("teach", "--seed", "9223372036854775807"),
        ("teach", "--seed", "99999999999999999999"),
        ("distill", "--seed", "4294967296"),
        ("distill", "--split-seed", "-5"),
        ("synth", "--seed", "4294967296"),
        ("bench", "--seed", "-1"),
    ],
)
def test_seeds_share_one_range(trained, tmp_path, cmd, flag, value):  # noqa: F811
    out = tmp_path / "o.pt"
    argv = {
        "teach": ["teach", trained["btf"], "-o", out, *FAST],
        "distill": ["distill", trained["teacher"], "-o", out, *FAST],
        "synth": ["btf", "synth", "--res", "4", "--dirs", "3", "-o", tmp_path / "o.btf"],
        "bench": ["bench", "quality", "--out", tmp_path / "bq"],
    }[cmd]
    expect_one_line_error([*argv, f"{flag}={value}"], flag, "allowed [0, 4294967295]")
    assert list(tmp_path.iterdir()) == []


def test_non_finite_loss_stops_with_one_line_and_keeps_the_checkpoint(
    trained,  # noqa: F811
    tmp_path,
    monkeypatch,
):
    import json

    from vrneural.distill.core import DistillNet

    out = tmp_path / "t.pt"
    code, err = run_cli("teach", trained["btf"], "-o", out, "--epochs", 1, *FAST)
    assert code == 0, err
    good = out.read_bytes()
    real = DistillNet.forward
    calls = []

    def forward(self, *a):
        loss, parts = real(self, *a)
        calls.append(1)
        return (loss * float("nan") if len(calls) > 3 else loss), parts

    monkeypatch.setattr(DistillNet, "forward", forward)
    expect_one_line_error(
        ["teach", trained["btf"], "-o", out, "--epochs", 2, "--resume", *FAST],
        "training diverged: loss is nan at epoch 2 step 4/",
        "left as it was",
    )
    assert out.read_bytes() == good
    calls.clear()
    fresh = tmp_path / "f.pt"
    expect_one_line_error(
        ["teach", trained["btf"], "-o", fresh, *FAST], "no checkpoint was written"
    )
    assert not fresh.exists()
    json.loads((tmp_path / "t.pt.config.json").read_text())  # finished run's config: valid


def test_config_json_never_holds_bare_nan(tmp_path):
    import json

    from vrneural.config import write_config
    from vrneural.distill.config import TeachConfig

    p = write_config(tmp_path / "t.pt", TeachConfig(), {"history": [{"test_l1": float("nan")}]})
    text = p.read_text()
    assert "NaN" not in text
    assert json.loads(text, parse_constant=lambda c: 1 / 0)["history"] == [{"test_l1": None}]


def test_force_keeps_the_old_run_whole_when_one_file_cannot_be_removed(tmp_path, monkeypatch):
    """`--force` over an old run with one file that cannot go (immutable, or someone else's in
    a sticky folder) was a PermissionError traceback after the checkpoint had been deleted."""
    from vrneural.distill.outputs import clear_outputs
    from vrneural.errors import VrnError

    files = [tmp_path / n for n in ("s.pt", "s.pt.config.json", "s.vrnm", "s.vrnm.config.json")]
    for f in files:
        f.write_text(f.name)
    real = Path.rename

    def rename(self, target):
        if self.name == "s.vrnm":
            raise PermissionError(1, "Operation not permitted")
        return real(self, target)

    monkeypatch.setattr(Path, "rename", rename)
    with pytest.raises(VrnError, match=r"s.vrnm: cannot remove the old output to replace it "
                       r"\(Operation not permitted\); nothing was changed"):  # fmt: skip
        clear_outputs([str(f) for f in files])
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(f.name for f in files)
    assert all(f.read_text() == f.name for f in files)
    monkeypatch.setattr(Path, "rename", real)
    clear_outputs([str(f) for f in files])
    assert list(tmp_path.iterdir()) == []
