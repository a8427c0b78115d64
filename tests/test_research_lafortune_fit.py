"""scripts/research/lafortune_fit.py: the bench's Lafortune baseline on its own gives the
bench's own numbers (same fit, split and scoring), and reuses its fit when run again."""

import json
import subprocess
import sys

import pytest
from script_helpers import RESEARCH
from test_bench_quality_btf import _btf

from vrneural.cli import main

SCRIPT = RESEARCH / "lafortune_fit.py"


def test_matches_the_bench(tmp_path):
    f = _btf(tmp_path / "tiny.btf")
    out = tmp_path / "bq"
    argv = ["bench", "quality", "--btf", str(f), "--quick", "--lafortune-iters", "2",
            "--no-progress", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    bench = json.loads((out / "results.json").read_text())["results"]["tiny.btf"]
    laf = bench["methods"]["lafortune"]
    res = tmp_path / "laf.json"
    cmd = [sys.executable, str(SCRIPT), str(f), str(out / "tiny.btf" / "teacher.pt"), str(res),
           "--iters", "2"]  # fmt: skip
    for reused in (False, True):
        subprocess.run(cmd, check=True, capture_output=True)
        doc = json.loads(res.read_text())
        assert doc["reused"] is reused
        assert doc["whole_l1"] == pytest.approx(laf["whole_l1"], rel=1e-6)
        assert doc["test_l1"] == pytest.approx(laf["test_l1"], rel=1e-6)
    assert res.with_suffix(".npz").is_file()
