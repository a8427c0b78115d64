"""`vrneural bench quality` end to end at a toy budget (the real budget is in README)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from distill_helpers import expect_one_line_error, run_cli

from vrneural.distill.checkpoint import load_checkpoint


def test_bench_quality_smoke(tmp_path, capsys):
    out = tmp_path / "q"
    args = [
        "bench",
        "quality",
        "--presets",
        "leather",
        "--out",
        out,
        "--res",
        8,
        "--dirs",
        4,
        "--teacher-epochs",
        1,
        "--epochs",
        1,
        "--lafortune-iters",
        2,
        "--no-progress",
    ]
    code, err = run_cli(*args)
    assert code == 0, err
    doc = json.loads((out / "results.json").read_text())
    methods = doc["results"]["leather"]["methods"]
    assert set(methods) == {
        "teacher",
        "lafortune",
        "neumip",
        "single8",
        "student_nodistill",
        "student",
    }
    for m in methods.values():
        assert 0 < m["whole_l1"] < 10 and m["storage_bytes"] > 0
    assert methods["student"]["weight_bytes"] == 1516
    assert all(methods[k]["epoch_seconds_median"] > 0 for k in methods if k != "lafortune")
    assert doc["versions"]["torch"] and doc["config"]["res"] == 8
    md = (out / "results.md").read_text()
    assert "| leather |" in md and "1.5x below Lafortune" in md
    # PSNR / SSIM as `vrneural eval` defines them: the same numbers from the exported pack
    for k, m in methods.items():
        if k != "lafortune":
            assert 0 < m["ssim"] <= 1 and np.isfinite(m["psnr_db"]), k
    assert "PSNR and SSIM of the BTF slices" in md
    # a run stopped after its first material says so above the tables, not only in the JSON
    from vrneural.bench.quality_report import markdown

    assert doc["complete"] and doc["materials"] == ["leather"] and "Partial run" not in md
    part = markdown({**doc, "complete": False, "materials": ["leather", "wood"]})
    assert "**Partial run**: 1 of 2 materials finished (not yet: wood)" in part
    assert "`--resume` finishes it" in part and "| leather |" in part
    from vrneural.scoring.config import EvalConfig
    from vrneural.scoring.run import evaluate

    pack = out / "leather" / "student.vrnm"
    ev = evaluate(EvalConfig(packs=(str(pack),), btf=str(out / "btf" / "leather.btf")), False)
    row = ev["packs"][0]["scores"][0]
    assert row["psnr_db"] == pytest.approx(methods["student"]["psnr_db"], abs=1e-3)
    assert row["ssim"] == pytest.approx(methods["student"]["ssim"], abs=1e-4)
    assert row["l1"] == pytest.approx(methods["student"]["whole_l1"], rel=1e-4)
    for png in ("curves.png", "slices.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, err = run_cli(*args)  # results exist: refuse without --force
    assert code == 2 and "--force" in err
    capsys.readouterr()
    code, err = run_cli(*args, "--resume")  # every checkpoint matches: nothing is retrained
    assert code == 0, err
    log = capsys.readouterr().out
    assert "leather: teacher  reused" in log and "leather: student  reused" in log, log
    assert "leather: lafortune  reused" in log, log
    again = json.loads((out / "results.json").read_text())["results"]["leather"]["methods"]
    for name, m in methods.items():
        for key in ("whole_l1", "train_seconds", "epochs"):
            assert again[name][key] == m[key], (name, key)
    i = args.index("--epochs")
    longer = [*args[: i + 1], 2, *args[i + 2 :]]
    code, err = run_cli(*longer, "--resume")  # students continue to 2 epochs, teacher reused
    assert code == 0, err
    more = json.loads((out / "results.json").read_text())["results"]["leather"]["methods"]
    assert more["teacher"]["train_seconds"] == methods["teacher"]["train_seconds"]
    for name in ("neumip", "single8", "student_nodistill", "student"):
        assert (
            more[name]["epochs"] == 2
            and more[name]["train_seconds"] > methods[name]["train_seconds"]
        )
        assert len(more[name]["curve"]) == 2 and more[name]["curve"][0] == methods[name]["curve"][0]
    code, err = run_cli(*longer, "--resume", "--repeats", 2)  # seed 0 reused, seed 1 trained
    assert code == 0, err
    two = json.loads((out / "results.json").read_text())["results"]["leather"]["methods"]
    for name in ("neumip", "single8", "student_nodistill", "student"):
        r = two[name]
        assert (
            r["seeds"] == [0, 1]
            and len(r["curves"]) == 2
            and (out / "leather" / f"{name}.seed1.pt").exists()
        )
        assert r["whole_l1_seeds"][0] == more[name]["whole_l1"]  # the seed-0 network, reused
        assert r["whole_l1_seeds"][1] != r["whole_l1_seeds"][0]
        assert r["whole_l1"] == pytest.approx(sum(r["whole_l1_seeds"]) / 2)
    assert two["teacher"]["whole_l1_seeds"] == [more["teacher"]["whole_l1"]]
    assert "seeds 0-1" in (out / "results.md").read_text()
    j = args.index(out)
    extra = ("--ema", 0.9, "--lr-patience", 7)
    code, err = run_cli(*args[:j], tmp_path / "e", *args[j + 1 :], *extra)
    assert code == 0, err
    from vrneural.distill.checkpoint import load_checkpoint

    for name in ("neumip", "single8", "student_nodistill", "student"):
        ck = load_checkpoint(tmp_path / "e" / "leather" / f"{name}.pt")
        assert ck["config"]["ema"] == 0.9 and ck["ema"]["count"] > 0
        assert ck["config"]["lr_patience"] == 7
    tck = load_checkpoint(tmp_path / "e" / "leather" / "teacher.pt")
    assert tck["config"]["ema"] == 0.0 and tck["config"]["lr_patience"] == 2
    md = (tmp_path / "e" / "results.md").read_text()
    assert "weight averaging (--ema 0.9)" in md and "lr patience 7 epochs" in md


def _digests(root):
    import hashlib

    return {
        f.relative_to(root): hashlib.sha256(f.read_bytes()).hexdigest()
        for f in sorted(root.rglob("*"))
        if f.suffix in (".pt", ".btf", ".json") and f.name != "results.json"
    }


def test_bench_quality_resume_never_trains_over_a_checkpoint_it_cannot_reuse(tmp_path):
    """`--resume` once retrained, silently and over the user's files, every checkpoint it
    could not reuse: an older release's BTF header made it retrain six 48-epoch teachers and
    every network. Now each such checkpoint is a one-line error that names why, and nothing
    is written."""
    out = tmp_path / "q"
    args = ["bench", "quality", "--presets", "leather", "--out", out, "--res", 8, "--dirs", 4]
    args += ["--teacher-epochs", 1, "--epochs", 2, "--lafortune-iters", 2, "--no-progress"]
    expect_one_line_error([*args, "--resume"], "--resume: nothing to resume", "does not exist")
    assert not out.exists()
    code, err = run_cli(*args)
    assert code == 0, err
    before = _digests(out)
    i = args.index("--epochs")
    fewer = [*args[: i + 1], 1, *args[i + 2 :]]
    expect_one_line_error([*fewer, "--resume"], "neumip.pt", "2 epochs, more than the 1")
    expect_one_line_error([*args, "--resume", "--ema", 0.9], "neumip.pt", "ema 0.0 there, 0.9")
    assert _digests(out) == before
    stamp = out / "btf" / "leather.btf.synth.json"
    good = stamp.read_text()
    stamp.write_text(good.replace('"spp": 4', '"spp": 9'))  # synthesised by other settings
    expect_one_line_error([*args, "--resume"], "leather.btf", "cannot reuse this BTF", '"spp": 9')
    stamp.write_text(good)
    assert _digests(out) == before
    student = out / "leather" / "student.pt"
    kept = student.read_bytes()
    student.write_bytes(b"not a checkpoint")
    expect_one_line_error([*args, "--resume"], "student.pt", "corrupt or not a torch checkpoint")
    assert student.read_bytes() == b"not a checkpoint"
    student.write_bytes(kept)
    # a longer teacher is a new teacher: it is continued, then its students are refused
    j = args.index("--teacher-epochs")
    longer = [*args[: j + 1], 2, *args[j + 2 :]]
    expect_one_line_error([*longer, "--resume"], "neumip.pt", "another teacher", "move it away")
    after, teacher = _digests(out), (out / "leather" / "teacher.pt").relative_to(out)
    assert after[teacher] != before[teacher]  # the continued teacher (and its sidecars)

    def others(d):
        return {k: v for k, v in d.items() if not k.name.startswith("teacher.")}

    assert others(after) == others(before)  # and nothing else
    code, err = run_cli(*longer, "--force")  # --force retrains every network
    assert code == 0, err


def _rec(*seeds):
    return {"whole_l1": sum(seeds) / len(seeds), "whole_l1_seeds": list(seeds)}


def test_quality_targets_use_seed_means_and_flag_overlapping_ranges():
    from vrneural.bench.quality_report import decided, markdown, targets

    m = {
        "neumip": _rec(1.0, 1.1),
        "single8": _rec(1.2, 1.3),
        "student_nodistill": _rec(1.05, 1.5),
        "lafortune": _rec(2.0),
        "student": _rec(1.0, 1.2),  # mean 1.1
    }
    t, sure = targets(m), decided(m)
    assert t == {
        "within 10% of NeuMIP": True,  # 1.1 <= 1.1 * 1.05
        "below single-level 8-wide": True,  # 1.1 < 1.25
        "below no-distillation": True,  # 1.1 < 1.275
        "1.5x below Lafortune": True,  # 1.65 <= 2.0
    }
    assert sure == {
        "within 10% of NeuMIP": False,  # [1.0, 1.2] / 1.1 overlaps [1.0, 1.1]
        "below single-level 8-wide": False,  # [1.0, 1.2] overlaps [1.2, 1.3]
        "below no-distillation": False,  # [1.0, 1.2] overlaps [1.05, 1.5]
        "1.5x below Lafortune": True,  # 1.5 * 1.2 = 1.8 < 2.0 for every seed
    }
    m["student"] = _rec(1.4, 1.6)  # now clearly worse than single8, by every seed
    assert targets(m)["below single-level 8-wide"] is False
    assert decided(m)["below single-level 8-wide"] is True
    for r in m.values():
        r |= {
            "texture_bytes": 1,
            "weight_bytes": 1,
            "macs_per_texel": None,
            "test_l1": 1.0,
            "train_seconds": 1.0,
        }
    doc = {
        "results": {"leather": {"methods": m}},
        "config": {
            "res": 8,
            "dirs": 4,
            "teacher_epochs": 1,
            "epochs": 1,
            "lafortune_iters": 2,
            "seed": 3,
            "repeats": 2,
        },
        "labels": {k: k for k in m},
        "total_seconds": 1.0,
    }
    md = markdown(doc)
    assert "seeds 3-4" in md and "1.50000 (1.40000-1.60000)" in md
    # below no-distillation: 1.5 vs 1.275, overlapping; relative and absolute gap
    assert "**no** (+17.6%, +0.22500) *(seeds overlap)*" in md
    assert "**no** (-25.0%, -0.50000) |" in md  # 1.5x below Lafortune: 1.5 * 1.5 > 2.0
    assert "| leather | 0 of 2 | 0 of 2 |" in md  # pairs: 1.4, 1.6 vs 1.2, 1.3 and 1.05, 1.5


def test_seed_pairs_and_the_seed_picked_by_test_l1():
    from vrneural.bench.quality_report import picked, seed_pairs

    m = {
        "neumip": _rec(1.0, 1.2) | {"test_l1_seeds": [2.0, 1.0]},  # picks seed 1 by test L1
        "single8": _rec(1.3, 1.1) | {"test_l1_seeds": [1.0, 2.0]},
        "student_nodistill": _rec(1.4, 1.0) | {"test_l1_seeds": [1.0, 1.0]},  # a tie: the first
        "lafortune": _rec(2.0) | {"test_l1": 3.0},  # one fit, no seeds
        "student": _rec(1.2, 1.15) | {"test_l1_seeds": [3.0, 1.0]},
    }
    # seed 0: 1.2 < 1.3 and < 1.4; seed 1: 1.15 > 1.1 and > 1.0
    assert seed_pairs(m) == {"single8": (1, 2), "student_nodistill": (1, 2)}
    assert {k: v["whole_l1"] for k, v in picked(m).items()} == {
        "neumip": 1.2,
        "single8": 1.3,
        "student_nodistill": 1.4,
        "lafortune": 2.0,
        "student": 1.15,
    }


def test_bench_quality_jobs_equals_sequential(tmp_path):
    """``--jobs 2`` trains in worker processes (spawned) and gives the sequential table: on the
    CPU every network is bit-identical, so every L1 matches exactly."""
    args = ["bench", "quality", "--presets", "leather,wood", "--res", 8, "--dirs", 4]
    args += ["--teacher-epochs", 1, "--epochs", 1, "--lafortune-iters", 2, "--no-progress"]
    docs = []
    for jobs in (1, 2):
        out = tmp_path / f"j{jobs}"
        code, err = run_cli(*args, "--out", out, "--jobs", jobs)
        assert code == 0, err
        docs.append(json.loads((out / "results.json").read_text())["results"])
    for preset in ("leather", "wood"):
        seq, par = docs[0][preset]["methods"], docs[1][preset]["methods"]
        assert set(seq) == set(par)
        for name in seq:
            assert par[name]["whole_l1"] == seq[name]["whole_l1"], (preset, name)
            assert par[name]["curve"] == seq[name]["curve"], (preset, name)


def test_bench_quality_never_writes_into_a_folder_of_the_users_files(tmp_path):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "a.txt").write_text("keep")
    args = ["bench", "quality", "--presets", "leather", "--res", 8, "--dirs", 4, "--out", mine]
    for flag in ((), ("--force",), ("--resume",)):  # no flag helps, and none is suggested
        code, err = run_cli(*args, *flag)
        assert code == 2 and "not a vrneural output directory" in err, err
        assert "--resume" not in err and "--force" not in err, err
    assert sorted(p.name for p in mine.iterdir()) == ["a.txt"]


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--ema", "1"], "--ema = 1.0 is out of range"),
        (["--lr-patience", "-1"], "--lr-patience = -1 is out of range"),
        (["--out", ""], "--out is empty"),
        (["--dirs", "0"], "--dirs = 0 is out of range; allowed [2, 100000]"),
        (["--dirs", "1"], "--dirs = 1 is out of range; allowed [2, 100000]"),
        (["--presets", "leather,leather"], "--presets names leather more than once"),
        (["--resume", "--force"], "contradict"),
        (["--device", "tpu"], "--device 'tpu'"),
        (["--width", "0"], "--width = 0 is out of range; allowed [1, 64]"),
        (
            ["--width", "12", "--wide-start", "12"],
            "--wide-start 12: 0 (off) or a width in [13, 64]",
        ),
        (
            ["--wide-start", "8"],
            "--wide-start 8: 0 (off) or a width in [9, 64], wider than --width 8",
        ),
    ],
)
def test_bench_quality_checks_every_option_before_any_work(tmp_path, monkeypatch, argv, needle):
    monkeypatch.chdir(tmp_path)
    out = ["--out", "q"] if "--out" not in argv else []
    code, err = run_cli("bench", "quality", "--res", 8, "--dirs", 4, *out, *argv, "--no-progress")
    assert code == 2 and err.count("\n") == 1 and needle in err, err
    assert list(tmp_path.iterdir()) == []


def test_bench_quality_wide_start(tmp_path):
    """--wide-start 16: each 8-wide network (single8, both students) is pruned from its own
    16-wide run of the first half of the epochs and reported as one run of all the epochs;
    NeuMIP trains as before; --resume reuses all of it and refuses a plain run's checkpoint."""
    out = tmp_path / "q"
    base = ["bench", "quality", "--presets", "leather", "--out", out, "--res", 8, "--dirs", 4]
    base += ["--teacher-epochs", 1, "--epochs", 3, "--lafortune-iters", 1, "--no-progress"]
    code, err = run_cli(*base, "--wide-start", 16)
    assert code == 0, err
    d = out / "leather"
    methods = json.loads((out / "results.json").read_text())["results"]["leather"]["methods"]
    assert "neumip" in methods and not any("wide" in k for k in methods)
    for name in ("single8", "student_nodistill", "student"):
        wide, ck = load_checkpoint(d / f"{name}.wide.pt"), load_checkpoint(d / f"{name}.pt")
        assert (
            wide["epoch"] == 1
            and max(wide["spec"].get("hidden") or wide["spec"]["fine_hidden"]) == 16
        )
        assert ck["epoch"] == 2 and ck["init_from"]["path"] == str(d / f"{name}.wide.pt")
        assert methods[name]["epochs"] == 3 and len(methods[name]["curve"]) == 3
        assert methods[name]["wide_start"] == {"width": 16, "epochs": 1}
        assert ck["config"]["distill"] == wide["config"]["distill"]
    assert load_checkpoint(d / "neumip.pt")["init_from"] is None
    assert methods["neumip"]["wide_start"] is None
    assert methods["student"]["weight_bytes"] == 1516  # the runtime network is 8 wide
    assert "pruned to 8 wide (--wide-start)" in (out / "results.md").read_text()
    # the bench schedules the two halves itself; `distill --wide-start` on its teacher, with
    # the bench's settings, must train the same student (the README's recipe relies on it)
    one = tmp_path / "one.pt"
    fast = ["--max-test-slices", 0, "--threads", 1, "--no-progress", "--no-export"]
    code, err = run_cli(
        "distill", d / "teacher.pt", "-o", one, "--wide-start", 16, "--epochs", 3, *fast
    )
    assert code == 0, err
    got, want = load_checkpoint(one), load_checkpoint(d / "student.pt")

    def curve(ck):  # the wall-clock seconds of each epoch differ
        return [{k: v for k, v in h.items() if k != "seconds"} for h in ck["history"]]

    assert curve(got) == curve(want) and got["net"].keys() == want["net"].keys()
    for k, v in want["net"].items():
        assert np.array_equal(got["net"][k].numpy(), v.numpy()), k
    stamp = (d / "student.pt").stat().st_mtime_ns
    code, err = run_cli(*base, "--wide-start", 16, "--resume")
    assert code == 0, err
    assert (d / "student.pt").stat().st_mtime_ns == stamp  # reused, not retrained
    code, err = run_cli(*base, "--resume")  # plain networks asked: the pruned ones do not do
    assert code == 2 and "pruned from a wide start there, from random weights here" in err, err
    code, err = run_cli(*base, "--wide-start", 16, "--epochs", 1, "--force")
    assert code == 2 and "--wide-start" in err and "at least 2" in err, err
    # more epochs cannot extend a wide start (the pruned networks would start again): one
    # line before any work
    code, err = run_cli(*base, "--wide-start", 16, "--epochs", 4, "--resume")
    assert code == 2 and "a wide start cannot be extended" in err, err
    assert (d / "student.pt").stat().st_mtime_ns == stamp
    # a moved OUT resumes in place, reading the wide runs where they are now
    moved = tmp_path / "moved"
    out.rename(moved)
    code, err = run_cli(*[moved if a == out else a for a in base], "--wide-start", 16, "--resume")
    # no "--epochs N with N > 1 continues it" for the halves (no option sets their epochs)
    assert code == 0 and "wide.pt: already" not in err and "student.pt: already" not in err, err
    assert "neumip.pt: already trained for 3 epochs" in err
    again = json.loads((moved / "results.json").read_text())["results"]["leather"]["methods"]
    assert again["student"]["curve"] == methods["student"]["curve"]
    out = moved
    # --jobs: the wide starts train first, in worker processes; the same table
    code, err = run_cli(*base, "--wide-start", 16, "--out", tmp_path / "j", "--jobs", 2)
    assert code == 0 and "wide.pt: already" not in err, err
    par = json.loads((tmp_path / "j" / "results.json").read_text())["results"]["leather"]
    for name, m in methods.items():
        assert par["methods"][name]["whole_l1"] == m["whole_l1"], name


