"""``vrneural teach``: train the 128-wide teacher ("NeuMIP Max", arch ``single``) on a BTF,
on the ground truth alone (loss ``L1(y, y_gt)`` in the output's space)."""

from __future__ import annotations

import dataclasses

import torch

from vrneural.btf.format import read_btf
from vrneural.btf.identity import btf_fingerprint, check_btf_record, split_pairs
from vrneural.config import given, resolved
from vrneural.distill.config import RESUME_FREE, TeachConfig
from vrneural.distill.core import DistillNet
from vrneural.distill.data import SliceData
from vrneural.distill.evaluate import mean_value, test_pairs
from vrneural.distill.models import NeuralModel, make_spec
from vrneural.distill.outputs import (
    clear_outputs,
    finish_outputs,
    outputs_of,
    prepare_outputs,
)
from vrneural.distill.train import compile_networks, dist_setup, fit, train_device
from vrneural.errors import VrnError, check_range, check_seed, count
from vrneural.outputs import output_lock
from vrneural.parallax import setup_parallax


def check_train_config(cfg) -> None:
    check_range("--epochs", cfg.epochs, 1, 100_000)
    check_seed("--seed", cfg.seed)
    check_seed("--split-seed", cfg.split_seed)
    check_range("--lr", cfg.lr, 1e-9, 1.0)
    # > 0: the held-out test L1 drives the lr schedule and the reports
    check_range("--test-fraction", cfg.test_fraction, 1e-6, 0.9)
    check_range("--lr-factor", cfg.lr_factor, 1e-3, 0.999)
    check_range("--lr-min", cfg.lr_min, 0.0, cfg.lr)
    # rel: a fraction of the best L1; abs: L1 units (a huge one makes every epoch a plateau)
    check_range(
        "--lr-threshold", cfg.lr_threshold, 0.0, 1.0 if cfg.lr_threshold_mode == "rel" else 1e6
    )
    check_range("--lr-patience", cfg.lr_patience, 0, 10_000)
    check_range("--tex-lr-scale", cfg.tex_lr_scale, 1e-6, 1e6)
    check_range("--ema", cfg.ema, 0.0, 0.999999)
    check_range("--max-test-slices", cfg.max_test_slices, 0, 10**9)
    check_range("--threads", cfg.threads, 1, 1024)


def resumed_config(
    cfg,
    stored: dict,
    ck: dict,
    epochs_flag: str = "--epochs",
) -> dict:
    """The checkpoint's config with the :data:`~vrneural.distill.config.RESUME_FREE` fields
    taken from ``cfg`` (an unresolved config: a field left None was not given).

    A field given with another value than the checkpoint used (even the default) is an
    error, not silently ignored; so is an ``--epochs`` below the epochs already trained.
    ``epochs_flag`` names the option that sets ``epochs`` in messages ("": none does).
    """

    def shown(k: str) -> str:
        return (epochs_flag if k == "epochs" else "") or "--" + k.replace("_", "-")

    chosen = given(cfg)
    for k in (f.name for f in dataclasses.fields(cfg) if f.name in chosen):
        if k in RESUME_FREE or k in ("force", "btf", "teacher") or k not in stored:
            continue
        now = getattr(cfg, k)
        if now != stored[k]:
            raise VrnError(
                f"{shown(k)} = {now!r}, but {cfg.output} was trained with "
                f"{stored[k]!r}; --resume continues the checkpoint's settings (drop the flag, "
                "or start over: --force instead of --resume)"
            )
    now = resolved(cfg)  # no --epochs: the run's own target (when it has one)
    merged = dict(stored) | {k: getattr(now, k) for k in RESUME_FREE if k != "epochs"}
    merged["epochs"] = cfg.epochs if cfg.epochs is not None else stored.get("epochs", now.epochs)
    done = int(ck["epoch"])
    if merged["epochs"] < done:
        least = done + 1 if int(ck.get("step", 0)) else done  # partway through the next one
        raise VrnError(
            f"{shown('epochs')} = {merged['epochs']}, but {cfg.output} already has "
            f"{count(done, 'epoch')}; pass {shown('epochs')} {least} or more to continue it"
        )
    if merged["epochs"] == done and int(ck.get("step", 0)):  # its weights are past epoch `done`
        raise VrnError(
            f"{shown('epochs')} = {done}, but {cfg.output} stopped partway through epoch "
            f"{done + 1} (step {int(ck['step'])}); pass {shown('epochs')} {done + 1} or more to "
            "continue it"
        )
    return merged


def run_teach(asked: TeachConfig, on_step=None, epochs_flag: str = "--epochs") -> dict:
    """Train (or resume) a teacher; returns the final checkpoint dict. Holds a lock on its
    outputs while it trains (:func:`vrneural.outputs.output_lock`). Fields left None take
    their defaults, or on ``--resume`` the checkpoint's; ``epochs_flag``: the option that
    sets ``asked.epochs``, for messages."""
    with output_lock(asked.output):
        cfg = resolved(asked)
        check_train_config(cfg)
        check_range("--width", cfg.width, 1, 4096)
        check_range("--layers", cfg.layers, 3, 16)
        check_range("--channels", cfg.channels, 1, 64)
        outs = outputs_of(cfg.output, cfg.export)
        resume = prepare_outputs(cfg, outs, inputs=[cfg.btf])
        if resume is not None:
            if resume.get("kind") != "teacher":
                raise VrnError(f"{cfg.output}: is not a teacher checkpoint; cannot --resume teach")
            stored = {"parallax": "off"} | resume["config"]
            old = resumed_config(asked, stored, resume, epochs_flag=epochs_flag)
            cfg = resolved(TeachConfig(**(old | {"btf": cfg.btf})))
        btf = read_btf(cfg.btf)
        fp = btf_fingerprint(btf)
        if resume is not None:
            mismatch = f"differs from the one {cfg.output} was trained on"
            check_btf_record(cfg.btf, fp, resume["btf"], mismatch, "the run began on")
        dev = train_device(cfg.device)
        rank, world = dist_setup(cfg.device)
        L, V, H, W = btf.shape
        train, test = split_pairs(L, V, cfg.test_fraction, cfg.split_seed)
        data = SliceData(btf, test, rank, world, device=dev)
        spec = make_spec(
            "teacher", (H, W), cfg.space, width=cfg.width, layers=cfg.layers, channels=cfg.channels
        )
        recorded = resume.get("parallax") if resume is not None else None
        height, parallax = setup_parallax(cfg, spec, btf, cfg.btf, recorded)
        model = NeuralModel(spec, cfg.seed)
        if height is not None:
            model.set_height(height)
        net = DistillNet(model, None, data, cfg).to(dev)
        compile_networks(cfg.compile, model)
        pairs = test_pairs(data, cfg.max_test_slices)
        payload = {
            "kind": "teacher",
            "method": "teacher",
            "spec": spec,
            "config": dataclasses.asdict(cfg),
            "btf": fp,
            "split": {"train": train, "test": test},
            "parallax": parallax,
            "versions": {"torch": str(torch.__version__)},
            "test_mean": mean_value(data, pairs),  # the L1 of predicting black
        }
        if cfg.force and resume is None and rank == 0:
            clear_outputs(outs)
        ck = fit(net, model, data, pairs, cfg, payload, resume, on_step, epochs_flag)
        if rank == 0:
            finish_outputs(ck, cfg, data, missing_only=ck is resume)
        return ck
