"""`vrneural bench quality` end to end at a toy budget (the real budget is in README)."""

from __future__ import annotations

import json

from distill_helpers import run_cli


def test_bench_quality_smoke(tmp_path):
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
    for png in ("curves.png", "slices.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, err = run_cli(*args)  # results exist: refuse without --force
    assert code == 2 and "--force" in err
    code, err = run_cli(*args, "--resume")  # every checkpoint matches: nothing is retrained
    assert code == 0, err
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
