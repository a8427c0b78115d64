"""--resume reproduces an uninterrupted run bit for bit (CPU), also after Ctrl-C mid-epoch."""

from __future__ import annotations

import signal

import pytest
import torch
from distill_helpers import FAST, analytic_btf, run_cli

from vrneural.distill.checkpoint import load_checkpoint
from vrneural.distill.config import DistillConfig, TeachConfig
from vrneural.distill.teach import run_teach
from vrneural.distill.train import Interrupted


def _same(a, b):
    ca, cb = load_checkpoint(a), load_checkpoint(b)
    assert ca["epoch"] == cb["epoch"]
    for k in ca["net"]:
        assert torch.equal(ca["net"][k], cb["net"][k]), k
    for sa, sb in zip(
        ca["optimizer"]["state"].values(), cb["optimizer"]["state"].values(), strict=True
    ):
        assert torch.equal(sa["exp_avg_sq"], sb["exp_avg_sq"])
    assert [h["test_l1"] for h in ca["history"]] == [h["test_l1"] for h in cb["history"]]


@pytest.fixture(scope="module")
def btf(tmp_path_factory):
    return analytic_btf(tmp_path_factory.mktemp("resume") / "r.btf", res=16, n_dirs=5)


def test_teach_resume_equals_straight_run(btf, tmp_path):
    a, b = tmp_path / "a.pt", tmp_path / "b.pt"
    assert run_cli("teach", btf, "-o", a, "--epochs", 3, "--width", 32, *FAST)[0] == 0
    assert run_cli("teach", btf, "-o", b, "--epochs", 1, "--width", 32, *FAST)[0] == 0
    code, err = run_cli("teach", btf, "-o", b, "--epochs", 3, "--resume", "--no-progress")
    assert code == 0, err
    _same(a, b)


def test_ctrl_c_saves_and_resume_continues_mid_epoch(btf, tmp_path):
    a, b = tmp_path / "a.pt", tmp_path / "b.pt"
    kw = dict(btf=str(btf), epochs=2, width=32, progress=False, max_test_slices=4, export=False)
    run_teach(TeachConfig(output=str(a), **kw))

    def ctrl_c(epoch, step):
        if (epoch, step) == (1, 5):
            signal.raise_signal(signal.SIGINT)  # the real handler: finish the step, save, stop

    with pytest.raises(Interrupted):
        run_teach(TeachConfig(output=str(b), **kw), on_step=ctrl_c)
    ck = load_checkpoint(b)
    assert (ck["epoch"], ck["step"], ck["finished"]) == (1, 5, False)
    run_teach(TeachConfig(output=str(b), resume=True, **kw))
    _same(a, b)


def test_distill_resume_equals_straight_run(btf, tmp_path):
    t = tmp_path / "t.pt"
    assert run_cli("teach", btf, "-o", t, "--epochs", 1, "--width", 32, *FAST)[0] == 0
    a, b = tmp_path / "a.pt", tmp_path / "b.pt"
    from vrneural.distill.distill import run_distill

    kw = dict(teacher=str(t), progress=False, max_test_slices=4, export=False)
    run_distill(DistillConfig(output=str(a), epochs=2, **kw))
    run_distill(DistillConfig(output=str(b), epochs=1, **kw))
    run_distill(DistillConfig(output=str(b), epochs=2, resume=True, **kw))
    _same(a, b)
    assert any(k.startswith("T1.") for k in load_checkpoint(b)["net"])  # T maps resumed too


def test_resume_writes_where_the_checkpoint_is_now(btf, tmp_path):
    """A checkpoint moved (with its teacher) to another directory resumes there: the stored
    config's old output path is neither written nor needed."""
    import shutil

    from vrneural.distill.distill import run_distill

    old, new = tmp_path / "old", tmp_path / "new"
    old.mkdir()
    kw = dict(progress=False, max_test_slices=4, export=False)
    run_teach(TeachConfig(btf=str(btf), output=str(old / "t.pt"), epochs=1, width=32, **kw))
    run_distill(DistillConfig(teacher=str(old / "t.pt"), output=str(old / "s.pt"), epochs=1, **kw))
    shutil.copytree(old, new)
    shutil.rmtree(old)
    run_distill(
        DistillConfig(
            teacher=str(new / "t.pt"), output=str(new / "s.pt"), epochs=2, resume=True, **kw
        )
    )
    run_teach(TeachConfig(btf=str(btf), output=str(new / "t.pt"), epochs=2, resume=True, **kw))
    assert not old.exists()
    assert load_checkpoint(new / "t.pt")["epoch"] == 2
    assert load_checkpoint(new / "s.pt")["epoch"] == 2
