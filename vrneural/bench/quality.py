"""`vrneural bench quality`: the paper's Table 1 (and Fig. 7/8/11/12/13 analogs) on synthetic BTFs.

For each preset: synthesise a BTF, train the teacher, then the five methods at one fixed budget
(the same epochs for every network, all from the same seed and data split):

- ``lafortune``: diffuse + 4 Lafortune lobes per texel, Levenberg-Marquardt (analytic baseline);
- ``neumip``: 7-channel texture, 4 x 25 MLP, log(1+y) output, ground truth only, directions
  as NeuMIP has them (wi.xy, wo.xy; ``--neumip-dirs full`` adds wi.z, wo.z and h);
- ``single8``: one 8-wide 4-layer MLP, distilled (the Fig. 13 ablation);
- ``student_nodistill``: the coarse-to-fine student on ground truth only (the Fig. 11 ablation);
- ``student``: the coarse-to-fine student distilled from the teacher (paper Eq. 5).

``--width W`` makes the single-level net and both students W wide instead of 8.

Whole-BTF L1 is the mean absolute error over every (light, view) pair, texel and channel in
linear BTF units (train and held-out pairs); test L1 uses the held-out pairs only.

``--repeats K`` trains every network but the teacher K times, with seeds ``seed .. seed+K-1``
(initialisation, data order and jitter; the BTF, the split and the teacher stay fixed), and
reports the mean and the range: at small budgets the seed alone moves an 8-wide network's L1 by
about 10%, as much as the differences the targets ask about.
"""

from __future__ import annotations

import dataclasses
import os
import statistics
import time
from functools import partial
from pathlib import Path

from vrneural.bench.quality_btf import btf_path as btf_file
from vrneural.bench.quality_checks import validate
from vrneural.bench.quality_lafortune import lafortune, slice_pairs
from vrneural.bench.quality_parallax import (
    PARALLAX_LABELS,
    VIEW_BINS,
    parallax_record,
    runs_table,
    teachers,
)
from vrneural.bench.quality_report import write_report
from vrneural.bench.quality_train import (
    check_bench_out,
    check_wide_start,
    job_pool,
    load_trained,
    make_btf,
    resume_hint,
    run_jobs,
    run_networks,
    set_resume,
    took,
    train_in_process,
    wide_start_record,
    with_wide_start,
)
from vrneural.bench.train_configs import QualityConfig
from vrneural.btf.format import read_btf
from vrneural.btf.identity import btf_fingerprint
from vrneural.config import config_dict
from vrneural.distill.config import DistillConfig, TeachConfig
from vrneural.outputs import file_sha256, write_json
from vrneural.scoring.score import score
from vrneural.versions import package_versions

METHODS = ("lafortune", "neumip", "single8", "student_nodistill", "student")
LABELS = {
    "teacher": "Teacher (NeuMIP Max, 128)",
    "lafortune": "Lafortune (4 lobes)",
    "neumip": "NeuMIP (4x25)",
    "single8": "Single-level 8-wide",
    "student_nodistill": "Ours w/o distillation",
    "student": "Ours (coarse-to-fine, distilled)",
}


def labels(width: int = 8) -> dict[str, str]:
    """The methods' names in the reports; with ``--width W`` (not 8) the three networks it
    sets say so: ``Single-level 12-wide``, ``Ours (coarse-to-fine, distilled, 12 wide)``."""
    if width == 8:
        return dict(LABELS) | PARALLAX_LABELS
    out = dict(LABELS, single8=f"Single-level {width}-wide") | PARALLAX_LABELS
    out["student_nodistill"] = f"Ours w/o distillation ({width} wide)"
    out["student"] = f"Ours (coarse-to-fine, distilled, {width} wide)"
    return out


RUNS = {
    "neumip": dict(method="neumip", distill=False),
    "single8": dict(method="single8"),
    "student_nodistill": dict(method="student", distill=False),
    "student": dict(method="student"),
}


