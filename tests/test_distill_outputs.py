"""Every file teach/distill/export write is checked before any work: inputs are never
overwritten (even with --force), existing config sidecars and packs need --force, --resume
replaces only the files its own run wrote, unwritable directories fail up front."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from distill_helpers import FAST, expect_one_line_error, run_cli, trained  # noqa: F401 (fixture)

from vrneural.distill.checkpoint import load_checkpoint, save_checkpoint
from vrneural.distill.outputs import outputs_of, written_by


def _copy(trained, tmp_path, name):  # noqa: F811
    dst = tmp_path / name
    shutil.copy(trained[name.split(".")[0]], dst)
    return dst


def test_output_equal_to_an_input_is_refused_even_with_force(trained, tmp_path):  # noqa: F811
    t = _copy(trained, tmp_path, "teacher.pt")
    before = t.read_bytes()
    expect_one_line_error(["distill", t, "-o", t, "--force", *FAST], "would overwrite the input")
    btf = tmp_path / "m.pt"  # a BTF that happens to be named like a checkpoint
    shutil.copy(trained["btf"], btf)
    btf_bytes = btf.read_bytes()
    expect_one_line_error(["teach", btf, "-o", btf, "--force", *FAST], "would overwrite the input")
    expect_one_line_error(
        ["distill", t, "--btf", btf, "-o", btf, "--force", *FAST], "overwrite the input"
    )
    s = _copy(trained, tmp_path, "student.pt")
    pack = tmp_path / "s.vrnm"
    shutil.copy(s, pack)  # export's input named .vrnm (-o equal to the input)
    expect_one_line_error(["export", pack, "-o", pack, "--force"], "would overwrite the input")
    assert t.read_bytes() == before and btf.read_bytes() == btf_bytes


def test_the_recorded_btf_is_an_input_too(trained, tmp_path):  # noqa: F811
    t = _copy(trained, tmp_path, "teacher.pt")
    out = tmp_path / "x.pt"
    shutil.copy(trained["btf"], out)
    ck = load_checkpoint(t)
    ck["btf"]["path"] = str(out)  # a teacher whose recorded BTF sits where -o points
    save_checkpoint(t, ck)
    expect_one_line_error(["distill", t, "-o", out, "--force", *FAST], "would overwrite the input")
    assert out.read_bytes() == trained["btf"].read_bytes()


@pytest.mark.parametrize("which", ["pt", "vrnm"])
def test_existing_config_sidecars_need_force(trained, tmp_path, which):  # noqa: F811
    side = tmp_path / f"q.{which}.config.json"
    side.write_text("keep")
    expect_one_line_error(
        ["distill", trained["teacher"], "-o", tmp_path / "q.pt", *FAST], str(side)
    )
    expect_one_line_error(["teach", trained["btf"], "-o", tmp_path / "q.pt", *FAST], "--force")
    assert side.read_text() == "keep" and not (tmp_path / "q.pt").exists()
    if which == "vrnm":
        expect_one_line_error(["export", trained["student"], "-o", tmp_path / "q.vrnm"], "--force")
        assert not (tmp_path / "q.vrnm").exists() and side.read_text() == "keep"


def test_btf_synth_checks_its_config_sidecar(tmp_path):
    side = tmp_path / "s.btf.config.json"
    side.write_text("keep")
    argv = ["btf", "synth", "--res", "4", "--dirs", "3", "--no-progress"]
    expect_one_line_error([*argv, "-o", tmp_path / "s.btf"], str(side), "--force")
    assert side.read_text() == "keep" and not (tmp_path / "s.btf").exists()


def test_resume_never_replaces_files_it_did_not_write(trained, tmp_path):  # noqa: F811
    foo = tmp_path / "foo.pt"
    shutil.copy(trained["teacher"], foo)
    (tmp_path / "foo.vrnm").write_text("precious")
    expect_one_line_error(
        ["teach", trained["btf"], "-o", foo, "--resume", *FAST], "foo.vrnm", "move it"
    )
    (tmp_path / "foo.vrnm").unlink()
    side = tmp_path / "foo.pt.config.json"
    side.write_text(json.dumps({"history": [{"test_l1": 0.5}]}))  # another run's config
    expect_one_line_error(["teach", trained["btf"], "-o", foo, "--resume", *FAST], str(side))
    assert json.loads(side.read_text())["history"] == [{"test_l1": 0.5}]
    # the run's own files (copied with it) are replaced: resuming a finished run works
    for f in outputs_of(str(trained["teacher"]), True)[1:]:
        shutil.copy(f, tmp_path / Path(f).name.replace("teacher", "foo"))
    code, err = run_cli("teach", trained["btf"], "-o", foo, "--resume", *FAST)
    assert code == 0, err


def test_written_by_recognises_the_runs_own_files(trained):  # noqa: F811
    ck = load_checkpoint(trained["student"])
    for f in outputs_of(str(trained["student"]), True)[1:]:
        assert written_by(f, ck), f
    other = load_checkpoint(trained["teacher"])
    assert not written_by(outputs_of(str(trained["student"]), True)[2], other)


def test_resume_and_force_contradict(trained, tmp_path):  # noqa: F811
    s = _copy(trained, tmp_path, "student.pt")
    before = s.read_bytes()
    expect_one_line_error(
        ["distill", trained["teacher"], "-o", s, "--resume", "--force"], "contradict"
    )
    assert s.read_bytes() == before


@pytest.mark.parametrize("cmd", ["teach", "distill", "export", "synth"])
def test_unwritable_output_directory_fails_before_any_work(trained, cmd):  # noqa: F811
    argv = {
        "teach": ["teach", trained["btf"], "-o", "/proc/x.pt", *FAST],
        "distill": ["distill", trained["teacher"], "-o", "/proc/x.pt", *FAST],
        "export": ["export", trained["student"], "-o", "/proc/x.vrnm"],
        "synth": ["btf", "synth", "--res", "4", "--dirs", "3", "-o", "/proc/x.btf"],
    }[cmd]
    expect_one_line_error(argv, "/proc: cannot write here")


def test_failed_checkpoint_write_is_one_line(tmp_path, monkeypatch):
    import torch

    from vrneural.errors import VrnError

    def boom(*a, **k):
        raise RuntimeError("File x cannot be opened.\nmore torch text")

    monkeypatch.setattr(torch, "save", boom)
    with pytest.raises(
        VrnError, match=r"cannot write the checkpoint \(File x cannot be opened"
    ) as e:
        save_checkpoint(tmp_path / "c.pt", {})
    assert "\n" not in str(e.value) and not list(tmp_path.iterdir())


def test_export_warns_about_an_unfinished_run(trained, tmp_path):  # noqa: F811
    ck = load_checkpoint(trained["student"])
    ck.update(finished=False, epoch=1, step=3)
    unf = tmp_path / "unf.pt"
    save_checkpoint(unf, {k: v for k, v in ck.items() if k not in ("format", "version")})
    from vrneural.distill.checkpoint import UnfinishedRunWarning

    with pytest.warns(UnfinishedRunWarning) as rec:
        code, err = run_cli("export", unf, "-o", tmp_path / "u.vrnm")
    assert code == 0, err
    msg = str(rec[0].message)
    assert "unfinished run (1 of 2 epochs done and 3 steps" in msg and "--resume" in msg
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", UnfinishedRunWarning)  # a finished run: no warning
        code, err = run_cli("export", trained["student"], "-o", tmp_path / "f.vrnm")
    assert code == 0, err


def test_missing_recorded_btf_names_the_teacher_and_btf_flag(trained, tmp_path):  # noqa: F811
    t = _copy(trained, tmp_path, "teacher.pt")
    ck = load_checkpoint(t)
    ck["btf"]["path"] = str(tmp_path / "gone" / "m.btf")
    save_checkpoint(t, {k: v for k, v in ck.items() if k not in ("format", "version")})
    out = tmp_path / "s.pt"
    expect_one_line_error(["distill", t, "-o", out, *FAST], "recorded in", str(t), "--btf PATH")
    expect_one_line_error(["export", t, "-o", tmp_path / "t.vrnm"], "recorded in", "--btf PATH")
    assert not out.exists()


def test_a_moved_folder_finds_its_btf_beside_the_checkpoint(trained, tmp_path):  # noqa: F811
    """BTF, teacher and pack copied to a new folder and the old BTF gone: distill, export and
    eval take the BTF of the recorded name beside the checkpoint (or pack), because it is the
    same BTF (fingerprint); another BTF under that name is still an error."""
    import shutil

    from vrneural.btf import read_btf, write_btf

    new = tmp_path / "moved"
    new.mkdir()
    t = _copy(trained, new, "teacher.pt")
    ck = load_checkpoint(t)
    ck["btf"]["path"] = str(tmp_path / "gone" / "m.btf")  # where it was
    save_checkpoint(t, {k: v for k, v in ck.items() if k not in ("format", "version")})
    shutil.copy(trained["btf"], new / "m.btf")
    code, err = run_cli("distill", t, "-o", new / "s.pt", "--epochs", 1, *FAST)
    assert code == 0, err
    assert f"using the same BTF at {new / 'm.btf'}" in err
    code, err = run_cli("export", t, "-o", new / "t.vrnm")
    assert code == 0, err
    code, err = run_cli("eval", new / "t.vrnm", "--slices", 2, "--no-progress", "-o", new / "ev")
    assert code == 0, err
    # another BTF of that name beside it: not taken for the recorded one
    b = read_btf(trained["btf"])
    write_btf(new / "m.btf", np.asarray(b.values) * 2, b.light_dirs, b.view_dirs, b.meta)
    expect_one_line_error(["distill", t, "-o", new / "s2.pt", *FAST], "recorded in", "--btf")


def test_only_rank_zero_reports(monkeypatch, capsys):
    from vrneural.cli.teach import _report
    from vrneural.distill.train import Interrupted

    def stop():
        raise Interrupted("epoch 1 step 2/9")

    monkeypatch.setenv("RANK", "1")
    assert _report(stop, "s.pt") == 130
    assert capsys.readouterr().err == ""
    monkeypatch.setenv("RANK", "0")
    assert _report(stop, "s.pt") == 130
    assert "checkpoint saved to s.pt" in capsys.readouterr().err


def test_a_failed_command_leaves_no_empty_folders_behind(trained, tmp_path):  # noqa: F811
    """Output folders are created when outputs are checked; a command that fails after that
    (here: on a later option, a student given as teacher) takes back the folders it made, and
    never a folder that was already there."""
    mine = tmp_path / "mine"
    mine.mkdir()  # the user's own empty folder: kept
    for argv in (
        ["teach", trained["btf"], "-o", tmp_path / "a" / "b" / "t.pt", "--epochs", 0],
        ["distill", trained["student"], "-o", tmp_path / "c" / "s.pt", *FAST],
        ["teach", trained["btf"], "-o", mine / "d" / "t.pt", "--epochs", 0],
    ):
        code, err = run_cli(*argv)
        assert code == 2, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine"]
    assert list(mine.iterdir()) == []
    code, err = run_cli("export", trained["student"], "-o", tmp_path / "e" / "f" / "x.vrnm")
    assert code == 0, err
    assert (tmp_path / "e" / "f" / "x.vrnm").is_file()  # a success keeps its folders


def test_resuming_a_finished_run_says_there_is_nothing_left_to_train(trained, tmp_path):  # noqa: F811
    s = _copy(trained, tmp_path, "student.pt")
    before = s.read_bytes()
    code, err = run_cli("distill", trained["teacher"], "-o", s, "--resume", "--max-test-slices", 4)
    assert code == 0, err
    assert "already trained for 2 epochs, nothing left to train" in err, err
    assert "slice/s" not in err  # no empty progress bar
    assert s.read_bytes() == before


@pytest.mark.parametrize("name", ["teacher", "student"])
def test_a_finished_run_resumed_writes_only_missing_files(trained, tmp_path, name):  # noqa: F811
    """Nothing trained, so nothing there is rewritten (a pack exported since stays); a
    deleted pack or config comes back."""
    s = _copy(trained, tmp_path, f"{name}.pt")
    files = [tmp_path / f"{name}{x}" for x in (".pt.config.json", ".vrnm", ".vrnm.config.json")]
    argv = ("distill", trained["teacher"]) if name == "student" else ("teach", trained["btf"])
    argv += ("-o", s, "--resume", "--max-test-slices", 4)
    code, err = run_cli(*argv)
    assert code == 0 and all(f.is_file() for f in files), err  # missing: written
    files[2].write_text(files[2].read_text() + "\n")  # edited since: stays
    stamp = {f: (f.read_bytes(), f.stat().st_mtime_ns) for f in files}
    code, err = run_cli(*argv)
    assert code == 0, err
    assert {f: (f.read_bytes(), f.stat().st_mtime_ns) for f in files} == stamp
    files[1].unlink()
    code, err = run_cli(*argv)
    assert code == 0 and files[1].read_bytes() == stamp[files[1]][0], err  # the same pack again
    assert files[0].stat().st_mtime_ns == stamp[files[0]][1]


def test_no_export_beside_an_earlier_pack_warns_that_it_goes_stale(trained, tmp_path):  # noqa: F811
    from vrneural.distill.outputs import StalePackWarning

    t = _copy(trained, tmp_path, "teacher.pt")
    shutil.copy(trained["teacher"].with_suffix(".vrnm"), tmp_path / "teacher.vrnm")
    before = (tmp_path / "teacher.vrnm").read_bytes()
    with pytest.warns(StalePackWarning, match=r"teacher\.vrnm: left as it is \(--no-export\)"):
        code, err = run_cli(
            "teach", trained["btf"], "-o", t, "--force", "--no-export", "--epochs", 1, *FAST
        )
    assert code == 0, err
    assert (tmp_path / "teacher.vrnm").read_bytes() == before  # warned about, never deleted


def test_force_then_ctrl_c_resumes_the_new_run(trained, tmp_path):  # noqa: F811
    """A finished run at -o, retrained with --force and interrupted before it finishes: the
    old run's checkpoint, config and pack are gone as training starts (not taken for the new
    run's), so --resume continues the new run."""
    import signal

    from vrneural.distill.config import DistillConfig
    from vrneural.distill.distill import run_distill
    from vrneural.distill.train import Interrupted

    s = tmp_path / "s.pt"
    args = ["distill", trained["teacher"], "-o", s, "--epochs", 1, *FAST]
    assert run_cli(*args)[0] == 0
    olds = outputs_of(str(s), True)[1:]
    assert all(Path(o).is_file() for o in olds)

    seen = []

    def ctrl_c(epoch, step):
        seen.append(s.exists())
        if step == 2:
            signal.raise_signal(signal.SIGINT)

    kw = dict(teacher=str(trained["teacher"]), progress=False, max_test_slices=4, epochs=2)
    with pytest.raises(Interrupted):
        run_distill(DistillConfig(output=str(s), force=True, seed=3, **kw), on_step=ctrl_c)
    assert seen[0] is False  # the old checkpoint went before the first step: an interrupt
    # before the new run's first save cannot leave it to be resumed as if it were the new one
    assert not any(Path(o).exists() for o in olds)
    code, err = run_cli("distill", trained["teacher"], "-o", s, "--resume", *FAST)
    assert code == 0, err
    ck = load_checkpoint(s)
    assert ck["epoch"] == 2 and ck["config"]["seed"] == 3
    assert all(Path(o).is_file() for o in olds)


