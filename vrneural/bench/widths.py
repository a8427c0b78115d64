"""`vrneural bench widths`: what the student's width costs and what it buys.

One synthetic preset and one teacher. The ``--methods`` networks (default: the coarse-to-fine
student; also the single-level net and the student without distillation) are trained at each
of ``--widths``:
from random weights (``plain``) and/or with a wide start (``wide``: 2W wide for the first half
of the epochs, then pruned to W, what ``distill --wide-start 2W`` does), ``--repeats`` seeds
each. NeuMIP (4 x 25, its own inputs) is the reference. Every network gets the same epochs,
seeds, data split and teacher, as in `bench quality`.

Reported per network: whole-BTF L1 (every (light, view) pair, linear units; mean and standard
deviation over the seeds), against the MLP multiply-adds per texel and the weight bytes of its
runtime network, and the narrowest width of each family within 10% of NeuMIP. Writes
results.json, results.md and widths.png (L1 against multiply-adds). `vrneural bench kernels
--networks student:W,single8:W` times the same networks on the GPU (wgpu). The defaults are the
width sweep of docs/quality-research.md.
"""

from __future__ import annotations

import dataclasses
import json
import os
import statistics
import time
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np

from vrneural.bench.quality import _teach_config
from vrneural.bench.quality import network_runs as one
from vrneural.bench.quality_checks import validate as quality_validate
from vrneural.bench.quality_train import (
    check_bench_out,
    job_pool,
    load_trained,
    make_btf,
    resume_hint,
    run_jobs,
    run_networks,
    train_in_process,
    with_wide_start,
)
from vrneural.bench.train_configs import METHODS, QualityConfig, WidthsConfig
from vrneural.bench.widths_report import within, write_report
from vrneural.btf.format import read_btf
from vrneural.btf.identity import btf_fingerprint
from vrneural.btf.synth import BtfConfig
from vrneural.config import config_dict
from vrneural.errors import VrnError, check_range, check_seed
from vrneural.outputs import file_sha256, write_json
from vrneural.versions import package_versions

#: --wide-start trains 2W wide, and distill's widths end at 64
MAX_WIDE = 32


@dataclass(frozen=True)
class Plan:
    """What one run trains: the parsed lists, and the `bench quality` config its shared
    stages (BTF, teacher, one network) take."""

    widths: tuple[int, ...]
    methods: tuple[str, ...]
    starts: tuple[str, ...]
    quality: object


def validate(cfg: WidthsConfig) -> Plan:
    """Every option, before anything is synthesised, trained or written."""
    check_seed("--seed", cfg.seed)
    BtfConfig(preset=cfg.preset).validate({"preset": "--preset"})  # one preset, as it is
    widths, methods, starts = tuple(sorted(cfg.widths)), cfg.methods, cfg.starts
    if "wide" in starts:
        too = [w for w in widths if w > MAX_WIDE]
        if too:
            raise VrnError(
                f"--widths {too[0]} with --starts wide: a wide start trains 2W wide and "
                f"distill's widths end at 64, so each width must be at most {MAX_WIDE}"
            )
        if cfg.epochs < 2:
            raise VrnError(
                f"--epochs {cfg.epochs} with --starts wide: half the epochs go to the wide "
                "start, so at least 2 are needed"
            )
    check_range("--repeats", cfg.repeats, 1, 100)
    # the fields the bench quality config it runs takes from this one
    shared = ("out", "res", "dirs", "teacher_epochs", "epochs", "seed", "repeats", "device")
    shared += ("compile", "jobs", "progress", "force", "resume")
    q = QualityConfig(presets=(cfg.preset,), **{k: getattr(cfg, k) for k in shared}).resolved()
    try:  # --out, --resume/--force, the seeds and the ranges of the options both share
        quality_validate(q)
    except VrnError as e:
        raise VrnError(str(e).replace("--presets", "--preset")) from None
    return Plan(widths, methods, starts, q)


def _key(method: str, width: int | None, start: str) -> str:
    """The network's row in results.json (``neumip``, ``student:12:wide``, ...)."""
    return "neumip" if method == "neumip" else f"{method}:{width}:{start}"


def network_runs(plan: Plan, root: Path, btf_path: Path, check_teacher: bool = True) -> list:
    """``((method, width, start), stem, config)`` of every network and seed (wide halves: None
    instead of the triple), in an order one process can train them in."""
    q = plan.quality
    d = root / q.presets[0]
    tsha = file_sha256(d / "teacher.pt") if check_teacher else None
    out = []
    for seed in range(q.seed, q.seed + q.repeats):
        kw = dict(method="neumip", distill=False, seed=seed)
        out += one(q, d, btf_path, tsha, ("neumip", None, "plain"), f"neumip-s{seed}", kw, None, 0)
        for m in plan.methods:
            for start in plan.starts:
                for w in plan.widths:
                    stem = f"{m}-w{w}{f'-from{2 * w}' if start == 'wide' else ''}-s{seed}"
                    kw = dict(METHODS[m][0], seed=seed)
                    wide = 2 * w if start == "wide" else 0
                    out += one(q, d, btf_path, tsha, (m, w, start), stem, kw, w, wide)
    return out