def _common(cfg: QualityConfig) -> dict:
    return dict(progress=cfg.progress, max_test_slices=0, device=cfg.device, compile=cfg.compile)


def _teach_config(
    preset: str,
    cfg: QualityConfig,
    root: Path,
    btf_path: Path,
    btf_sha: str | None,
    stem: str = "teacher",
    parallax: str = "off",
):
    """The teacher's config (``stem``: its file, ``parallax``: teach --parallax); ``resume``
    where ``--resume`` finds its checkpoint (it must match)."""
    tcfg = TeachConfig(
        btf=str(btf_path),
        output=str(root / preset / f"{stem}.pt"),
        epochs=cfg.teacher_epochs,
        seed=cfg.seed,
        parallax=parallax,
        **_common(cfg),
    )
    set_resume(tcfg, cfg.resume, btf_sha=btf_sha)
    return tcfg


def _distill_configs(
    preset: str, cfg: QualityConfig, root: Path, btf_path: Path, check_teacher: bool = True
) -> list:
    """``(name, stem, config)`` of every network and seed of a preset (its teacher trained;
    ``check_teacher=False`` skips comparing it with the teacher each checkpoint was made from,
    for the check before any work, when the teacher may not exist yet)."""
    d = root / preset
    out = []
    for name, kw in runs_table(cfg, RUNS).items():
        tstem = kw.get("teacher", "teacher")
        tsha = file_sha256(d / f"{tstem}.pt") if check_teacher else None
        neumip = kw.get("method") == "neumip"  # 4 x 25 (and its parallax variant), never pruned
        width, wide = (None, 0) if neumip else (cfg.width, cfg.wide_start)
        for seed in range(cfg.seed, cfg.seed + cfg.repeats):
            # the first seed keeps the plain name, so a one-seed run's checkpoints are reused
            stem = name if seed == cfg.seed else f"{name}.seed{seed}"
            out += network_runs(
                cfg, d, btf_path, tsha, name, stem, dict(kw, seed=seed), width, wide
            )
    return out


def network_runs(
    cfg, d: Path, btf_path: Path, tsha, name: str, stem: str, kw: dict, width, wide_start: int
) -> list:
    """``(name, stem, config)`` of one network of a bench (``kw``: method, seed, ...; ``width``
    None for NeuMIP), trained for ``cfg.epochs`` into ``d/stem.pt``: one run, or with
    ``wide_start`` two, the wide half first (name None) ``wide_start`` wide for half the
    epochs into ``d/stem.wide.pt``, then the network pruned from it to ``width``. A resumed
    run must match (``set_resume``; ``tsha``: the teacher's hash, None to skip it)."""
    out = []
    size = {} if width is None else {"width": width}
    wide_epochs = cfg.epochs // 2 if wide_start else 0
    if wide_start:
        wide_pt = d / f"{stem}.wide.pt"
        wide = _network_config(
            cfg, d, btf_path, wide_pt, **kw, epochs=wide_epochs, width=wide_start, export=False
        )
        set_resume(wide, cfg.resume, teacher_sha=tsha)
        out.append((None, f"{stem}.wide", wide))
        if cfg.resume:
            check_wide_start(d / f"{stem}.pt", wide_epochs, cfg.epochs)
        size["init_from"] = str(wide_pt)
    dcfg = _network_config(
        cfg, d, btf_path, d / f"{stem}.pt", **kw, epochs=cfg.epochs - wide_epochs, **size
    )
    set_resume(dcfg, cfg.resume, teacher_sha=tsha)
    out.append((name, stem, dcfg))
    return out


