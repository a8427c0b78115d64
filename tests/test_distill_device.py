"""``--device``: a bad or absent device is a one-line error; on CUDA (where present) the
trainers give the CPU result to float tolerance and the pack is exported from the CPU copy."""

from __future__ import annotations

import json

import pytest
import torch
from distill_helpers import FAST, analytic_btf, run_cli

from vrneural.btf.format import read_btf
from vrneural.distill.checkpoint import load_checkpoint
from vrneural.distill.data import SliceData

has_cuda = torch.cuda.is_available()


def _one_line_error(argv, needle):
    code, err = run_cli(*argv)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0], err


@pytest.mark.parametrize(
    ("device", "needle"),
    [
        ("gpu", "expected cpu, cuda or cuda:N"),
        ("cuda:x", "expected cpu, cuda or cuda:N"),
        ("cuda:99", "CUDA device 99 requested" if has_cuda else "CUDA is not available"),
    ],
)
def test_bad_device_is_one_line_and_writes_nothing(tmp_path, device, needle):
    btf = analytic_btf(tmp_path / "m.btf", res=8, n_dirs=3)
    out = tmp_path / "t.pt"
    _one_line_error(["teach", btf, "-o", out, "--device", device, *FAST], needle)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.btf"]


def test_slice_data_on_shares_the_cpu_copy(tmp_path):
    data = SliceData(read_btf(analytic_btf(tmp_path / "m.btf", res=8, n_dirs=3)), [0, 4])
    same = data.on("cpu")
    assert same.values is data.values and same.train == data.train
    for pair in (1, 7):
        assert torch.equal(same.target(pair), data.target(pair))
        assert all(torch.equal(a, b) for a, b in zip(same.dirs(pair), data.dirs(pair), strict=True))
    gen = [torch.Generator().manual_seed(3) for _ in range(2)]
    assert torch.equal(same.uv(gen[0]), data.uv(gen[1]))


@pytest.mark.skipif(not has_cuda, reason="no CUDA device (run on a GPU machine)")
def test_cuda_matches_cpu_and_exports(tmp_path):
    btf = analytic_btf(tmp_path / "m.btf", res=16, n_dirs=5)
    hist = {}
    for dev in ("cpu", "cuda"):
        t, s = tmp_path / f"teacher-{dev}.pt", tmp_path / f"student-{dev}.pt"
        code, err = run_cli("teach", btf, "-o", t, "--epochs", 2, "--device", dev, *FAST)
        assert code == 0, err
        code, err = run_cli("distill", t, "-o", s, "--epochs", 2, "--device", dev, *FAST)
        assert code == 0, err
        hist[dev] = [load_checkpoint(p)["history"] for p in (t, s)]
        meta = json.loads(s.with_name(f"student-{dev}.vrnm.config.json").read_text())
        assert meta["metrics"]["pack_vs_torch_max_abs"] < 1e-5
    for a, b in zip(hist["cpu"], hist["cuda"], strict=True):
        for ha, hb in zip(a, b, strict=True):
            assert hb["test_l1"] == pytest.approx(ha["test_l1"], rel=0.02)
    # a CUDA run resumes on the device given now (the default: the CPU)
    s = tmp_path / "student-cuda.pt"
    code, err = run_cli("distill", tmp_path / "teacher-cuda.pt", "-o", s, "--resume", "--epochs", 4)
    assert code == 0, err
    ck = load_checkpoint(s)
    assert ck["epoch"] == 4 and ck["config"]["device"] == "cpu"
    assert ck["history"][-1]["test_l1"] < ck["history"][1]["test_l1"] * 1.5


def test_compiled_training_equals_eager(tmp_path):
    """``--compile default`` fuses kernels (inductor's C++ backend on the CPU) without changing
    the result beyond float reassociation; the pack is exported from the plain network."""
    btf = analytic_btf(tmp_path / "m.btf", res=8, n_dirs=4)
    hist = {}
    for mode in ("off", "default"):
        t = tmp_path / f"t-{mode}.pt"
        code, err = run_cli("teach", btf, "-o", t, "--epochs", 2, "--compile", mode, *FAST)
        assert code == 0, err
        hist[mode] = [h["test_l1"] for h in load_checkpoint(t)["history"]]
        meta = json.loads(t.with_name(f"t-{mode}.vrnm.config.json").read_text())
        assert meta["metrics"]["pack_vs_torch_max_abs"] < 1e-5
    assert hist["default"] == pytest.approx(hist["off"], rel=1e-3)


def test_compiling_many_networks_in_one_process_stays_compiled():
    """``bench quality --jobs 1 --compile`` trains every network in one process. They share
    ``NeuralModel.forward``'s code; its compiled variants must not pile up to dynamo's limit
    (8), past which the later networks silently ran eagerly. Tracing with the "eager" backend
    exercises the same caches and guards as inductor, without its code generation."""
    from torch._dynamo.eval_frame import _debug_get_cache_entry_list

    from vrneural.distill.models import NeuralModel, make_spec
    from vrneural.distill.train import compile_networks

    code = NeuralModel.forward.__code__
    wi = torch.tensor([0.0, 0.6, 0.8])
    wo = torch.tensor([0.6, 0.0, 0.8])
    uv = torch.rand(16, 4, 2)
    teacher = NeuralModel(make_spec("teacher", (8, 8)), 0)
    for seed, method in enumerate(["neumip", "single8", "student", "student", "single8"]):
        model = NeuralModel(make_spec(method, (8, 8)), seed)
        compile_networks("default", model, teacher, backend="eager")
        for _ in range(2):
            model(wi, wo, uv)[0].sum().backward()  # training step
            with torch.no_grad():
                model(wi, wo, uv)  # per-epoch test
                teacher(wi, wo, uv)  # the teacher's hints
        assert len(_debug_get_cache_entry_list(code)) <= 3, method
    torch.compiler.reset()