def run_widths(cfg: WidthsConfig) -> dict:
    """Run the sweep; writes results.json, results.md and widths.png in ``out``."""
    cfg = cfg.resolved()
    plan = validate(cfg)
    root = Path(cfg.out)
    od = check_bench_out(root, cfg, "bench widths", "sweep")
    _check_same_preset(cfg, root)
    if cfg.resume:  # every checkpoint it would meet matches, before any work
        btf_path = root / "btf" / f"{cfg.preset}.btf"
        _teach_config(cfg.preset, plan.quality, root, btf_path, None)
        network_runs(plan, root, btf_path, check_teacher=False)
    with od, resume_hint(root):
        od.open()
        return _run(cfg, plan, root)


def _check_same_preset(cfg: WidthsConfig, root: Path) -> None:
    """One sweep per OUT: ``--resume`` in the OUT of another preset's sweep would replace
    that sweep's report (``--force`` replaces it on purpose)."""
    try:
        have = json.loads((root / "results.json").read_text())["config"]["preset"]
    except (OSError, ValueError, KeyError, TypeError):
        return
    if have != cfg.preset and not cfg.force:
        raise VrnError(
            f"{root}: holds the width sweep of preset {have}, not {cfg.preset}; use another "
            f"--out for {cfg.preset} (or --force to replace that sweep's report)"
        )


def _train(plan: Plan, root: Path, log) -> tuple[dict, list]:
    """Synthesise the BTF, train the teacher and every network (``--jobs`` processes at a
    time); returns the teacher's checkpoint and ``(key, final checkpoint)`` of each network."""
    q, preset = plan.quality, plan.quality.presets[0]
    (root / preset).mkdir(parents=True, exist_ok=True)
    btf_path = make_btf(preset, q, root / "btf" / f"{preset}.btf")
    sha = btf_fingerprint(read_btf(btf_path))["sha256"]
    tcfg = _teach_config(preset, q, root, btf_path, sha)
    if q.jobs == 1:
        return train_in_process(preset, tcfg, partial(network_runs, plan, root, btf_path), log)
    quiet = dataclasses.replace(q, progress=False)
    tcfg.progress = False
    with job_pool(q.jobs) as pool:
        run_jobs(pool, [(f"{preset}: teacher", "teach", tcfg)], log)
        runs = network_runs(dataclasses.replace(plan, quality=quiet), root, btf_path)
        run_networks(pool, [(f"{preset}: {s}", k, c) for k, s, c in runs], log)
    return load_trained(tcfg, lambda: runs)


def _run(cfg: WidthsConfig, plan: Plan, root: Path) -> dict:
    from vrneural.distill.checkpoint import model_from_checkpoint
    from vrneural.distill.data import SliceData
    from vrneural.distill.evaluate import mean_l1

    t0 = time.perf_counter()
    tck, done = _train(plan, root, print)
    btf = read_btf(root / "btf" / f"{cfg.preset}.btf")
    data = SliceData(btf, tck["split"]["test"])
    every = list(range(len(data.train) + len(data.test)))
    # what an all-black output scores: a network at or above it has learned nothing
    zero = float(np.abs(btf.values).mean(dtype=np.float64))
    rows: dict = {}
    for key, ck, wide_path in done:
        model = model_from_checkpoint(ck)
        mat = model.to_material()
        whole = with_wide_start(ck, wide_path)  # both halves' seconds and epochs
        method, width, start = key
        r = rows.setdefault(
            _key(*key),
            {
                "method": method,
                "width": width,
                "start": start,
                "macs_per_texel": mat.macs_per_texel,
                "weight_bytes": mat.weight_bytes,
                "texture_bytes": mat.texture_bytes,
                "seeds": [],
                "whole_l1_seeds": [],
                "test_l1_seeds": [],
                "train_seconds_seeds": [],
            },
        )
        r["seeds"].append(int(ck["config"]["seed"]))
        r["whole_l1_seeds"].append(mean_l1(model, data, every))
        r["test_l1_seeds"].append(mean_l1(model, data, data.test))
        r["train_seconds_seeds"].append(float(whole["train_seconds"]))
    for r in rows.values():
        s = r["whole_l1_seeds"]
        r["whole_l1"] = statistics.fmean(s)
        r["whole_l1_sd"] = statistics.stdev(s) if len(s) > 1 else 0.0
        r["test_l1"] = statistics.fmean(r["test_l1_seeds"])
    doc = {
        "benchmark": "widths",
        "config": config_dict(cfg),
        "versions": package_versions(),
        "machine": {"cpu_count": os.cpu_count()},
        "teacher": {
            "epochs": int(tck["epoch"]),
            "whole_l1": mean_l1(model_from_checkpoint(tck), data, every),
        },
        "btf": tck["btf"],
        "pairs": len(every),
        "zero_output_l1": zero,
        "total_seconds": time.perf_counter() - t0,
        "rows": rows,
        "within_10pct": narrowest(rows, plan),
    }
    write_json(root / "results.json", doc)
    write_report(doc, root)
    return doc


def narrowest(rows: dict, plan: Plan) -> dict:
    """Per ``method:start`` family: the narrowest width whose seed mean is within 10% of
    NeuMIP's (None where none is)."""

    nm = rows["neumip"]
    out = {}
    for m in plan.methods:
        for start in plan.starts:
            ok = [w for w in plan.widths if within(rows[_key(m, w, start)], nm)]
            out[f"{m}:{start}"] = ok[0] if ok else None
    return out