def test_a_second_run_on_the_same_output_is_refused_while_the_first_runs(trained, tmp_path):  # noqa: F811
    """Two commands given the same -o at once (the second started before the first wrote
    anything) would overwrite each other's checkpoints: while one holds the output, teach,
    distill and btf synth on it are one-line errors; once it ends, the output is free."""
    import subprocess
    import sys

    out = tmp_path / "race.pt"
    btf_out = tmp_path / "race.btf"
    hold = (
        "import sys; from vrneural.outputs import output_lock\n"
        f"with output_lock({str(out)!r}, {str(btf_out)!r}): "
        "print('held', flush=True); sys.stdin.read()"
    )
    holder = subprocess.Popen(
        [sys.executable, "-c", hold], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    try:
        assert holder.stdout.readline().strip() == "held"
        busy = "another vrneural process is writing this output right now"
        expect_one_line_error(["distill", trained["teacher"], "-o", out, *FAST], busy)
        expect_one_line_error(["teach", trained["btf"], "-o", out, *FAST], busy)
        expect_one_line_error(["btf", "synth", "--res", 8, "--dirs", 4, "-o", btf_out], busy)
        assert not out.exists() and not btf_out.exists()
    finally:
        holder.communicate("", timeout=30)
    code, err = run_cli("distill", trained["teacher"], "-o", out, "--epochs", 1, *FAST)
    assert code == 0, err
    # a released lock leaves no file behind (the holder above, which never released its own,
    # left one, which the run took over and removed)
    import hashlib
    import tempfile

    name = hashlib.sha256(str(out.resolve()).encode()).hexdigest()[:32] + ".lock"
    assert not (Path(tempfile.gettempdir()) / "vrneural-locks" / name).exists()
