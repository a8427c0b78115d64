"""scripts/research/distance_student_seeds.py: its budgets, the pack names it trains into and
the table it writes (the training and rendering are the CLI's and the bench's, tested there)."""

import pytest
from script_helpers import load_research


@pytest.fixture(scope="module")
def mod():
    return load_research("distance_student_seeds")


def test_budgets(mod):
    assert mod.parse_budget("48") == (48, False)
    assert mod.parse_budget("24+ema") == (24, True)
    assert mod.stem(1, "48+ema") == "student-e48-ema-s1"
    for bad in ("0", "x", "48+swa", "-3", ""):
        with pytest.raises(SystemExit, match="--budgets"):
            mod.parse_budget(bad)


def test_summary_and_table(mod):
    s = mod.summary([0.2, 0.1, 0.15])
    assert s["mean"] == pytest.approx(0.15)
    assert (s["min"], s["max"], s["spread"]) == (0.1, 0.2, pytest.approx(2.0))
    doc = {"seeds": [0, 1, 2], "results": {"tiling 8": {"24": s, "48+ema": mod.summary([0.1] * 3)}}}
    lines = mod.report(doc).splitlines()
    assert lines[0] == "| condition | budget | seed 0 | seed 1 | seed 2 | mean | spread (max/min) |"
    assert lines[2] == "| tiling 8 | 24 | 0.2000 | 0.1000 | 0.1500 | 0.1500 | 2.00 |"
    assert lines[3].endswith("| 0.1000 | 1.00 |")
