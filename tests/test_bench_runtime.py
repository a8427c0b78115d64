"""`vrneural bench runtime --quick`: the runtime targets' measurement runs end to end and
reports sane, self-consistent numbers (never an absolute time: those live in benchmarks)."""

from __future__ import annotations

import json
import math

import pytest

from vrneural.cli import main


@pytest.mark.gpu
def test_runtime_quick_writes_every_target(tmp_path, capsys):
    out = tmp_path / "m"
    assert main(["bench", "runtime", "--quick", "--no-progress", "--out", str(out)]) == 0
    text = capsys.readouterr().out  # a short report, the numbers are in the JSON
    assert text.startswith(f"bench runtime: {out}/ results.json, results.md (")
    assert "texture_vs_screen: ratio " in text and "staggered.p99_over_median" in text
    assert "mlp_only: constants_vs_buffer " in text and len(text.splitlines()) == 6
    md = (out / "results.md").read_text()
    assert md.startswith("# vrneural bench runtime") and "| vs_torch | ratio " in md
    one = tmp_path / "one"  # --only keeps --quick's sizes and the run's context
    argv = ["bench", "runtime", "--only", "mlp_only", "--quick", "--no-progress", "--out", str(one)]
    assert main(argv) == 0
    d = json.loads((one / "results.json").read_text())
    assert d["mlp_only"]["blocks"] == 4096 and d["quick"] and "adapter" in d
    assert d["bench"] == "runtime" and [r["measurement"] for r in d["records"]] == ["mlp_only"]
    assert set(d) & {"texture_vs_screen", "schedules"} == set()
    assert main([*argv, "--force"]) == 0  # replaced
    doc = json.loads((out / "results.json").read_text())
    for key in ("texture_vs_screen", "constants_vs_buffer", "vs_torch"):
        r = doc[key]
        assert math.isfinite(r["ratio"]) and r["ratio"] > 0 and r["target"] > 1, key
    tvs = doc["texture_vs_screen"]
    # per displayed frame the texture pass evaluates fewer networks than the screen pass
    assert tvs["texture_mlp_evals_per_update"] / 5 < tvs["screen_mlp_evals_per_frame"]
    sch = doc["schedules"]
    n = sch["config"]["frames"] - 1
    for k in ("burst", "staggered"):
        d = sch[k]
        assert len(d["frame_wall_ms"]["series"]) == len(d["frame_cpu_ms"]["series"]) == n
        assert d["p99_over_median"] >= 1 and d["cpu_p99_over_median"] >= 1
        assert (
            0 <= d["mean_abs_error_vs_every_frame"] < 0.1 * sch["config"]["mean_displayed_radiance"]
        )
    # staggered spreads the work: its busiest frame is far below a burst frame's (counters)
    assert sch["staggered"]["work_p99_over_median"] < 1.5
    assert (
        sch["burst"]["mlp_evals_per_frame"]["p99"]
        > 3 * sch["staggered"]["mlp_evals_per_frame"]["p99"]
    )
    assert sch["control_every_frame"]["p99_over_median"] >= 1


def test_runtime_checks_its_options_and_output_before_measuring(tmp_path, capsys, monkeypatch):
    """A bad --only, or an output folder that is not ours or needs --force, is a one-line
    error (exit 2) before any work; --force replaces."""
    import vrneural.bench.runtime as m

    def never(*a, **k):
        raise AssertionError("measured before the options and output were checked")

    monkeypatch.setattr(m, "measure_all", never)
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep")
    cases = [
        (["--only", "bogus"], "error: --only: unknown measurement 'bogus'; choose from "),
        (["--only", ","], "error: --only is empty; choose from texture_vs_screen, "),
        (["--out", str(mine)], "not a vrneural output directory"),
    ]
    for argv, why in cases:
        assert main(["bench", "runtime", "--quick", *argv]) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and why in err and "Traceback" not in err, err
    assert (mine / "notes.txt").read_text() == "keep" and not (tmp_path / "bench-runtime").exists()
    nested = tmp_path / "a" / "b"  # missing folders are created
    argv = ["bench", "runtime", "--only", "mlp_only", "--no-progress", "--out", str(nested)]
    monkeypatch.setattr(
        m, "measure_all", lambda quick, only, progress: ({"mlp_only": {"x": 1.0}}, {"mlp_only": 1})
    )
    assert main(argv) == 0 and json.loads((nested / "results.json").read_text())["mlp_only"]
    assert main(argv) == 2 and "--force" in capsys.readouterr().err  # ours: needs --force
    assert main([*argv, "--force"]) == 0