def _network_config(cfg: QualityConfig, d: Path, btf_path: Path, output, **kw):
    """The `distill` config of one network of the bench (``kw``: method, seed, epochs, ...)."""
    from vrneural.distill.distill import resolve_method

    kw = dict(kw)
    kw.setdefault("parallax", "off")  # the bench's networks: parallax only where it asks
    if kw.get("method") == "neumip":  # given to the others, it would be refused as unused
        kw["neumip_dirs"] = cfg.neumip_dirs
    return resolve_method(
        DistillConfig(
            teacher=str(d / f"{kw.pop('teacher', 'teacher')}.pt"),
            output=str(output),
            btf=str(btf_path),  # not the teacher's record: OUT may have moved
            ema=cfg.ema,
            lr_patience=cfg.lr_patience,
            **kw,
            **_common(cfg),
        )
    )


def _train_parallel(presets: list[str], cfg: QualityConfig, root: Path, log) -> None:
    """``--jobs N``: synthesise, then train every teacher, then every other network, N
    processes at a time; the evaluation afterwards finds them finished and reuses them."""
    quiet = dataclasses.replace(cfg, progress=False)
    btfs = {p: btf_file(p, cfg, root) for p in presets}
    with job_pool(cfg.jobs) as pool:
        run_jobs(pool, [(f"{p}: btf", "synth", (p, quiet, btfs[p])) for p in presets], log)
        teach = []
        for p in presets:
            (root / p).mkdir(parents=True, exist_ok=True)
            sha = btf_fingerprint(read_btf(btfs[p]))["sha256"]
            for stem, par in teachers(cfg):
                c = _teach_config(p, quiet, root, btfs[p], sha, stem, par)
                teach.append((f"{p}: {stem}", "teach", c))
        run_jobs(pool, teach, log)
        runs = [
            (p, n, stem, c)
            for p in presets
            for n, stem, c in _distill_configs(p, quiet, root, btfs[p])
        ]
        run_networks(pool, [(f"{p}: {stem}", n, c) for p, n, stem, c in runs], log)


def bench_material(preset: str, cfg: QualityConfig, root: Path, log, trained: bool = False) -> dict:
    """Train and evaluate every method on one preset; returns its records. ``trained``: the
    ``--jobs`` workers trained them all, so only load them."""
    from vrneural.distill.checkpoint import model_from_checkpoint
    from vrneural.distill.data import SliceData, from_blocks
    from vrneural.distill.evaluate import mean_l1, predict_slice

    d = root / preset
    d.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    btf_path = make_btf(preset, cfg, btf_file(preset, cfg, root))
    synth_s = time.perf_counter() - t0
    btf = read_btf(btf_path)
    sha = btf_fingerprint(btf)["sha256"]
    tcfgs = [_teach_config(preset, cfg, root, btf_path, sha, *t) for t in teachers(cfg)]
    tcfg = tcfgs[0]
    runs = partial(_distill_configs, preset, cfg, root, btf_path)  # they read the teacher
    if trained:
        tck, done = load_trained(tcfg, runs, tcfgs[1:])
    else:
        tck, done = train_in_process(preset, tcfg, runs, log, tcfgs[1:])
    records = {"teacher": [tck]}
    for name, ck, init_from in done:
        records.setdefault(name, []).append(with_wide_start(ck, init_from))
    data = SliceData(btf, tck["split"]["test"])
    every = list(range(len(data.train) + len(data.test)))
    slices = slice_pairs(data)
    out: dict = {"btf": tck["btf"], "synth_seconds": synth_s, "methods": {}, "slices": {}}
    gt = [data.target(p, shard=False) for p in slices]
    out["slices"]["ground truth"] = [from_blocks(g, data.res).numpy() for g in gt]

    for name, cks in records.items():
        models = [model_from_checkpoint(ck) for ck in cks]
        mats = [m.to_material() for m in models]  # the packs' materials, one per seed
        mat = mats[0]
        whole = [mean_l1(m, data, every) for m in models]
        test = [mean_l1(m, data, data.test) for m in models]
        # PSNR and SSIM of every slice as displayed (`vrneural eval`'s definitions), per seed
        shown = score(mats, btf, every, ["f32"])["scores"]
        psnr = [s[0]["psnr_db"] for s in shown]
        ssim = [s[0]["ssim"] for s in shown]
        out["methods"][name] = {
            "whole_l1": statistics.fmean(whole),
            "test_l1": statistics.fmean(test),
            "whole_l1_seeds": whole,
            "test_l1_seeds": test,
            "psnr_db": statistics.fmean(psnr),
            "ssim": statistics.fmean(ssim),
            "psnr_db_seeds": psnr,
            "ssim_seeds": ssim,
            "seeds": [int(ck["config"]["seed"]) for ck in cks],
            "train_seconds": statistics.fmean(ck["train_seconds"] for ck in cks),
            "epoch_seconds_median": statistics.median(
                h["seconds"] for ck in cks for h in ck["history"]
            ),
            "epochs": cks[0]["epoch"],
            "devices": sorted({str(ck["config"].get("device", "cpu")) for ck in cks}),
            "curve": [h["test_l1"] for h in cks[0]["history"]],
            "curves": [[h["test_l1"] for h in ck["history"]] for ck in cks],
            "weight_bytes": mat.weight_bytes,
            "texture_bytes": mat.texture_bytes,
            "storage_bytes": mat.weight_bytes + mat.texture_bytes,
            "macs_per_texel": mat.macs_per_texel,
            "wide_start": wide_start_record(cks[0]),
            **parallax_record(models, mat, data, every),  # view-angle bins, fetches, parallax
        }
        out["slices"][name] = [predict_slice(models[0], data, p).numpy() for p in slices]
    out["methods"]["lafortune"], reused = lafortune(
        data, every, slices, cfg, out, d / "lafortune.npz", tck["btf"]["sha256"]
    )
    out["view_bins"] = [list(b) for b in VIEW_BINS]
    log(f"{preset}: lafortune  {took(out['methods']['lafortune'], reused)}")
    out["slice_pairs"] = slices
    return out


