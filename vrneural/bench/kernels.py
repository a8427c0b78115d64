"""`vrneural bench kernels`: the MLP evaluators of the runtime, in one run on one adapter.

For the student (coarse 2 x 8 per 2x2 block + fine 8 -> 3 per texel), the single-level 8-wide
network and the NeuMIP-sized network (arch single, 7-channel texture, 4 x 25, log1p), all with
seeded random weights (speed does not depend on the values): the generated kernel with constant
(unrolled) weights, the same kernel reading weights from a storage buffer, each in f32 and f16,
and PyTorch CPU (f32). Reports texel evaluations/s, achieved GFLOP/s (2 FLOP per multiply-add)
and their ratio to this machine's numpy sgemm GFLOP/s, the roofline of a CPU adapter.
GPU times come from timestamps around the dispatches (inputs uploaded beforehand, excluded).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from vrneural.bench import report as rp
from vrneural.config import opt, quick_defaults

NETWORKS = ("student", "single8", "neumip")
VARIANTS = ("constants", "buffer", "torch")


@dataclass
class KernelsConfig:
    """`vrneural bench kernels`."""

    out: str = opt("bench-kernels", "output directory", cli=False)
    texels: int = opt(1 << 18, "texels per evaluation (the student's coarse net runs on 1/4)")
    repeats: int = opt(3, "timed repeats (median)")
    networks: str = opt("student,single8,neumip", "networks (comma-separated)")
    precisions: str = opt("f32,f16", "GPU precisions (f16 needs shader-f16)")
    sgemm_n: int = opt(1024, "matrix side of the numpy sgemm roofline")
    quick: bool = opt(False, "CI-sized: student and NeuMIP, 16384 texels, 2 repeats, sgemm 256")
    progress: bool = opt(True, "show progress bars")
    force: bool = opt(False, "overwrite an existing output directory")

    def resolved(self) -> KernelsConfig:
        if not self.quick:
            return self
        return quick_defaults(self, texels=16384, repeats=2, sgemm_n=256, networks="student,neumip")


def network(name: str):
    """``[(layers, rows per texel)]`` of a network family, and its MACs per texel."""
    from vrneural.material import random_material

    if name == "student":
        m = random_material(5)
        parts = [(m.networks["coarse"], 0.25), (m.networks["fine"], 1.0)]
    elif name == "single8":
        parts = [(random_material(6, "single", 8, 8).networks["mlp"], 1.0)]
    else:
        m = random_material(7, "single", width=25, channels=7, layers=3, output="log1p")
        parts = [(m.networks["mlp"], 1.0)]
    return parts, sum(sum(lay.n_in * lay.n_out for lay in p) * f for p, f in parts)


def sgemm_gflops(n: int, repeats: int) -> float:
    """numpy float32 ``n x n @ n x n``: best of ``repeats`` (at least 5) timings, each of
    enough products to last about 50 ms, so that one hiccup of a shared machine during a
    sub-millisecond product cannot pass for the roofline (2 n^3 FLOP per product)."""
    rng = np.random.default_rng(0)
    a = rng.standard_normal((n, n), dtype=np.float32)
    b = rng.standard_normal((n, n), dtype=np.float32)
    a @ b
    k = max(1, int(0.05 / max(min(_timed(lambda: a @ b) for _ in range(3)), 1e-6)))

    def batch():
        for _ in range(k):
            a @ b

    best = min(_timed(batch) for _ in range(max(repeats, 5))) / k
    return 2 * n**3 / best / 1e9


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def _gpu_ms(parts, texels, precision, buffer_weights, repeats, rng) -> float:
    from vrneural.gpu.mlp_kernel import MlpKernel
    from vrneural.gpu.timing import GpuTimer

    total = 0.0
    for layers, f in parts:
        rows = max(1, int(texels * f))
        x = rng.standard_normal((rows, layers[0].n_in)).astype(np.float32)
        k = MlpKernel(layers, precision, buffer_weights)
        k.run(x)  # compile (the row count is a pipeline constant) and warm up
        timer = GpuTimer(2 * repeats + 2)
        k.run(x, repeats=repeats, timer=timer)
        total += timer.read()["mlp"] / repeats
    return total


def _torch_ms(parts, texels, repeats, rng) -> float:
    import torch

    from vrneural.runtime.measure import _median_ms, _torch_net

    nets, xs = [], []
    for layers, f in parts:
        rows = max(1, int(texels * f))
        nets.append(_torch_net(layers))
        xs.append(torch.from_numpy(rng.standard_normal((rows, layers[0].n_in), np.float32)))

    def run():
        with torch.no_grad():
            for net, x in zip(nets, xs, strict=True):
                net(x)

    return _median_ms(run, repeats)


def run_kernels(cfg: KernelsConfig) -> dict:
    from vrneural.errors import VrnError, check_range
    from vrneural.gpu.device import adapter_summary

    c = cfg.resolved()
    check_range("--texels", c.texels, 64, 1 << 22)
    check_range("--repeats", c.repeats, 1, 100)
    check_range("--sgemm-n", c.sgemm_n, 16, 8192)
    nets = rp.choice_list("--networks", c.networks, NETWORKS)
    precs = rp.choice_list("--precisions", c.precisions, ("f32", "f16"))
    if "f16" in precs and not adapter_summary().features.get("shader-f16"):
        raise VrnError("--precisions: f16 needs the shader-f16 feature, which the adapter lacks")
    root = rp.prepare_out(cfg.out, cfg.force, "kernels")
    import torch

    t0 = time.perf_counter()
    doc = rp.header("kernels", c)
    sg = sgemm_gflops(c.sgemm_n, c.repeats)
    doc["sgemm_gflops"] = sg
    doc["torch_threads"] = torch.get_num_threads()
    jobs = [(n, v, p) for n in nets for v in ("constants", "buffer") for p in precs]
    jobs += [(n, "torch", "f32") for n in nets]
    bar = rp_progress(len(jobs), c.progress)
    for name, var, prec in jobs:
        parts, macs = network(name)
        rng = np.random.default_rng(0)
        if var == "torch":
            ms = _torch_ms(parts, c.texels, c.repeats, rng)
        else:
            ms = _gpu_ms(parts, c.texels, prec, var == "buffer", c.repeats, rng)
        s = ms / 1e3
        gf = 2 * macs * c.texels / s / 1e9
        doc["records"].append(
            {
                "network": name,
                "variant": var,
                "precision": prec,
                "texels": c.texels,
                "macs_per_texel": macs,
                "ms": ms,
                "texels_per_s": c.texels / s,
                "gflops": gf,
                "fraction_of_sgemm": gf / sg,
            }
        )
        bar.update()
    bar.close()
    for r in doc["records"]:
        ref = next(
            q
            for q in doc["records"]
            if q["network"] == r["network"]
            and q["variant"] == "constants"
            and q["precision"] == "f32"
        )
        r["speedup_vs_constants_f32"] = ref["ms"] / r["ms"]
    md = markdown(doc)
    plot(doc, root / "kernels.png")
    md += ["", "![kernels](kernels.png)"]
    return rp.finish(root, doc, md, t0)


def rp_progress(total: int, enabled: bool):
    from tqdm import tqdm

    return tqdm(total=total, desc="bench kernels", unit="kernel", disable=not enabled)


def markdown(doc: dict) -> list[str]:
    c = doc["config"]
    md = [
        "# Kernels: generated constants vs storage buffer vs PyTorch CPU, f32 vs f16",
        "",
        rp.adapter_line(doc),
        f"{c['texels']} texels per evaluation, median of {c['repeats']} timed repeats (GPU: "
        f"timestamps). numpy sgemm ({c['sgemm_n']}^2, float32): **{doc['sgemm_gflops']:.1f} "
        f"GFLOP/s** (our roofline on a CPU adapter); torch threads: {doc['torch_threads']}."
        + (" **Quick run.**" if c["quick"] else ""),
        "",
    ]
    rows = [
        [
            r["network"],
            r["variant"],
            r["precision"],
            r["macs_per_texel"],
            r["ms"],
            r["texels_per_s"] / 1e6,
            r["gflops"],
            r["fraction_of_sgemm"],
            r["speedup_vs_constants_f32"],
        ]
        for r in doc["records"]
    ]
    md += rp.table(
        [
            "network",
            "variant",
            "precision",
            "MACs/texel",
            "ms",
            "Mtexel/s",
            "GFLOP/s",
            "of sgemm",
            "speed vs constants f32",
        ],
        rows,
    )
    return md


def plot(doc: dict, path) -> None:
    recs = doc["records"]
    nets = list(dict.fromkeys(r["network"] for r in recs))
    labels = list(dict.fromkeys(f"{r['variant']} {r['precision']}" for r in recs))
    fig, (ax,) = rp.figure(7, 3.6)
    w = 0.8 / len(labels)
    for i, lab in enumerate(labels):
        ys = []
        for n in nets:
            m = [r for r in recs if r["network"] == n and f"{r['variant']} {r['precision']}" == lab]
            ys.append(m[0]["gflops"] if m else 0.0)
        ax.bar(np.arange(len(nets)) + i * w, ys, w, label=lab)
    ax.axhline(doc["sgemm_gflops"], color="k", ls="--", label="numpy sgemm")
    ax.set_xticks(np.arange(len(nets)) + 0.4 - w / 2, nets)
    ax.set_ylabel("achieved GFLOP/s")
    ax.set_yscale("log")
    ax.legend(fontsize=7, ncol=2)
    ax.set_title(f"bench kernels on {doc['adapter']['name']}", fontsize=9)
    rp.save_png(fig, path)
