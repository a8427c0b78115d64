"""``vrneural teach``: train the 128-wide teacher ("NeuMIP Max", arch ``single``) on a BTF."""

from __future__ import annotations

import dataclasses

import torch
from torch import nn

from vrneural.btf.format import read_btf
from vrneural.distill.checkpoint import load_checkpoint
from vrneural.distill.config import TeachConfig
from vrneural.distill.data import SliceData, btf_fingerprint, split_pairs
from vrneural.distill.evaluate import mean_l1, space_l1, test_pairs
from vrneural.distill.models import NeuralModel, make_spec
from vrneural.distill.train import compile_networks, dist_setup, fit, train_device
from vrneural.errors import VrnError, check_range


class GroundTruthNet(nn.Module):
    """A model trained on ground truth alone: loss ``L1(y, y_gt)`` in the output's space."""

    def __init__(self, model: NeuralModel, data: SliceData, space: str):
        super().__init__()
        self.model = model
        self.data = data
        self.space = space

    def forward(self, wi, wo, uv, pair):
        raw, _ = self.model(wi, wo, uv)
        loss = space_l1(raw, self.data.target(pair), self.space)
        return loss, {"gt": loss.detach()}


def check_train_config(cfg) -> None:
    check_range("--epochs", cfg.epochs, 1, 100_000)
    check_range("--lr", cfg.lr, 1e-9, 1.0)
    check_range("--test-fraction", cfg.test_fraction, 0.0, 0.9)
    check_range("--lr-factor", cfg.lr_factor, 1e-3, 0.999)
    check_range("--ema", cfg.ema, 0.0, 0.999999)


def outputs_of(output: str, export: bool) -> list[str]:
    """Files a stage writes: the checkpoint and (optionally) its ``.vrnm`` beside it."""
    from pathlib import Path

    p = Path(output)
    return [str(p)] + ([str(p.with_suffix(".vrnm"))] if export else [])


def prepare_outputs(cfg, outputs: list[str]) -> dict | None:
    """Refuse existing outputs without --force; with --resume return the checkpoint to resume."""
    from vrneural.formats.atomic import check_output

    if cfg.resume:
        ck = load_checkpoint(cfg.output)
        return ck
    for o in outputs:
        check_output(o, cfg.force)
    return None


def run_teach(cfg: TeachConfig, on_step=None) -> dict:
    """Train (or resume) a teacher; returns the final checkpoint dict."""
    check_train_config(cfg)
    check_range("--width", cfg.width, 1, 4096)
    check_range("--layers", cfg.layers, 3, 16)
    check_range("--channels", cfg.channels, 1, 64)
    outs = outputs_of(cfg.output, cfg.export)
    resume = prepare_outputs(cfg, outs)
    if resume is not None:
        if resume.get("kind") != "teacher":
            raise VrnError(f"{cfg.output}: is not a teacher checkpoint; cannot --resume teach")
        old = dict(resume["config"])
        old.update(
            epochs=cfg.epochs,
            output=cfg.output,
            btf=cfg.btf,
            resume=True,
            progress=cfg.progress,
            device=cfg.device,
            compile=cfg.compile,
        )
        cfg = TeachConfig(**old)
    btf = read_btf(cfg.btf)
    fp = btf_fingerprint(btf)
    if resume is not None and resume["btf"]["sha256"] != fp["sha256"]:
        raise VrnError(f"{cfg.btf}: BTF differs from the one {cfg.output} was trained on")
    dev = train_device(cfg.device)
    rank, world = dist_setup(cfg.device)
    L, V, H, W = btf.shape
    train, test = split_pairs(L, V, cfg.test_fraction, cfg.split_seed)
    data = SliceData(btf, test, rank, world, device=dev)
    spec = make_spec(
        "teacher", (H, W), cfg.space, width=cfg.width, layers=cfg.layers, channels=cfg.channels
    )
    model = NeuralModel(spec, cfg.seed)
    net = GroundTruthNet(model, data, cfg.space).to(dev)
    compile_networks(cfg.compile, model)
    pairs = test_pairs(data, cfg.max_test_slices)
    payload = {
        "kind": "teacher",
        "method": "teacher",
        "spec": spec,
        "config": dataclasses.asdict(cfg),
        "btf": fp,
        "split": {"train": train, "test": test},
        "versions": {"torch": str(torch.__version__)},
    }
    ck = fit(
        net,
        lambda: mean_l1(model, data, pairs),
        data,
        cfg,
        cfg.output,
        payload,
        resume,
        tex_params=list(model.tex.parameters()),
        on_step=on_step,
    )
    if rank == 0:
        finish_outputs(ck, cfg, data)
    return ck


def finish_outputs(ck: dict, cfg, data: SliceData) -> None:
    """Write ``<output>.config.json`` and (with export) the ``.vrnm`` pack + its config."""
    from vrneural.config import write_config

    extra = {"epochs_done": ck["epoch"], "history": ck["history"], "btf": ck["btf"]}
    write_config(cfg.output, cfg, extra)
    if cfg.export:
        from vrneural.distill.export import export_checkpoint

        pack = outputs_of(cfg.output, True)[1]
        _, meta = export_checkpoint(ck, pack, data=data.on("cpu"), force=True, source=cfg.output)
        write_config(pack, cfg, {**extra, "metrics": meta["metrics"]})