def test_bench_quality_width(tmp_path):
    """--width 4: the single-level net and both students 4 wide (NeuMIP 4 x 25 as ever), said
    in the labels, the budget and the target headers; with --wide-start pruned to 4; --resume
    with another width refuses (one line) instead of training over them."""
    out = tmp_path / "q"
    base = ["bench", "quality", "--presets", "leather", "--out", out, "--res", 8, "--dirs", 4]
    base += ["--teacher-epochs", 1, "--epochs", 2, "--lafortune-iters", 1, "--no-progress"]
    code, err = run_cli(*base, "--width", 4, "--wide-start", 6)
    assert code == 0, err
    d = out / "leather"
    doc = json.loads((out / "results.json").read_text())
    methods = doc["results"]["leather"]["methods"]
    for name in ("single8", "student_nodistill", "student"):
        ck = load_checkpoint(d / f"{name}.pt")
        assert max(ck["spec"].get("hidden") or ck["spec"]["fine_hidden"]) == 4, name
        assert methods[name]["wide_start"] == {"width": 6, "epochs": 1}
    assert load_checkpoint(d / "neumip.pt")["spec"]["hidden"] == [25, 25, 25]
    assert methods["student"]["weight_bytes"] == 636  # the runtime network: 4 wide
    assert doc["config"]["width"] == 4 and doc["labels"]["single8"] == "Single-level 4-wide"
    md = (out / "results.md").read_text()
    assert "| Ours (coarse-to-fine, distilled, 4 wide) |" in md
    assert "then pruned to 4 wide (--wide-start)" in md and "| below single-level 4-wide |" in md
    assert "below single-level 8-wide" not in md
    code, err = run_cli(*base, "--width", 5, "--wide-start", 6, "--resume")
    assert code == 2 and err.count("\n") == 1 and "width 4 there, 5 here" in err, err
    code, err = run_cli(*base, "--width", 4, "--out", tmp_path / "p")  # from random weights
    assert code == 0, err
    assert (
        "; the single-level net and both students 4 wide (--width)"
        in (tmp_path / "p" / "results.md").read_text()
    )
    ck = load_checkpoint(tmp_path / "p" / "leather" / "student.pt")
    assert ck["spec"]["fine_hidden"] == [4] and ck["init_from"] is None


