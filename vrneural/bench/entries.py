"""CLI entries of the timing and trade-off benchmarks for :data:`vrneural.cli.bench.BENCHMARKS`.

Each entry is ``name -> register(sub)``; a handler imports its bench module (and with it torch or
wgpu) only when run. ``bench all`` runs every one of them into ``OUT/<name>``.
"""

from __future__ import annotations

import importlib
import time
from pathlib import Path

from vrneural.bench import configs as c
from vrneural.bench import train_configs as tc
from vrneural.config import add_config_args, config_from_args
from vrneural.outputs import OutputDir, atomic_path, write_json

#: name -> (config class, help); each run by ``run_<name>`` of ``vrneural.bench.<name>``
SPECS = {
    "frames": (
        c.FramesConfig,
        "paper Table 2: frame time over texture resolution x update interval N",
    ),
    "lights": (
        c.LightsConfig,
        "paper Fig. 10: frame time over the number of point lights (1 to 8 by default)",
    ),
    "materials": (c.MaterialsConfig, "paper Table 3: 1 to 4 materials, 3 lights, 1024^2, N = 7"),
    "frame": (
        c.FrameConfig,
        "one frame's time: host, GPU per pass, frames in flight, against the adapter's floors",
    ),
    "kernels": (
        c.KernelsConfig,
        "MLP kernels: constants vs buffer vs torch vs NeuMIP-sized, f32 vs f16",
    ),
    "tradeoff": (
        tc.TradeoffConfig,
        "speed/accuracy: each knob vs the per-pixel teacher (FLIP, PSNR, SSIM)",
    ),
    "atlas": (
        c.AtlasBenchConfig,
        "atlas stage: time, memory, coverage, charts and seam error over a fixed mesh set",
    ),
    "distance": (
        tc.DistanceConfig,
        "level of detail: a neural sphere from 0.3 to 20 m and tiled 1-16x, with and without "
        "radiance mips, resolution from the screen and prefiltered neural textures",
    ),
}


def _load(name: str):
    return SPECS[name][0], getattr(importlib.import_module(f"vrneural.bench.{name}"), f"run_{name}")


def _summary(name: str, doc: dict, out: str) -> None:
    files = sorted(p.name for p in Path(out).iterdir() if p.is_file() and p.name[0] != ".")
    print(f"bench {name}: {out}/ {', '.join(files)} ({doc['total_seconds']:.0f} s)")


def add_bench(sub, name: str, cls, run, help_: str, description: str, **config_kw) -> None:
    """The subcommand `vrneural bench NAME`: ``--out`` (default ``bench-NAME``) and the fields of
    config class ``cls`` as options (``config_kw``: :func:`~vrneural.config.add_config_args`'s);
    ``run(args)`` handles it."""
    p = sub.add_parser(name, help=help_, description=description)
    p.add_argument(
        "--out", default=f"bench-{name}", help=f"output directory (default: bench-{name})"
    )
    add_config_args(p, cls, **config_kw)
    p.set_defaults(func=run)


def _entry(name: str):
    def register(sub) -> None:
        help_ = SPECS[name][1]
        add_bench(sub, name, SPECS[name][0], lambda args: _run(name, args), help_, help_ + ".")

    return register


def _run(name: str, args) -> int:
    cls, fn = _load(name)
    doc = fn(config_from_args(cls, args, out=args.out))
    _summary(name, doc, args.out)
    return 0


def _register_all(sub) -> None:
    p = sub.add_parser(
        "all",
        help="run frames, lights, materials, frame, kernels, tradeoff, atlas and distance into "
        "OUT/<name>",
        description="Every timing and trade-off benchmark (not `quality`, which trains its own "
        "baselines; run it separately). --quick: each at its CI size.",
    )
    p.add_argument(
        "--out",
        default="bench-all",
        help="output directory, one folder per bench (default: bench-all)",
    )
    p.add_argument("--quick", action="store_true", help="CI-sized runs")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.add_argument("--no-progress", dest="progress", action="store_false", help="no progress bars")
    p.set_defaults(func=_run_all)


def _run_all(args) -> int:
    t0 = time.perf_counter()
    # the folder is checked as every bench checks its own: a folder of other files is refused,
    # and one of ours needs --force (each bench below then replaces only its own sub-folder)
    with OutputDir(args.out, "bench all", force=args.force, keep=True) as od:
        od.check()
        for name in SPECS:  # every bench's folder before the first bench replaces its own
            OutputDir(Path(args.out) / name, f"bench {name}", force=args.force).check()
        od.open()
        docs = {}
        for name in SPECS:
            cls, fn = _load(name)
            out = str(Path(args.out) / name)
            docs[name] = fn(
                cls(out=out, quick=args.quick, force=args.force, progress=args.progress)
            )
            _summary(name, docs[name], out)
        _write_index(Path(args.out), docs, args.quick, time.perf_counter() - t0)
    print(f"bench all: {args.out}/index.md ({time.perf_counter() - t0:.0f} s)")
    return 0


def _write_index(out: Path, docs: dict, quick: bool, seconds: float) -> None:
    """``OUT/index.md`` + ``index.json``: what each bench reproduces, its time and its files."""
    first = next(iter(docs.values()))
    a = first.get("adapter", {})
    lines = [
        "# vrneural bench all" + (" (quick, CI sizes)" if quick else ""),
        "",
        f"Adapter: {a.get('name', '?')} ({a.get('backend', '?')}, {a.get('adapter_type', '?')}); "
        f"{seconds:.0f} s in all.",
        "",
        "| bench | reproduces | seconds | report | plots |",
        "|---|---|---|---|---|",
    ]
    benches = {}
    for name, doc in docs.items():
        pngs = sorted(p.name for p in (out / name).glob("*.png"))
        plots = ", ".join(f"[{p}]({name}/{p})" for p in pngs) or "-"
        lines.append(
            f"| {name} | {SPECS[name][1]} | {doc['total_seconds']:.0f} | "
            f"[results.md]({name}/results.md) | {plots} |"
        )
        benches[name] = {
            "seconds": doc["total_seconds"],
            "results": f"{name}/results.json",
            "records": len(doc.get("records", [])),
            "plots": [f"{name}/{p}" for p in pngs],
        }
    if quick:
        lines += [
            "",
            "With --quick every bench runs at CI sizes (smaller textures, eyes, frame counts and "
            "trained packs than the paper's settings named under 'reproduces'); each "
            "results.md states the settings it ran.",
        ]
    with atomic_path(out / "index.md") as tmp:
        tmp.write_text("\n".join(lines) + "\n")
    write_json(
        out / "index.json",
        {"quick": quick, "total_seconds": seconds, "adapter": a, "benches": benches},
    )


ENTRIES = {name: _entry(name) for name in SPECS}
ENTRIES["all"] = _register_all