def _check_resumable(presets: list[str], cfg: QualityConfig, root: Path) -> None:
    """Before any work: every checkpoint that ``--resume`` would meet is readable and was
    trained with this run's settings (the BTF and teacher hashes are compared later, once
    the BTFs exist), so a mismatch stops the run before hours of other presets."""
    for p in presets:
        btf_path = btf_file(p, cfg, root)
        for t in teachers(cfg):
            _teach_config(p, cfg, root, btf_path, None, *t)
        _distill_configs(p, cfg, root, btf_path, check_teacher=False)


def run_quality(cfg: QualityConfig) -> dict:
    """Run the benchmark; writes results.json, results.md, curves.png, slices.png in ``out``."""
    cfg = cfg.resolved()
    presets = validate(cfg)
    root = Path(cfg.out)
    od = check_bench_out(root, cfg, "bench quality", "report")
    if cfg.resume:
        _check_resumable(presets, cfg, root)
    with od, resume_hint(root):
        od.open()  # its checkpoints stay in it
        return _run(presets, cfg, root)


def _run(presets: list[str], cfg: QualityConfig, root: Path) -> dict:
    results, slices, t_all = {}, {}, time.perf_counter()
    if cfg.jobs > 1:
        _train_parallel(presets, cfg, root, print)
        cfg = dataclasses.replace(cfg, resume=True)  # evaluate what was just trained
    doc: dict = {}
    for preset in presets:
        r = bench_material(preset, cfg, root, print, trained=cfg.jobs > 1)
        slices[preset] = (r.pop("slices"), r["slice_pairs"])
        results[preset] = r
        doc = {
            "benchmark": "quality",
            "config": config_dict(cfg),
            "versions": package_versions(),
            "machine": {"cpu_count": os.cpu_count(), "torch_threads": 1},
            "total_seconds": time.perf_counter() - t_all,
            "complete": len(results) == len(presets),
            "materials": presets,
            "labels": labels(cfg.width),
            "results": results,
        }
        write_json(root / "results.json", doc)  # after every material: partial results
        write_report(doc, slices, root)
    return doc