def test_bench_quality_resume_takes_a_teacher_trained_without_its_pack(tmp_path):
    """A teacher trained by hand with `teach --no-export` at the bench's settings is the
    bench's teacher: --resume reuses it (the flag changes no weight), and the table is the
    same as with the bench's own teacher."""
    from vrneural.outputs import OutputDir

    out = tmp_path / "q"
    base = ["bench", "quality", "--presets", "leather", "--out", out, "--res", 8, "--dirs", 4]
    base += ["--teacher-epochs", 1, "--epochs", 1, "--lafortune-iters", 1, "--no-progress"]
    code, err = run_cli(*base)
    assert code == 0, err
    teacher = out / "leather" / "teacher.pt"
    want = load_checkpoint(teacher)["net"]
    fresh = tmp_path / "fresh"
    with OutputDir(fresh, "bench quality") as od:
        od.open()
        (fresh / "leather").mkdir()
        (fresh / "btf").mkdir()
        for f in ("leather.btf", "leather.btf.synth.json"):
            (fresh / "btf" / f).write_bytes((out / "btf" / f).read_bytes())
    mine = fresh / "leather" / "teacher.pt"
    argv = ["teach", fresh / "btf" / "leather.btf", "-o", mine, "--epochs", 1, "--no-export"]
    code, err = run_cli(*argv, "--max-test-slices", 0, "--no-progress")
    assert code == 0, err
    stamp = mine.stat().st_mtime_ns
    code, err = run_cli(*[fresh if a == out else a for a in base], "--resume")
    assert code == 0, err
    assert mine.stat().st_mtime_ns == stamp  # reused, not retrained
    got = load_checkpoint(mine)["net"]
    assert all(np.array_equal(got[k].numpy(), v.numpy()) for k, v in want.items())
    a, b = (
        json.loads((d / "results.json").read_text())["results"]["leather"] for d in (out, fresh)
    )
    assert a["methods"]["student"]["whole_l1"] == b["methods"]["student"]["whole_l1"]


def test_bench_quality_help_words_shared_fields_for_the_bench(capsys):
    """The fields bench quality shares with distill (TrainBudget, StudentShape) are declared
    once, but its --help speaks of the bench's networks, not of distill's output file."""
    from vrneural.cli import main

    with pytest.raises(SystemExit):
        main(["bench", "quality", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "<output>.wide.pt" not in text
    assert "--wide-start WIDE_START train the single-level net and both students" in text
    assert "--ema EMA weight-average decay of every network but the teacher" in text
    assert "--width WIDTH hidden width of the single-level net and both students" in text
