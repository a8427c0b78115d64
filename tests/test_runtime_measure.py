"""`python -m vrneural.runtime.measure --quick`: the runtime targets' measurement runs end to end
and reports sane, self-consistent numbers (never an absolute time: those live in benchmarks)."""

from __future__ import annotations

import json
import math

import pytest


@pytest.mark.gpu
def test_measure_quick_writes_every_target(tmp_path, capsys):
    from vrneural.runtime.measure import main

    out = tmp_path / "m.json"
    assert main([str(out), "--quick"]) == 0
    text = capsys.readouterr().out  # a short report, the numbers are in the JSON
    assert text.startswith(f"wrote {out}") and "texture_vs_screen: ratio " in text
    assert "mlp_only: constants_vs_buffer " in text and "staggered.p99_over_median" in text
    assert len(text.splitlines()) == 6
    for bad, why in (("bogus", "unknown measurement 'bogus'"), (",", "--only is empty")):
        with pytest.raises(SystemExit) as e:
            main([str(tmp_path / "x.json"), "--only", bad])
        assert e.value.code == 2 and why in capsys.readouterr().err
    one = tmp_path / "one.json"  # --only keeps --quick's sizes and the run's context
    assert main([str(one), "--only", "mlp_only", "--quick"]) == 0
    d = json.loads(one.read_text())
    assert d["mlp_only"]["blocks"] == 4096 and d["quick"] and "adapter" in d and "seconds" in d
    assert set(d) & {"texture_vs_screen", "schedules"} == set()
    assert main([str(one), "--only", "mlp_only", "--quick", "--force"]) == 0  # replaced
    doc = json.loads(out.read_text())
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


def test_measure_checks_its_output_before_measuring(tmp_path, capsys, monkeypatch):
    """A bad or existing output is a one-line error (exit 2) before any work; --force replaces."""
    import vrneural.runtime.measure as m

    def never(*a, **k):
        raise AssertionError("measured before the output was checked")

    monkeypatch.setattr(m, "measure_all", never)
    old = tmp_path / "m.json"
    old.write_text("{}")
    cases = [
        ([str(old)], "output exists; pass --force to overwrite"),
        ([str(tmp_path)], "output path is a directory (a file is written here)"),
        ([str(tmp_path / "new") + "/"], "output path is a directory (a file is written here)"),
    ]
    for argv, why in cases:
        assert m.main([*argv, "--quick"]) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and why in err and "Traceback" not in err, err
    assert old.read_text() == "{}" and not (tmp_path / "new").exists()
    monkeypatch.setattr(m, "measure_all", lambda quick, only: {"seconds": 1.0, "quick": quick})
    nested = tmp_path / "a" / "b" / "m.json"  # missing folders are created
    assert m.main([str(nested), "--quick"]) == 0 and json.loads(nested.read_text())["quick"]
    assert m.main([str(old), "--force"]) == 0 and json.loads(old.read_text())["seconds"] == 1.0
