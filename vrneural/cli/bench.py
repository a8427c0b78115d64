"""`vrneural bench <benchmark>`: benchmarks that write JSON + Markdown + PNG.

A group: each benchmark is a subcommand registered in :data:`BENCHMARKS` (name -> register
function), so later benchmarks add one entry and one function.
"""

from __future__ import annotations

from pathlib import Path

from vrneural.bench.configs import ExtremesConfig, RuntimeConfig
from vrneural.bench.entries import ENTRIES, add_bench
from vrneural.bench.train_configs import QualityConfig, WidthsConfig
from vrneural.config import config_from_args

_EVERY = "of every network but the teacher"
#: `bench quality`'s own words for the fields it shares with distill (TrainBudget, ...)
QUALITY_HELPS = {
    "seed": "seed of synthesis, initialisation, data order and texture-lookup jitter",
    "ema": f"weight-average decay {_EVERY} (distill --ema; 0 = off)",
    "lr_patience": f"ReduceLROnPlateau patience {_EVERY} (distill --lr-patience; see "
    "docs/quality-research.md on a gentler schedule)",
    "device": "train on cpu, cuda or cuda:N (teach/distill --device)",
    "compile": "torch.compile the networks: off, default or reduce-overhead "
    "(teach/distill --compile)",
    "neumip_dirs": "NeuMIP's direction inputs: xy (NeuMIP's own) or full (wi, wo, h, as "
    "the student)",
    "width": "hidden width of the single-level net and both students (distill --width; "
    "the paper's 8; see the width sweep in docs/quality-research.md)",
    "wide_start": "train the single-level net and both students this wide for the first "
    "half of --epochs, then prune them to --width for the rest (distill --wide-start; "
    "0 = off, from random weights)",
}


def _run_quality(args) -> int:
    from vrneural.bench.quality import run_quality  # each bench, when it runs

    doc = run_quality(config_from_args(QualityConfig, args))
    print(
        f"{args.out}: results.json, results.md, curves.png, slices.png "
        f"({doc['total_seconds'] / 60:.1f} min)"
    )
    return 0


def _run_widths(args) -> int:
    from vrneural.bench.widths import run_widths

    doc = run_widths(config_from_args(WidthsConfig, args))
    print(f"{args.out}: results.json, results.md, widths.png ({doc['total_seconds'] / 60:.1f} min)")
    return 0


def _run_extremes(args) -> int:
    from vrneural.bench.extremes import run_extremes

    doc = run_extremes(config_from_args(ExtremesConfig, args), args.out)
    png = ", f16_error.png" if (Path(args.out) / "f16_error.png").is_file() else ""
    print(
        f"bench extremes: {args.out}/ results.json, results.md{png} "
        f"({doc['n_fail']} FAIL, {doc['total_seconds']:.0f} s)"
    )
    return 1 if doc["n_fail"] else 0


def _run_runtime(args) -> int:
    from vrneural.bench.runtime import HEADLINES, headline, run_runtime

    doc = run_runtime(config_from_args(RuntimeConfig, args), args.out)
    print(f"bench runtime: {args.out}/ results.json, results.md ({doc['total_seconds']:.0f} s)")
    for name, paths in HEADLINES.items():
        if name in doc:
            print(f"  {name}: {headline(doc[name], paths)}")
    return 0


#: name -> register(sub), in `--help` order
BENCHMARKS = {
    "quality": lambda sub: add_bench(
        sub,
        "quality",
        QualityConfig,
        _run_quality,
        "Table 1 analog: whole-BTF L1 of the student and baselines per material",
        "Synthesise each preset's BTF, train the teacher and the five methods "
        "(Lafortune, NeuMIP, single-level 8-wide, student without and with distillation) at "
        "one fixed budget, and write results.json, results.md, curves.png and slices.png.",
        helps=QUALITY_HELPS,
    ),
    "runtime": lambda sub: add_bench(
        sub,
        "runtime",
        RuntimeConfig,
        _run_runtime,
        "the runtime's performance targets: texture vs screen space, constants vs "
        "buffer, kernel vs PyTorch, the networks alone, burst vs staggered",
        "Measure the runtime's performance targets in one run on this adapter "
        "(texture_vs_screen, constants_vs_buffer, vs_torch, mlp_only, schedules) and write "
        "results.json and results.md.",
    ),
    "widths": lambda sub: add_bench(
        sub,
        "widths",
        WidthsConfig,
        _run_widths,
        "what the student's width costs and buys: whole-BTF L1 against MACs per texel",
        "Synthesise one preset's BTF, train its teacher, then the --methods "
        "networks (default: the student) at every --widths, from random weights and/or with "
        "a wide start, and NeuMIP as the reference; write results.json, results.md and "
        "widths.png.",
    ),
    "extremes": lambda sub: add_bench(
        sub,
        "extremes",
        ExtremesConfig,
        _run_extremes,
        "numerical stability at the extremes: every case works or is rejected clearly",
        "Run every extreme case (directions, precision, geometry, settings, "
        "training) and write results.json, results.md and f16_error.png; exit 1 on any FAIL.",
    ),
}

BENCHMARKS.update(ENTRIES)  # frames, lights, materials, kernels, tradeoff, ..., all


def register(sub) -> None:
    p = sub.add_parser(
        "bench",
        help="run a benchmark (JSON + Markdown + PNG)",
        description="Benchmarks: " + ", ".join(BENCHMARKS),
    )
    group = p.add_subparsers(dest="benchmark", required=True, metavar="BENCHMARK")
    for reg in BENCHMARKS.values():
        reg(group)
