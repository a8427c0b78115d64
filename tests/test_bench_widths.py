"""`vrneural bench widths` end to end at a toy budget (the real sweep is in
docs/quality-research.md)."""

from __future__ import annotations

import json

import pytest
from distill_helpers import run_cli

from vrneural.distill.checkpoint import load_checkpoint

BASE = ["bench", "widths", "--preset", "leather", "--res", 8, "--dirs", 4]
BASE += ["--teacher-epochs", 1, "--epochs", 2, "--repeats", 1, "--no-progress"]


def test_bench_widths_sweep(tmp_path):
    """Every family at every width, its MACs and weights from the trained network, NeuMIP
    as the reference; --resume reuses everything; --jobs 2 trains the same networks."""
    out = tmp_path / "w"
    argv = [*BASE, "--out", out, "--widths", "8,4", "--methods", "student,single8"]
    code, err = run_cli(*argv)
    assert code == 0, err
    doc = json.loads((out / "results.json").read_text())
    rows = doc["rows"]
    fams = [(m, s) for m in ("student", "single8") for s in ("plain", "wide")]
    assert set(rows) == {"neumip"} | {f"{m}:{w}:{s}" for m, s in fams for w in (4, 8)}
    # the trained shapes: the student's M_c 2 layers, M_f one hidden layer; single-level 4 x W
    assert rows["student:8:plain"]["macs_per_texel"] == 202
    assert rows["student:8:wide"]["weight_bytes"] == 1516  # pruned to 8: the 8-wide network
    assert rows["student:4:plain"]["macs_per_texel"] == 81
    assert rows["single8:8:plain"]["macs_per_texel"] == 288
    assert rows["neumip"]["macs_per_texel"] == 1600
    for key, r in rows.items():
        assert r["seeds"] == [0] and len(r["whole_l1_seeds"]) == 1, key
        assert 0 < r["whole_l1"] < 1 and r["whole_l1_sd"] == 0.0, key
    d = out / "leather"
    wide = load_checkpoint(d / "student-w4-from8-s0.wide.pt")
    assert wide["spec"]["fine_hidden"] == [8] and wide["epoch"] == 1
    pruned = load_checkpoint(d / "student-w4-from8-s0.pt")
    assert pruned["init_from"]["path"] == str(d / "student-w4-from8-s0.wide.pt")
    assert pruned["spec"]["fine_hidden"] == [4]
    assert load_checkpoint(d / "student-w4-s0.pt")["init_from"] is None
    assert set(doc["within_10pct"]) == {f"{m}:{s}" for m, s in fams}
    md = (out / "results.md").read_text()
    assert "| student (coarse-to-fine, distilled), wide start (2W, pruned to W) | 4 | 81 |" in md
    assert "Narrowest width within 10% of NeuMIP" in md
    assert (out / "widths.png").read_bytes()[:4] == b"\x89PNG"

    stamp = (d / "student-w8-s0.pt").stat().st_mtime_ns
    code, err = run_cli(*argv, "--resume")
    assert code == 0, err
    assert (d / "student-w8-s0.pt").stat().st_mtime_ns == stamp  # reused, not retrained
    again = json.loads((out / "results.json").read_text())["rows"]
    assert {k: r["whole_l1"] for k, r in again.items()} == {
        k: r["whole_l1"] for k, r in rows.items()
    }
    code, err = run_cli(*argv, "--resume", "--epochs", 4)  # a wide start cannot be extended
    assert code == 2 and err.count("\n") == 1 and "a wide start cannot be extended" in err, err

    par = tmp_path / "j"
    code, err = run_cli(*[par if a == out else a for a in argv], "--jobs", 2)
    assert code == 0, err
    rows_j = json.loads((par / "results.json").read_text())["rows"]
    assert {k: r["whole_l1"] for k, r in rows_j.items()} == {
        k: r["whole_l1"] for k, r in rows.items()
    }


