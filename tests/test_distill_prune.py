"""``distill --width`` and ``--init-from``: pruning a wide network to a narrow one.

Parity: units that are constant over the data (their mean folded into the next bias) or that
nothing reads are dropped first, and then the pruned network is the wide one exactly. The CLI
trains a wide run, prunes it, exports the pruned pack (numpy forward == torch) and refuses
every init it cannot use with one line.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from distill_helpers import FAST, analytic_btf, expect_one_line_error, run_cli

from vrneural.btf.format import read_btf
from vrneural.distill.checkpoint import (
    UnfinishedRunWarning,
    load_checkpoint,
    model_from_checkpoint,
    save_checkpoint,
)
from vrneural.distill.data import SliceData
from vrneural.distill.models import NeuralModel, make_spec
from vrneural.distill.prune import prune_to
from vrneural.formats.vrnm import read_vrnm
from vrneural.material import material_forward


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    d = tmp_path_factory.mktemp("prune")
    return SliceData(read_btf(analytic_btf(d / "m.btf", res=16, n_dirs=4)), [0, 5])


def _hidden_chains(spec):
    if spec["arch"] == "single":
        return [("mlp", len(spec["hidden"]))]
    return [("coarse", len(spec["coarse_hidden"])), ("fine", len(spec["fine_hidden"]))]


@torch.no_grad()
def _predict(net, data, pairs=(1, 2, 7, 11)):
    g = torch.Generator().manual_seed(3)
    uv = data.uv(g, shard=False)  # jittered: not only the texel centres pruning looked at
    return torch.stack([net.predict(*data.dirs(p), uv) for p in pairs])


@pytest.mark.parametrize("method", ["student", "single8"])
@pytest.mark.parametrize("kind", ["constant", "unread"])
def test_dropped_units_that_carry_nothing_leave_the_function_exact(data, method, kind):
    """A 12-wide network whose units 8-11 are constant (kind ``constant``: zero incoming
    weights, positive bias; pruning folds their value into the next bias) or read by nothing
    (``unread``) prunes to an 8-wide network with the same output."""
    wide_spec = make_spec(method, data.res, width=12)
    wide = NeuralModel(wide_spec, seed=1)
    with torch.no_grad():
        for name, n in _hidden_chains(wide_spec):
            for i in range(n):
                lin = getattr(wide, name).layers[i]
                lin.bias[:8] += 0.5  # keep the real units alive
                if kind == "constant":
                    lin.weight[8:] = 0.0
                    lin.bias[8:] = torch.linspace(0.1, 0.4, 4)
                else:
                    lin.weight[8:] *= 3.0  # large variance, but nothing reads them
                    reader = _reader(wide, name, i, n)
                    reader.weight[:, 8:12] = 0.0
    narrow = prune_to(wide, make_spec(method, data.res, width=8), data)
    for name, n in _hidden_chains(narrow.spec):
        for i in range(n):
            got = getattr(narrow, name).layers[i].weight
            full = getattr(wide, name).layers[i].weight
            # kept: units 0-7; inputs: all, or units 0-7 of the layer before + the rest
            cols = list(range(full.shape[1]))
            if full.shape[1] != got.shape[1]:
                cols = cols[:8] + cols[12:]
            assert got.shape[0] == 8 and torch.equal(got, full[:8][:, cols])
    np.testing.assert_allclose(
        _predict(narrow, data).numpy(), _predict(wide, data).numpy(), rtol=1e-5, atol=1e-6
    )
    for k in narrow.tex:
        assert torch.equal(narrow.tex[k], wide.tex[k])


def _reader(net, name, i, n):
    if name == "coarse" and i + 1 == n:
        return net.fine.layers[0]  # the coarse MLP's last layer, z_c, is read by M_f
    return getattr(net, name).layers[i + 1]


@pytest.mark.parametrize("method", ["student", "single8"])
def test_pruning_to_the_same_width_changes_nothing(data, method):
    spec = make_spec(method, data.res, width=8)
    net = NeuralModel(spec, seed=4)
    same = prune_to(net, spec, data)
    for k, v in net.state_dict().items():
        assert torch.equal(same.state_dict()[k], v), k


def test_importance_is_spread_times_the_weights_that_read_it(data):
    """A unit with a large spread that nothing reads goes before a weakly varying one that is
    read; a read, varying unit stays."""
    spec = make_spec("single8", data.res, width=3)
    net = NeuralModel(spec, seed=2)
    with torch.no_grad():
        first, second = net.mlp.layers[0], net.mlp.layers[1]
        first.weight[0] *= 10.0  # varies a lot, read by nothing
        second.weight[:, 0] = 0.0
        first.bias += 1.0  # all alive
        first.weight[2] *= 0.1  # varies a little, read
    narrow = prune_to(net, make_spec("single8", data.res, width=2), data)
    assert torch.equal(narrow.mlp.layers[0].weight, net.mlp.layers[0].weight[[1, 2]])


def test_width_and_init_from_end_to_end(tmp_path):
    """A 16-wide student (its pack runs in numpy), pruned into an 8-wide one by --init-from;
    the pack of the pruned run equals its torch network and records where it started."""
    btf = analytic_btf(tmp_path / "m.btf", res=16, n_dirs=4)
    t, w, s = tmp_path / "t.pt", tmp_path / "wide.pt", tmp_path / "s.pt"
    assert run_cli("teach", btf, "-o", t, "--epochs", 1, *FAST)[0] == 0
    code, err = run_cli("distill", t, "-o", w, "--width", 16, "--epochs", 1, *FAST)
    assert code == 0, err
    wide_ck = load_checkpoint(w)
    assert wide_ck["spec"]["coarse_hidden"] == [16, 16] and wide_ck["spec"]["fine_hidden"] == [16]
    code, err = run_cli("distill", t, "-o", s, "--init-from", w, "--epochs", 1, *FAST)
    assert code == 0, err
    ck = load_checkpoint(s)
    assert ck["spec"]["coarse_hidden"] == [8, 8] and ck["config"]["init_from"] == str(w)
    assert ck["init_from"]["epochs"] == 1 and ck["init_from"]["spec"] == wide_ck["spec"]
    assert json.loads((tmp_path / "s.pt.config.json").read_text())["init_from"] == str(w)
    # the packs say what they are: eval's method column, and where the pruned one started
    from vrneural.scoring.run import label

    pruned = read_vrnm(tmp_path / "s.vrnm")
    assert label(read_vrnm(tmp_path / "wide.vrnm"), "w")["method"] == "student 16 wide"
    assert label(pruned, "s")["method"] == "student (16 -> 8 wide)"
    init = pruned.meta["provenance"]["init_from"]
    assert (init["width"], init["epochs"]) == (16, 1)
    assert init["sha256"] == ck["init_from"]["sha256"]
    data = SliceData(read_btf(btf), ck["split"]["test"])
    for path, ckpt in ((tmp_path / "wide.vrnm", wide_ck), (tmp_path / "s.vrnm", ck)):
        net = model_from_checkpoint(ckpt)
        mat = read_vrnm(path)
        wi, wo = data.dirs(3)
        uv = data.uv(None, shard=False)
        n = uv.shape[0]
        with torch.no_grad():
            want = net.predict(wi, wo, uv).numpy()
        tile = (n, 1)
        got = material_forward(
            mat, np.tile(wi.numpy(), tile), np.tile(wo.numpy(), tile), uv.numpy()
        )
        np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-5)
    # a resumed pruned run keeps its weights (no second pruning) and its record, and the
    # same init spelled another way is no contradiction
    again = [
        "distill",
        t,
        "-o",
        s,
        "--resume",
        "--epochs",
        2,
        "--init-from",
        f"{tmp_path}/./wide.pt",
    ]
    code, err = run_cli(*again, *FAST)
    assert code == 0, err
    assert load_checkpoint(s)["init_from"] == ck["init_from"]
    # an unfinished wide run: a one-line warning, then it is used as it is
    unfinished = dict(wide_ck, finished=False)
    save_checkpoint(tmp_path / "unfinished.pt", unfinished)
    argv = ["distill", t, "-o", tmp_path / "u.pt", "--init-from", tmp_path / "unfinished.pt"]
    with pytest.warns(UnfinishedRunWarning, match="starting from it as it is"):
        code, err = run_cli(*argv, "--epochs", 1, *FAST)
    assert code == 0, err


def test_init_from_errors(tmp_path):
    btf = analytic_btf(tmp_path / "m.btf", res=16, n_dirs=4)
    t, t2 = tmp_path / "t.pt", tmp_path / "t2.pt"
    assert run_cli("teach", btf, "-o", t, "--epochs", 1, *FAST)[0] == 0
    assert run_cli("teach", btf, "-o", t2, "--epochs", 1, "--seed", 1, *FAST)[0] == 0
    runs = {
        "s8": ("--width", 8),
        "s4": ("--width", 4),
        "w16s8": ("--method", "single8", "--width", 16),
        "nm": ("--method", "neumip", "--no-distill"),
        "log": ("--space", "log"),
        "s8nd": ("--method", "single8", "--no-distill"),
    }
    for name, flags in runs.items():
        code, err = run_cli(
            "distill", t, "-o", tmp_path / f"{name}.pt", "--epochs", 1, *flags, *FAST
        )
        assert code == 0, err
    code, err = run_cli(
        "distill", t2, "-o", tmp_path / "other.pt", "--epochs", 1, "--width", 16, *FAST
    )
    assert code == 0, err
    from vrneural.scoring.run import label

    for name, want in (("s8nd", "single8 w/o distillation"), ("s4", "student 4 wide")):
        assert label(read_vrnm(tmp_path / f"{name}.vrnm"), name)["method"] == want
    out = tmp_path / "new.pt"
    cases = [
        (["--init-from", tmp_path / "s4.pt"], "is 4 wide, narrower than --width 8"),
        (["--init-from", tmp_path / "w16s8.pt"], "is a single8 run; this run trains student"),
        (["--init-from", tmp_path / "other.pt"], "was distilled from another teacher"),
        (["--init-from", t], "--init-from"),
        (["--init-from", tmp_path / "missing.pt"], "missing.pt"),
        (["--init-from", tmp_path / "nm.pt", "--method", "neumip"], "--init-from prunes"),
        (["--method", "neumip", "--width", 16], "NeuMIP is always 4 x 25"),
        (["--width", 0], "--width"),
        (
            ["--init-from", tmp_path / "s8.pt", "--coarse-channels", 4],
            "was trained with --coarse-channels 8, this run with 4",
        ),
        (
            ["--init-from", tmp_path / "log.pt"],
            "was trained with --space log, this run with linear",
        ),
        (
            ["--init-from", tmp_path / "s8.pt", "--width", 9],
            "needs a run at least 9 wide (train one with --width 18), or ask for --width 8 or less",
        ),
    ]
    for flags, needle in cases:
        expect_one_line_error(["distill", t, "-o", out, "--epochs", 1, *flags, *FAST], needle)
        assert not out.exists()
    # the init is an input: never the output, even with --force
    s8 = tmp_path / "s8.pt"
    before = s8.read_bytes()
    expect_one_line_error(
        ["distill", t, "-o", s8, "--init-from", s8, "--force", *FAST], "would overwrite the input"
    )
    assert s8.read_bytes() == before


def test_wide_start_is_width_then_init_from_in_one_resumable_run(tmp_path, capsys):
    """``distill --wide-start 16 --epochs 3`` trains exactly what ``--width 16 --epochs 1``
    and then ``--init-from`` with ``--epochs 2`` train; Ctrl-C in either half resumes to the
    same weights; every refusal is one line before any work."""
    import signal

    from vrneural.distill.config import DistillConfig
    from vrneural.distill.distill import run_distill
    from vrneural.distill.train import Interrupted

    btf = analytic_btf(tmp_path / "m.btf", res=16, n_dirs=4)
    t, w, p, s = (tmp_path / f"{n}.pt" for n in ("t", "w", "p", "s"))
    assert run_cli("teach", btf, "-o", t, "--epochs", 1, *FAST)[0] == 0
    assert run_cli("distill", t, "-o", w, "--width", 16, "--epochs", 1, *FAST)[0] == 0
    assert run_cli("distill", t, "-o", p, "--init-from", w, "--epochs", 2, *FAST)[0] == 0
    capsys.readouterr()
    code, err = run_cli("distill", t, "-o", s, "--wide-start", 16, "--epochs", 3, *FAST)
    assert code == 0, err
    wide = tmp_path / "s.wide.pt"
    assert f"from {wide} (16 wide, 1 epoch, pruned to 8)" in capsys.readouterr().out
    assert (tmp_path / "s.wide.pt.config.json").is_file() and (tmp_path / "s.vrnm").is_file()
    assert not (tmp_path / "s.wide.vrnm").exists()
    ck, ref = load_checkpoint(s), load_checkpoint(p)
    assert load_checkpoint(wide)["spec"]["fine_hidden"] == [16] and ck["epoch"] == 2
    assert ck["init_from"]["path"] == str(wide) and ck["init_from"]["epochs"] == 1
    for k, v in ref["net"].items():
        assert torch.equal(v, ck["net"][k]), k
    assert [h["test_l1"] for h in ck["history"]] == [h["test_l1"] for h in ref["history"]]

    # Ctrl-C in the wide half, then in the pruned half; each resumed without --epochs (the
    # run's own target, recorded in both halves): the same network
    kw = dict(teacher=str(t), progress=False, max_test_slices=4, wide_start=16)
    r = tmp_path / "r.pt"
    calls = []

    def ctrl_c_at(n):
        def hook(epoch, step):
            calls.append(1)
            if len(calls) == n:
                signal.raise_signal(signal.SIGINT)

        return hook

    with pytest.raises(Interrupted) as stop:
        run_distill(DistillConfig(output=str(r), epochs=3, **kw), on_step=ctrl_c_at(3))
    assert stop.value.path == str(tmp_path / "r.wide.pt") and not r.exists()
    calls.clear()
    steps = len(ck["split"]["train"])  # one epoch of the wide half
    with pytest.raises(Interrupted) as stop:
        run_distill(DistillConfig(output=str(r), resume=True, **kw), on_step=ctrl_c_at(steps + 2))
    assert stop.value.path == str(r) and load_checkpoint(r)["finished"] is False
    assert "pruned half, 8 wide" in str(stop.value) and stop.value.resume == f"-o {r} --resume"
    code, err = run_cli("distill", t, "-o", r, "--resume", *FAST)  # --wide-start is recorded
    assert code == 0, err
    got = load_checkpoint(r)
    assert (got["config"]["wide_start"], got["config"]["wide_start_epochs"]) == (16, 3)
    assert got["epoch"] == 2 and got["config"]["wide_start_width"] == 8
    for k, v in ck["net"].items():
        assert torch.equal(v, got["net"][k]), k
    code, err = run_cli("distill", t, "-o", r, "--resume", *FAST)  # finished: says so
    assert code == 0 and "nothing left to train; a wide start cannot be extended" in err, err

    # --force starts both halves afresh: interrupted in its wide half, the old pruned half
    # is gone, so --resume continues the new run (not the old one's result)
    calls.clear()
    seen = []

    def look_then_ctrl_c(epoch, step):  # at the first step, before the new run's first save
        seen.append([f.name for f in tmp_path.glob("r.*")])
        ctrl_c_at(2)(epoch, step)

    with pytest.raises(Interrupted) as stop:
        run_distill(DistillConfig(output=str(r), epochs=3, force=True, **kw), look_then_ctrl_c)
    assert seen[0] == []  # the old run's files (both halves) are gone as training starts
    assert "wide half, 16 wide" in str(stop.value) and not r.exists()
    assert not (tmp_path / "r.vrnm").exists()
    # a stray file where the pruned half will write: refused before the wide half trains on
    stray = tmp_path / "r.vrnm"
    stray.write_bytes(b"x")
    wide_before = (tmp_path / "r.wide.pt").read_bytes()
    expect_one_line_error(["distill", t, "-o", r, "--resume", *FAST], "r.vrnm: exists")
    assert (tmp_path / "r.wide.pt").read_bytes() == wide_before
    stray.unlink()
    # the wide half is resumed through its run, and flags must match what the run recorded
    expect_one_line_error(
        ["distill", t, "-o", tmp_path / "r.wide.pt", "--resume", *FAST],
        "is the wide half of a --wide-start run",
        f"-o {r} --resume",
    )
    for flags, needle in (
        (["--width", 4], "--width = 4, but"),
        (["--wide-start", 32], "--wide-start = 32, but"),
        (["--epochs", 5], "--epochs = 5, but"),
    ):
        expect_one_line_error(["distill", t, "-o", r, "--resume", *flags, *FAST], needle)
    assert (tmp_path / "r.wide.pt").read_bytes() == wide_before
    with pytest.warns(UnfinishedRunWarning, match=f"its --wide-start run, .* -o {r} --resume"):
        code, err = run_cli("export", tmp_path / "r.wide.pt", "-o", tmp_path / "rw.vrnm")
    assert code == 0, err
    code, err = run_cli("distill", t, "-o", r, "--resume", *FAST)
    assert code == 0, err
    for k, v in ck["net"].items():
        assert torch.equal(v, load_checkpoint(r)["net"][k]), k

    # --no-export is the run's setting, kept when its wide half is resumed; a plain run at the
    # output of an unfinished wide half warns that it leaves that half as it is
    n = tmp_path / "n.pt"
    calls.clear()
    with pytest.raises(Interrupted):
        run_distill(DistillConfig(output=str(n), epochs=2, export=False, **kw), ctrl_c_at(2))
    (tmp_path / "o.wide.pt").write_bytes((tmp_path / "n.wide.pt").read_bytes())
    with pytest.warns(UnfinishedRunWarning, match="unfinished wide half of a --wide-start run"):
        code, err = run_cli("distill", t, "-o", tmp_path / "o.pt", "--epochs", 1, *FAST)
    assert code == 0, err
    expect_one_line_error(["distill", t, "-o", n, "--resume", "--export", *FAST], "--export")
    assert run_cli("distill", t, "-o", n, "--resume", *FAST)[0] == 0
    assert not (tmp_path / "n.vrnm").exists() and not (tmp_path / "n.wide.vrnm").exists()
    assert load_checkpoint(n)["config"]["export"] is False

    # refusals: one line, exit 2, nothing written or changed
    before = {f: f.read_bytes() for f in tmp_path.iterdir() if f.is_file()}
    new = tmp_path / "new.pt"
    cases = [
        ([s, "--wide-start", 16, "--epochs", 3], "s.pt"),
        ([new, "--wide-start", 8], "wider than --width 8"),
        ([new, "--wide-start", 65], "[9, 64]"),
        ([new, "--wide-start", 16, "--method", "neumip", "--no-distill"], "NeuMIP is always"),
        ([new, "--wide-start", 16, "--init-from", w], "pass one of the two"),
        ([new, "--wide-start", 16, "--epochs", 1], "at least 2"),
        ([new, "--wide-start", 16, "--resume"], "nothing to resume"),
        ([s, "--wide-start", 16, "--epochs", 5, "--resume"], "its epochs were split"),
        ([s, "--resume", "--epochs", 5], "--epochs = 5, but", "--wide-start"),
        ([s, "--resume", "--width", 4], "--width = 4, but"),
        ([w, "--wide-start", 32, "--epochs", 2, "--resume"], "was not trained with --wide-start"),
        ([p, "--wide-start", 16, "--epochs", 3, "--resume"], "was not trained with --wide-start"),
        ([s, "--resume", "--force"], "contradict"),
        ([s, "--resume", "--init-from", w], "which started from its own wide half"),
        ([new, "--width", 64, "--wide-start", 65], "64 is the widest"),
    ]
    for flags, *needles in cases:
        expect_one_line_error(["distill", t, "-o", *flags, *FAST], *needles)
    assert {f: f.read_bytes() for f in tmp_path.iterdir() if f.is_file()} == before
