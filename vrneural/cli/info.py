"""`vrneural info`: the adapter, its features and limits, measured MLP throughput, versions."""

from __future__ import annotations

import json

from vrneural.errors import check_range


def register(sub) -> None:
    p = sub.add_parser(
        "info",
        help="show the GPU adapter, features, limits and MLP throughput",
        description="Show the wgpu adapter, the features and limits vrneural "
        "uses, measured f32/f16 throughput of a small unrolled MLP kernel, and "
        "package versions.",
    )
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.add_argument(
        "--texels",
        type=int,
        default=1 << 20,
        help="texels per throughput dispatch, [1024, 16777216]; f32 and f16 alternate, best "
        "of 3 rounds of 4 dispatches each (default 1048576)",
    )
    p.set_defaults(func=run)


#: Alternating rounds of the f32 / f16 throughput measurement (best of each is reported)
ROUNDS = 3


def collect(texels: int) -> dict:
    from vrneural.gpu import adapter_summary, has_feature
    from vrneural.gpu.probe import mlp_throughput
    from vrneural.gpu.timing import timestamp_period_ns
    from vrneural.versions import package_versions  # importlib.metadata: 30 ms

    check_range("--texels", texels, 1024, 1 << 24)
    summary = adapter_summary().to_dict()
    # f32 and f16 alternate, best of ROUNDS each: a busy CPU or GPU only ever slows a
    # measurement down, so the best is the least disturbed (one sample of a few ms on
    # lavapipe could call emulated f16 "native")
    precisions = ["f32", "f16"] if has_feature("shader-f16") else ["f32"]
    best: dict = {}
    for _ in range(ROUNDS):
        for p in precisions:
            t = mlp_throughput(p, texels)
            if p not in best or t["evals_per_s"] > best[p]["evals_per_s"]:
                best[p] = t
    thr = [best[p] for p in precisions]
    f32 = thr[0]["evals_per_s"]
    f16 = thr[1]["evals_per_s"] if len(thr) > 1 else None
    return {
        "adapter": summary,
        "timestamp_period_ns": timestamp_period_ns(),
        "mlp_throughput": thr,
        "f16_vs_f32": (f16 / f32) if f16 else None,
        "f16_verdict": None
        if f16 is None
        else ("native (faster or equal)" if f16 >= 0.9 * f32 else "emulated or slow: prefer f32"),
        "versions": package_versions(),
    }


def run(args) -> int:
    info = collect(args.texels)
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    a = info["adapter"]
    print(f"adapter   {a['name']}  ({a['adapter_type']}, {a['backend']})")
    print(f"driver    {a['driver']}   vendor {a['vendor']}")
    print("features  " + "  ".join(f"{k}={'yes' if v else 'no'}" for k, v in a["features"].items()))
    lim = a["limits"]
    print(
        f"limits    max 2D texture {lim['max_texture_dimension_2d']}   max storage binding "
        f"{lim['max_storage_buffer_binding_size'] / 2**20:.0f} MiB"
    )
    print(f"timestamp period {info['timestamp_period_ns']:g} ns/tick")
    for t in info["mlp_throughput"]:
        print(
            f"MLP {t['precision']}   {t['evals_per_s'] / 1e6:9.1f} M texel-evals/s  "
            f"{t['gflops']:7.2f} GFLOP/s  ({t['ms']:.2f} ms for {t['texels']} texels, "
            f"{t['timed_by']})"
        )
    if info["f16_vs_f32"] is not None:
        print(f"f16/f32   {info['f16_vs_f32']:.2f}x -> {info['f16_verdict']}")
    print("versions  " + "  ".join(f"{k} {v}" for k, v in info["versions"].items() if v))
    return 0
