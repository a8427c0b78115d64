"""`vrneural bench <benchmark>`: benchmarks that write JSON + Markdown + PNG.

A group: each benchmark is a subcommand registered in :data:`BENCHMARKS` (name -> register
function), so later benchmarks add one entry and one function.
"""

from __future__ import annotations

from vrneural.config import add_config_args, config_from_args


def _register_quality(sub) -> None:
    from vrneural.bench.quality import QualityConfig

    p = sub.add_parser(
        "quality",
        help="Table 1 analog: whole-BTF L1 of the student and baselines per material",
        description="Synthesise each preset's BTF, train the teacher and the five methods "
        "(Lafortune, NeuMIP, single-level 8-wide, student without and with distillation) at "
        "one fixed budget, and write results.json, results.md, curves.png and slices.png.",
    )
    p.add_argument("--out", default="bench-quality", help="output directory")
    add_config_args(p, QualityConfig)
    p.set_defaults(func=_run_quality)


def _run_quality(args) -> int:
    from vrneural.bench.quality import QualityConfig, run_quality

    doc = run_quality(config_from_args(QualityConfig, args))
    print(
        f"{args.out}: results.json, results.md, curves.png, slices.png "
        f"({doc['total_seconds'] / 60:.1f} min)"
    )
    return 0


BENCHMARKS = {"quality": _register_quality}

# frames, lights, materials, kernels, tradeoff, all (vrneural/bench/entries.py)
from vrneural.bench.entries import ENTRIES  # noqa: E402

BENCHMARKS.update(ENTRIES)


def register(sub) -> None:
    p = sub.add_parser(
        "bench",
        help="run a benchmark (JSON + Markdown + PNG)",
        description="Benchmarks: " + ", ".join(BENCHMARKS),
    )
    group = p.add_subparsers(dest="benchmark", required=True, metavar="BENCHMARK")
    for reg in BENCHMARKS.values():
        reg(group)
