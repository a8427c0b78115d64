"""`vrneural bench <benchmark>`: benchmarks that write JSON + Markdown + PNG.

A group: each benchmark is a subcommand registered in :data:`BENCHMARKS` (name -> register
function), so later benchmarks add one entry and one function.
"""

from __future__ import annotations

from pathlib import Path

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
    p.add_argument(
        "--out", default="bench-quality", help="output directory (default: bench-quality)"
    )
    seed = "seed of synthesis, initialisation, data order and texture-lookup jitter"
    add_config_args(p, QualityConfig, helps={"seed": seed})  # (the BTFs' too: its own help)
    p.set_defaults(func=_run_quality)


def _run_quality(args) -> int:
    from vrneural.bench.quality import QualityConfig, run_quality

    doc = run_quality(config_from_args(QualityConfig, args))
    print(
        f"{args.out}: results.json, results.md, curves.png, slices.png "
        f"({doc['total_seconds'] / 60:.1f} min)"
    )
    return 0


def _register_widths(sub) -> None:
    from vrneural.bench.widths import WidthsConfig

    p = sub.add_parser(
        "widths",
        help="what the student's width costs and buys: whole-BTF L1 against MACs per texel",
        description="Synthesise one preset's BTF, train its teacher, then the --methods "
        "networks (default: the student) at every --widths, from random weights and/or with "
        "a wide start, and NeuMIP as the reference; write results.json, results.md and "
        "widths.png.",
    )
    p.add_argument("--out", default="bench-widths", help="output directory (default: bench-widths)")
    add_config_args(p, WidthsConfig)
    p.set_defaults(func=_run_widths)


def _run_widths(args) -> int:
    from vrneural.bench.widths import WidthsConfig, run_widths

    doc = run_widths(config_from_args(WidthsConfig, args))
    print(f"{args.out}: results.json, results.md, widths.png ({doc['total_seconds'] / 60:.1f} min)")
    return 0


def _register_extremes(sub) -> None:
    from vrneural.bench.extremes import ExtremesConfig

    p = sub.add_parser(
        "extremes",
        help="numerical stability at the extremes: every case works or is rejected clearly",
        description="Run every extreme case (directions, precision, geometry, settings, "
        "training) and write results.json, results.md and f16_error.png; exit 1 on any FAIL.",
    )
    p.add_argument(
        "--out", default="bench-extremes", help="output directory (default: bench-extremes)"
    )
    add_config_args(p, ExtremesConfig)
    p.set_defaults(func=_run_extremes)


def _run_extremes(args) -> int:
    from vrneural.bench.extremes import ExtremesConfig, run_extremes

    doc = run_extremes(config_from_args(ExtremesConfig, args), args.out)
    png = ", f16_error.png" if (Path(args.out) / "f16_error.png").is_file() else ""
    print(
        f"bench extremes: {args.out}/ results.json, results.md{png} "
        f"({doc['n_fail']} FAIL, {doc['total_seconds']:.0f} s)"
    )
    return 1 if doc["n_fail"] else 0


def _register_runtime(sub) -> None:
    from vrneural.bench.runtime import RuntimeConfig

    p = sub.add_parser(
        "runtime",
        help="the runtime's performance targets: texture vs screen space, constants vs "
        "buffer, kernel vs PyTorch, the networks alone, burst vs staggered",
        description="Measure the runtime's performance targets in one run on this adapter "
        "(texture_vs_screen, constants_vs_buffer, vs_torch, mlp_only, schedules) and write "
        "results.json and results.md.",
    )
    p.add_argument(
        "--out", default="bench-runtime", help="output directory (default: bench-runtime)"
    )
    add_config_args(p, RuntimeConfig)
    p.set_defaults(func=_run_runtime)


def _run_runtime(args) -> int:
    from vrneural.bench.runtime import HEADLINES, RuntimeConfig, headline, run_runtime

    doc = run_runtime(config_from_args(RuntimeConfig, args), args.out)
    print(f"bench runtime: {args.out}/ results.json, results.md ({doc['total_seconds']:.0f} s)")
    for name, paths in HEADLINES.items():
        if name in doc:
            print(f"  {name}: {headline(doc[name], paths)}")
    return 0


BENCHMARKS = {
    "quality": _register_quality,
    "runtime": _register_runtime,
    "widths": _register_widths,
    "extremes": _register_extremes,
}

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
