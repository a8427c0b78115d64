"""`bench quality`'s option checks: every option checked before anything is synthesised,
trained or written, with the ranges the stages would check later."""

from __future__ import annotations

import dataclasses

from vrneural.bench.quality_btf import check_given
from vrneural.bench.quality_parallax import bench_kinds, check_parallax_data
from vrneural.btf.synth import BtfConfig
from vrneural.config import resolved
from vrneural.distill.config import DistillConfig, TrainBudget
from vrneural.errors import VrnError, check_range, check_seed
from vrneural.outputs import check_resume_force


def validate(cfg) -> list[str]:
    """Check every option before anything is synthesised, trained or written (the checks the
    stages would make later, with their ranges); returns the presets."""
    from vrneural.distill.teach import check_train_config
    from vrneural.distill.train import train_device

    if not cfg.out:
        raise VrnError("--out is empty; pass an output directory")
    check_resume_force(cfg.resume, cfg.force)
    given = check_given(cfg)
    presets = list(cfg.presets)
    if not presets and not given:
        raise VrnError("--presets is empty (and no --btf file given)")
    twice = sorted({p for p in presets if presets.count(p) > 1})
    if twice:
        raise VrnError(f"--presets names {', '.join(twice)} more than once")
    for k in ("teacher_epochs", "epochs", "repeats", "lafortune_iters"):
        check_range(f"--{k.replace('_', '-')}", getattr(cfg, k), 1, 10_000)
    check_range("--jobs", cfg.jobs, 1, 256)
    check_range("--width", cfg.width, 1, 64)
    if cfg.wide_start:
        if not cfg.width < cfg.wide_start <= 64:
            raise VrnError(
                f"--wide-start {cfg.wide_start}: 0 (off) or a width in [{cfg.width + 1}, 64], "
                f"wider than --width {cfg.width}"
            )
        if cfg.epochs < 2:
            raise VrnError(
                f"--epochs {cfg.epochs} with --wide-start: half the epochs go to the wide start, "
                "so at least 2 are needed"
            )
    for p in presets:  # --preset, --res, --dirs, --seed as `btf synth` checks them
        BtfConfig(preset=p, res=cfg.res, dirs=cfg.dirs, seed=cfg.seed).validate(
            {"preset": "--presets"}
        )
    if "height" in bench_kinds(cfg):
        check_parallax_data(presets, given, cfg.parallax)
    presets = presets + list(given)  # the given BTFs, labelled by file name
    check_seed("--seed + --repeats - 1", cfg.seed + cfg.repeats - 1)
    shared = {f.name: getattr(cfg, f.name) for f in dataclasses.fields(TrainBudget)}
    check_train_config(resolved(DistillConfig(epochs=cfg.epochs, **shared)))  # as distill does
    train_device(cfg.device)
    return presets
