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
from vrneural.errors import VrnError
from vrneural.formats.vrnm import read_vrnm


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
    assert ("ema" in ca) == ("ema" in cb)
    if "ema" in ca:
        assert ca["ema"]["count"] == cb["ema"]["count"]
        for k, v in ca["ema"]["avg"].items():
            assert torch.equal(v, cb["ema"]["avg"][k]), k


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


def test_resume_refuses_changed_settings_and_fewer_epochs(btf, tmp_path):
    t = tmp_path / "t.pt"
    assert run_cli("teach", btf, "-o", t, "--epochs", 2, "--width", 32, *FAST)[0] == 0
    before = t.read_bytes()
    again = ("teach", btf, "-o", t, "--resume", "--no-progress")
    code, err = run_cli(*again, "--epochs", 3, "--width", 64)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "--width = 64, but" in err and "trained with 32" in err
    code, err = run_cli(*again, "--epochs", 1)
    assert code == 2 and "already has 2 epochs" in err, err
    assert t.read_bytes() == before
    # without --epochs a resume continues to the run's own target: here finished, so a no-op
    code, err = run_cli(*again)
    assert code == 0, err
    assert t.read_bytes() == before and load_checkpoint(t)["epoch"] == 2
    # a flag typed with its default value is still a choice: 128 is the default width, and
    # --epochs 20 (the default) extends the run instead of being taken for "no --epochs"
    code, err = run_cli(*again, "--width", 128)
    assert code == 2 and "--width = 128, but" in err, err
    assert t.read_bytes() == before
    code, err = run_cli(*again, "--epochs", 20, "--width", 32)
    assert code == 0, err
    assert load_checkpoint(t)["epoch"] == 20


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
    done = r"holds an unfinished run \(1 of 2 epochs done and 5 steps of the next\); pass --resume"
    with pytest.raises(VrnError, match=done):
        run_teach(TeachConfig(output=str(b), **kw))  # the hint points at --resume, not --force
    # --epochs 1 would end before the weights it holds (partway through epoch 2): refused, and
    # the checkpoint keeps its state and its target
    before = b.read_bytes()
    code, err = run_cli("teach", btf, "-o", b, "--resume", "--epochs", 1, "--no-progress")
    assert code == 2 and "stopped partway through epoch 2 (step 5)" in err, err
    assert "--epochs 2 or more" in err and b.read_bytes() == before
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


def test_distill_with_ema_resumes_exactly_and_exports_the_average(btf, tmp_path):
    """--ema: Ctrl-C mid-epoch + resume equals the straight run (average included); the
    checkpoint's network, its test L1 and its pack are the average, not the last step."""
    import numpy as np

    from vrneural.btf.format import read_btf
    from vrneural.distill.data import SliceData
    from vrneural.distill.distill import model_from_checkpoint, run_distill
    from vrneural.distill.evaluate import mean_l1
    from vrneural.formats.vrnm import read_vrnm
    from vrneural.material import material_forward

    t = tmp_path / "t.pt"
    assert run_cli("teach", btf, "-o", t, "--epochs", 1, "--width", 32, *FAST)[0] == 0
    a, b = tmp_path / "a.pt", tmp_path / "b.pt"
    kw = dict(teacher=str(t), progress=False, max_test_slices=0, ema=0.9, epochs=2)
    ck = run_distill(DistillConfig(output=str(a), **kw))

    def ctrl_c(epoch, step):
        if (epoch, step) == (1, 3):
            signal.raise_signal(signal.SIGINT)

    with pytest.raises(Interrupted):
        run_distill(DistillConfig(output=str(b), **kw), on_step=ctrl_c)
    run_distill(DistillConfig(output=str(b), resume=True, **kw))
    _same(a, b)
    steps = 2 * (25 - round(25 * 0.1))  # 2 epochs of the 5 x 5 pairs' training share
    assert ck["ema"]["count"] == steps
    last = {k: v for k, v in ck["net"].items() if k.startswith("model.")}
    avg = {k: v for k, v in ck["ema"]["avg"].items() if k.startswith("model.")}
    assert set(avg) == set(last) and any(not torch.equal(avg[k], last[k]) for k in avg)
    model = model_from_checkpoint(ck)
    for k, v in model.state_dict().items():
        assert torch.equal(v, avg["model." + k]), k
    data = SliceData(read_btf(btf), ck["split"]["test"])
    assert mean_l1(model, data, data.test) == pytest.approx(ck["history"][-1]["test_l1"], rel=1e-6)
    mat = read_vrnm(a.with_suffix(".vrnm"))
    wi, wo = data.dirs(data.test[0])
    uv = data.uv(None, shard=False)
    n = uv.shape[0]
    got = material_forward(
        mat, np.tile(wi.numpy(), (n, 1)), np.tile(wo.numpy(), (n, 1)), uv.numpy()
    )
    want = model.predict(wi, wo, uv).numpy()
    np.testing.assert_allclose(got, want, atol=1e-5)