def test_bench_widths_keeps_what_exists(tmp_path):
    out = tmp_path / "w"
    argv = [*BASE, "--out", out, "--widths", 4, "--starts", "plain"]
    code, err = run_cli(*argv)
    assert code == 0, err
    code, err = run_cli(*argv)  # no flag: nothing is overwritten
    assert code == 2 and err.count("\n") == 1 and "--resume" in err and "--force" in err, err
    code, err = run_cli(*BASE, "--out", tmp_path / "none", "--resume")
    assert code == 2 and "nothing to resume" in err, err


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--widths", "0"], "--widths"),
        (["--widths", "4,4"], "lists 4 twice"),
        (["--widths", "40"], "--widths 40 with --starts wide: a wide start trains 2W wide"),
        (["--methods", "neumip"], "--methods"),
        (["--starts", "narrow"], "--starts"),
        (["--epochs", "1"], "--epochs 1 with --starts wide"),
        (["--preset", "velvet"], "--preset"),
        (["--preset", "leather,wood"], "--preset"),
        (["--repeats", "0"], "--repeats = 0 is out of range"),
        (["--resume", "--force"], "contradict"),
    ],
)
def test_bench_widths_checks_every_option_before_any_work(tmp_path, monkeypatch, argv, needle):
    monkeypatch.chdir(tmp_path)
    code, err = run_cli(*BASE, "--out", "w", *argv)
    assert code == 2 and err.count("\n") == 1 and needle in err, err
    assert list(tmp_path.iterdir()) == []


def test_bench_jobs_stop_on_sigterm(tmp_path):
    """`kill` (SIGTERM) of a --jobs run stops it as Ctrl-C does: its workers get SIGINT, save
    and exit with it (none is left behind), exit code 130, and --resume finishes the sweep."""
    import os
    import signal
    import subprocess
    import sys
    import time

    argv = [sys.executable, "-m", "vrneural", *map(str, BASE), "--quick", "--jobs", "2"]
    argv += ["--repeats", "2", "--out", str(tmp_path / "w")]
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, text=True
    )
    assert "teacher" in proc.stdout.readline()
    assert "leather: " in proc.stdout.readline()  # a network done: both workers are up
    kids = f"/proc/{proc.pid}/task/{proc.pid}/children"
    workers = [int(p) for p in open(kids).read().split()]
    assert len(workers) >= 2  # the two workers (and the pool's resource tracker)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "interrupted" in err and "--resume" in err, err
    deadline = time.monotonic() + 10
    while any(os.path.exists(f"/proc/{w}") for w in workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    alive = [w for w in workers if os.path.exists(f"/proc/{w}")]
    assert not alive, f"workers left running: {alive}"
    done = subprocess.run([*argv, "--resume"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "w" / "results.json").is_file()


def test_bench_widths_one_sweep_per_out(tmp_path):
    """--resume in another preset's OUT would replace its report: refused; --force may."""
    out = tmp_path / "w"
    argv = [*BASE, "--out", out, "--widths", 4, "--starts", "plain"]
    code, err = run_cli(*argv)
    assert code == 0, err
    doc = json.loads((out / "results.json").read_text())
    # the all-black reference: the mean |value| of the BTF, which every row is compared with
    assert 0 < doc["zero_output_l1"] < 1
    other = [a if a != "leather" else "wood" for a in argv]
    code, err = run_cli(*other, "--resume")
    assert code == 2 and "holds the width sweep of preset leather, not wood" in err, err
    assert json.loads((out / "results.json").read_text())["config"]["preset"] == "leather"


def test_sigterm_outside_training_is_a_ctrl_c(tmp_path, capsys):
    """SIGTERM in any phase of a training bench (here: no worker pool, no training loop, as
    in the evaluation and report after the networks) stops it as Ctrl-C does, with the
    --resume hint, and the previous SIGTERM handler comes back afterwards."""
    import os
    import signal
    import time

    from vrneural.bench.quality_train import resume_hint

    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(KeyboardInterrupt) as ei, resume_hint(tmp_path):
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)  # the handler raises at once
    # the hint rides on the interrupt to the command line's one "interrupted" line
    assert "rerun the same command with --resume" in str(ei.value), ei.value
    assert str(tmp_path) in str(ei.value) and capsys.readouterr().err == ""
    assert signal.getsignal(signal.SIGTERM) is before
