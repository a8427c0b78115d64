"""scripts/research/pt_students.py: the student targets it reports (issue #35's five-seed
students) are the bench's rules, on the seed means and seed pair by seed pair."""

import pytest
from script_helpers import load_research


@pytest.fixture(scope="module")
def mod():
    return load_research("pt_students")


def test_verdicts_on_means_and_pairs(mod):
    l1 = {
        "student": {0: 1.05, 1: 1.20, 2: 0.95},
        "neumip": {0: 1.0, 1: 1.0, 2: 1.0},
        "single8": {0: 1.10, 1: 1.10, 2: 1.05},
        "student_nodistill": {0: 1.00, 2: 0.90},  # seed 1 missing: two pairs only
    }
    v = mod.verdicts(l1)
    assert v["student_over_neumip"] == pytest.approx(3.2 / 3)
    assert v["student_over_neumip_by_seed"] == pytest.approx([1.05, 1.20, 0.95])
    assert v["within_10pct_of_neumip"] is True
    assert v["below_single8"] is True  # 3.2 / 3 against 3.25 / 3
    assert v["below_single8_pairs"] == [2, 3]
    assert v["below_student_nodistill"] is False
    assert v["below_student_nodistill_pairs"] == [0, 2]
    row = mod.report({"bark": v}).splitlines()[2]
    assert row.startswith("| bark | 1.06667 (3) | 1.00000 (3) |")
    assert "1.067 (0.95-1.20)" in row and "(0 of 2)" in row


def test_a_miss_of_the_10pct_target(mod):
    v = mod.verdicts({"student": {0: 1.2, 1: 1.1}, "neumip": {0: 1.0, 1: 1.0}})
    assert v["within_10pct_of_neumip"] is False
    assert "below_single8" not in v


def test_a_recipe_suffix_names_the_narrow_networks_only(mod):
    assert mod.stems() == {m: m for m in mod.METHODS}
    s = mod.stems("ws")
    assert s["neumip"] == "neumip"  # the bench never widens NeuMIP
    assert [s[m] for m in ("student", "single8", "student_nodistill")] == [
        "student_ws",
        "single8_ws",
        "student_nodistill_ws",
    ]


def test_the_tally_names_every_miss(mod):
    hit = mod.verdicts(
        {
            "student": {0: 1.0},
            "neumip": {0: 1.0},
            "single8": {0: 1.1},
            "student_nodistill": {0: 1.1},
        }
    )
    miss = mod.verdicts(
        {
            "student": {0: 1.2},
            "neumip": {0: 1.0},
            "single8": {0: 1.1},
            "student_nodistill": {0: 1.3},
        }
    )
    t = mod.tally({"bark": hit, "weave": miss})
    assert "within 10% of NeuMIP on 1 of 2 (not weave)" in t
    assert "below the single-level net on 1 of 2 (not weave)" in t
    assert "below the no-distillation student on 2 of 2." in t
    assert t in mod.report({"bark": hit, "weave": miss})
    assert mod.tally({}) == ""


def test_add_keeps_the_other_presets_in_their_order(mod):
    old = {"bark": {"x": 1}, "fur": {"x": 2}}
    assert list(mod.merge(old, {"fur": {"x": 3}, "weave": {"x": 4}}).items()) == [
        ("bark", {"x": 1}),
        ("fur", {"x": 3}),
        ("weave", {"x": 4}),
    ]


def test_add_writes_the_merged_table(mod, tmp_path, monkeypatch):
    import json
    import sys

    out = tmp_path / "students"
    out.with_suffix(".json").write_text(json.dumps({"bark": mod.verdicts({"student": {0: 1.0}})}))
    out.with_suffix(".md").write_text(
        "An introduction written by hand.\n\n" + mod.TABLE_HEAD + "\n|---|\n| bark | old |\n"
    )
    monkeypatch.setattr(
        mod, "score", lambda root, p, suffix="": {"student": {0: 2.0}, "neumip": {0: 1.0}}
    )
    monkeypatch.setattr(
        sys, "argv", ["pt_students", str(tmp_path), "--presets", "weave", "--add", "-o", str(out)]
    )
    mod.main()
    res = json.loads(out.with_suffix(".json").read_text())
    assert list(res) == ["bark", "weave"]
    assert res["weave"]["within_10pct_of_neumip"] is False
    md = out.with_suffix(".md").read_text()
    assert (
        "| bark |" in md
        and "| weave |" in md
        and "within 10% of NeuMIP on 0 of 1 (not weave)" in md
    )
    # the introduction is kept, the old table replaced by the merged one
    assert md.startswith("An introduction written by hand.\n\n" + mod.TABLE_HEAD)
    assert md.count(mod.TABLE_HEAD) == 1 and "| bark | old |" not in md