def test_ema_average_and_swap():
    from torch import nn

    from vrneural.distill.train import Ema

    net = nn.Linear(2, 1, bias=False)
    with torch.no_grad():
        net.weight.fill_(0.0)
    ema = Ema(net, decay=0.5)
    with torch.no_grad():
        net.weight.fill_(1.0)
    ema.update()  # decay min(0.5, 2/11): avg = 0 + (1 - 2/11) * 1
    assert float(ema.avg["weight"][0, 0]) == pytest.approx(9 / 11)
    ema.update()  # now min(0.5, 3/12) = 0.25
    assert float(ema.avg["weight"][0, 0]) == pytest.approx(9 / 11 + 0.75 * (1 - 9 / 11))
    with ema.applied():
        assert float(net.weight.detach()[0, 0]) == pytest.approx(float(ema.avg["weight"][0, 0]))
    assert float(net.weight[0, 0].detach()) == 1.0  # swapped back
    again = Ema(net, decay=0.5)
    again.load(ema.state())
    assert again.count == 2 and torch.equal(again.avg["weight"], ema.avg["weight"])


def test_resume_messages_name_the_option_that_set_the_field():
    """`bench quality` sets its teachers' epochs with --teacher-epochs: the resume errors say so."""
    from vrneural.distill.teach import resumed_config

    cfg = TeachConfig(output="t.pt", epochs=1)
    with pytest.raises(VrnError, match=r"^--epochs = 1, but t\.pt already has 2 epochs"):
        resumed_config(cfg, {"epochs": 3}, {"epoch": 2})
    with pytest.raises(VrnError, match="pass --teacher-epochs 2 or more") as e:
        resumed_config(cfg, {"epochs": 3}, {"epoch": 2}, epochs_flag="--teacher-epochs")
    assert str(e.value).startswith("--teacher-epochs = 1, but t.pt")
    # stopped partway through epoch 3: the least --epochs that continues it is 3, not 2
    with pytest.raises(VrnError, match="pass --epochs 3 or more to continue it"):
        resumed_config(cfg, {"epochs": 3}, {"epoch": 2, "step": 5})


def test_unfinished_teacher_warns_and_exported_unfinished_student_resumes(btf, tmp_path):
    """A teacher stopped in epoch 0: distilling from it warns. A student stopped in its first
    epoch and exported (export says to finish it with --resume): that --resume works and
    replaces the pack, which records no test-L1 curve yet but names its checkpoint."""
    from vrneural.distill.checkpoint import UnfinishedRunWarning
    from vrneural.distill.distill import run_distill

    t, s = tmp_path / "t.pt", tmp_path / "s.pt"

    def ctrl_c(epoch, step):
        if (epoch, step) == (0, 3):
            signal.raise_signal(signal.SIGINT)

    kw = dict(progress=False, max_test_slices=4)
    with pytest.raises(Interrupted):
        run_teach(TeachConfig(btf=str(btf), output=str(t), epochs=2, width=32, **kw), ctrl_c)
    with pytest.warns(UnfinishedRunWarning, match=r"t\.pt: an unfinished run \(0 of 2 epochs"):
        with pytest.raises(Interrupted):
            run_distill(DistillConfig(teacher=str(t), output=str(s), epochs=1, **kw), ctrl_c)
    assert load_checkpoint(s)["history"] == []
    with pytest.warns(UnfinishedRunWarning, match="which replaces this pack"):
        code, err = run_cli("export", s, "-o", s.with_suffix(".vrnm"))
    assert code == 0, err
    code, err = run_cli("distill", t, "-o", s, "--resume", "--no-progress")
    assert code == 0, err
    meta = read_vrnm(s.with_suffix(".vrnm")).meta
    assert len(meta["metrics"]["test_l1_curve"]) == 1  # the finished run's pack replaced it


def test_finished_run_resumed_names_the_benchs_flag(btf, tmp_path, capsys):
    """`bench quality --resume` on a finished teacher: the "nothing left" note names
    --teacher-epochs, the flag that sets it there (kept through the resumed config)."""
    t = tmp_path / "t.pt"
    kw = dict(btf=str(btf), output=str(t), epochs=1, width=32, progress=False, export=False)
    run_teach(TeachConfig(**kw))
    capsys.readouterr()
    run_teach(TeachConfig(**kw, resume=True), epochs_flag="--teacher-epochs")
    err = capsys.readouterr().err
    assert "already trained for 1 epoch, nothing left" in err
    assert "(--teacher-epochs N with N > 1 continues it)" in err


def test_finished_run_resumed_where_no_flag_sets_its_epochs_shows_nothing(btf, tmp_path, capsys):
    """A finished `bench quality --wide-start` half resumed (no option sets a half's epochs,
    so no "nothing left" note): no empty progress bar either."""
    t = tmp_path / "t.pt"
    kw = dict(btf=str(btf), output=str(t), epochs=1, width=32, export=False)
    run_teach(TeachConfig(**kw, progress=False))
    capsys.readouterr()
    run_teach(TeachConfig(**kw, resume=True), epochs_flag="")
    assert capsys.readouterr().err == ""
