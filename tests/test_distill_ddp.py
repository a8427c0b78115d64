"""torchrun --nproc_per_node 2 (DDP, gloo) gives the single-process result to float tolerance."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import warnings

import pytest
import torch
from distill_helpers import FAST, run_cli, trained  # noqa: F401 (fixture)

from vrneural.distill.checkpoint import load_checkpoint


@pytest.mark.parametrize("wide", [False, True], ids=["plain", "wide-start"])
def test_ddp_equals_single_process(trained, tmp_path, wide):  # noqa: F811
    """Plain, and --wide-start (both halves under DDP, every rank pruning the wide half that
    rank 0 wrote)."""
    single, multi = tmp_path / "single.pt", tmp_path / "multi.pt"
    epochs = ["--epochs", "2", "--wide-start", "16"] if wide else ["--epochs", "1"]
    args = ["distill", str(trained["teacher"]), *epochs, *FAST, "--no-export"]
    # TMPDIR: torchrun's per-run torchelastic_* directories stay in the test's folder
    env = {**os.environ, "OMP_NUM_THREADS": "1", "TMPDIR": str(tmp_path)}
    code, err = run_cli(*args, "-o", single)  # in-process: saves one torch start-up
    assert code == 0, err
    torchrun = [
        sys.executable,
        "-m",
        "torch.distributed.run",
        "--standalone",
        "--nproc_per_node",
        "2",
        "-m",
        "vrneural",
    ]
    if shutil.which(sys.executable) is None:
        pytest.skip("no python executable for torchrun")
    # A rare crash of a gloo worker (SIGABRT, about 1 in 5 full-suite runs on the 2-core CI
    # VM, never in isolation; not yet explained) gets one more try, and is reported as a
    # warning with its whole output; two failures in a row fail the test.
    failures = []
    for _ in range(2):
        r = subprocess.run(
            [*torchrun, *args, "-o", str(multi), "--force"],
            capture_output=True,
            text=True,
            env=env,
            timeout=240,
        )
        if r.returncode == 0:
            break
        failures.append(f"torchrun exit {r.returncode}\n{r.stdout}\n{r.stderr}")
    assert r.returncode == 0, "\n\n".join(failures)
    if failures:
        warnings.warn(f"torchrun failed once, then passed:\n{failures[0]}", stacklevel=1)
    a, b = load_checkpoint(single), load_checkpoint(multi)
    assert b["epoch"] == 1 and b["finished"]
    if wide:  # the pruned half started from the same wide half
        assert b["init_from"]["spec"] == a["init_from"]["spec"]
        assert b["init_from"]["path"] == str(tmp_path / "multi.wide.pt")
    # gradients are averaged over two equal halves of each slice: equal to the full-slice
    # gradient up to float32 summation order; after one epoch of Adam the weights agree to
    # about 1e-6 (measured 2e-7); a wrong split (e.g. unequal shares) is off by > 1e-3
    for k in a["net"]:
        torch.testing.assert_close(b["net"][k], a["net"][k], atol=2e-5, rtol=1e-4)
    assert abs(a["history"][-1]["test_l1"] - b["history"][-1]["test_l1"]) < 1e-5
    # the recorded loss is the whole slice's (it was rank 0's half: 0.5% off)
    ta, tb = a["history"][-1]["train_loss"], b["history"][-1]["train_loss"]
    assert abs(ta - tb) < 1e-5 * ta, (ta, tb)
