"""`vrneural bench extremes`: a thin wrapper that runs the pytest cases of tests/extremes and
writes the report (results.json, results.md); every outcome (works, rejected, and the FAILs:
behaviour violated, unexpected acceptance, crash) and exit 1 on a FAIL; the cases are the ones
--only names, each once."""

from __future__ import annotations

import json
import re

from extremes import geometry, precision, shading

from vrneural.bench.configs import CASES
from vrneural.cli import main


def test_wrapper_runs_the_named_cases_and_reports_each_outcome(tmp_path, capsys, monkeypatch):
    def boom(quick):
        raise ValueError("boom")

    # CPU cases made to fail each way (the real ones run in tests/extremes/test_cases.py)
    monkeypatch.setattr(
        shading, "case_dir_normal_and_opposite", lambda q: {"ok": False, "note": "n"}
    )
    monkeypatch.setattr(geometry, "case_geo_nan_vertex", lambda q: {"ok": True})
    monkeypatch.setattr(shading, "case_dir_grazing", boom)
    out = tmp_path / "x"
    only = "normal_and_wi=-wo,nan_vertex,grazing_89.99deg,intensity_above_1e6,inf_vertex_obj"
    argv = ["bench", "extremes", "--quick", "--no-progress", "--only", only, "--out", str(out)]
    assert main(argv) == 1  # a FAIL
    text = capsys.readouterr().out
    assert re.fullmatch(
        rf"bench extremes: {out}/ results.json, results.md \(3 FAIL, \d+ s\)\n", text
    )
    doc = json.loads((out / "results.json").read_text())
    rec = {r["case"]: r for r in doc["records"]}
    assert [r["case"] for r in doc["records"]] == [c.name for c in CASES if c.name in rec]
    assert len(rec) == 5 and doc["n_fail"] == 3 and doc["config"]["quick"]
    assert (
        rec["normal_and_wi=-wo"]["outcome"] == "FAIL" and rec["normal_and_wi=-wo"]["message"] == "n"
    )
    assert rec["nan_vertex"]["message"] == "accepted, but the documented behaviour is a rejection"
    assert rec["grazing_89.99deg"]["message"] == "crash: ValueError: boom"
    for name in ("intensity_above_1e6", "inf_vertex_obj"):
        r = rec[name]
        assert r["outcome"] == "rejected" and "\n" not in r["message"] and r["seconds"] >= 0
    assert (
        rec["inf_vertex_obj"]["checks"] == "load_mesh"
        and "inf.obj" in rec["inf_vertex_obj"]["message"]
    )
    md = (out / "results.md").read_text()
    assert "5 cases: 0 works, 2 rejected (as documented), 3 FAIL." in md
    monkeypatch.undo()
    argv = [*argv[:5], "intensity_above_1e6", "--out", str(out)]
    assert main(argv) == 2 and "--force" in capsys.readouterr().err  # ours: needs --force
    assert main([*argv, "--force"]) == 0
    doc = json.loads((out / "results.json").read_text())
    assert [r["outcome"] for r in doc["records"]] == ["rejected"] and doc["n_fail"] == 0


def test_wrapper_needs_pytest_and_the_cases(tmp_path, capsys, monkeypatch):
    """Without the source checkout's cases (an installed wheel): one line, exit 2, no folder."""
    import vrneural.bench.extremes as ext

    monkeypatch.setattr(ext, "TESTS", tmp_path / "none" / "test_cases.py")
    out = tmp_path / "o"
    assert main(["bench", "extremes", "--quick", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pip install -e '.[dev]'" in err and "missing" in err, err
    assert not out.exists()


def test_pytest_writes_the_same_report(tmp_path):
    """`pytest -m extremes --extremes-report DIR`: the bench's report of the cases that ran."""
    import pytest

    out = tmp_path / "r"
    path = str(precision.__file__).replace("precision.py", "test_cases.py")
    args = [path, "-q", "-p", "no:cacheprovider", "-k", "intensity_above_1e6 or nan_vertex"]
    assert pytest.main([*args, "--extremes-report", str(out)]) == 0
    doc = json.loads((out / "results.json").read_text())
    assert doc["bench"] == "extremes" and doc["n_fail"] == 0 and doc["config"]["quick"]
    assert [r["case"] for r in doc["records"]] == ["intensity_above_1e6", "nan_vertex"]
