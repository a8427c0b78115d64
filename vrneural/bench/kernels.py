"""`vrneural bench kernels`: the MLP evaluators of the runtime, in one run on one adapter.

For the networks `distill` trains, in their shapes and with their initial weights (speed does
not depend on the values): the student (M_c 17 -> 8 -> 8 once per 2x2 block, M_f 16 -> 8 -> 3
per texel; ``student:W`` the student ``distill --width W`` trains), the single-level 8-wide
network (``single8:W``: W wide) and NeuMIP (4 x 25, 7-channel texture, reading wi.xy and wo.xy;
log1p). Each as the generated kernel with constant (unrolled) weights, the same kernel reading
weights from a storage buffer, each in f32 and f16, and PyTorch CPU (f32). Reports texel
evaluations/s, achieved GFLOP/s (2 FLOP per multiply-add) and their ratio to this machine's
numpy sgemm GFLOP/s, the roofline of a CPU adapter (measured before and after the kernels, the
better kept; a kernel above it is flagged in results.md). Speed-ups are against the same
network's constants kernel in f32, or in f16 when only f16 was measured (the column header names
the reference). GPU times come from timestamps around the dispatches (inputs uploaded
beforehand, excluded).
"""

from __future__ import annotations

import os
import subprocess
import sys
import time

import numpy as np
from tqdm import tqdm

from vrneural.bench import report as rp
from vrneural.bench.configs import KernelsConfig, network_width
from vrneural.bench.runtime import torch_net
from vrneural.bench.runtime_frames import median_ms, wall_ms
from vrneural.errors import VrnError, check_range, count
from vrneural.neural_offset import OFFSET_SIZES


def network(name: str):
    """``[(layers, rows per texel)]`` of a network, and its MACs per texel: the network
    `distill` trains under that name (:func:`~vrneural.distill.models.make_spec`; ``student:W``
    and ``single8:W`` as ``--width W``), with its initial weights (speed does not depend on
    their values; the inputs NeuMIP does not read are zero, so the constants kernel skips them
    as in a pack)."""
    from vrneural.distill.models import NeuralModel, make_spec

    base = name.removesuffix("_offset")
    method, width = network_width(base) or (base, 8)
    spec = make_spec(method, (16, 16), width=width)
    if base != name:  # as setup_parallax gives a pack --parallax neural
        channels, hidden = OFFSET_SIZES[method]
        spec["parallax"] = {"kind": "neural", "march": "texel", "res": [16, 16],
                            "channels": channels, "hidden": list(hidden)}  # fmt: skip
    model = NeuralModel(spec, 5)
    if base != name:  # its last layer starts at zero; speed does not depend on the values
        for p in model.offset_mlp.parameters():
            p.data.normal_(0.0, 0.5)
    mat = model.to_material()
    if mat.arch == "coarse_fine":  # M_c once per 2x2 block, M_f per texel
        parts = [(mat.networks["coarse"], 0.25), (mat.networks["fine"], 1.0)]
    else:
        parts = [(mat.networks["mlp"], 1.0)]
    if mat.offset_net:  # the offset MLP per texel
        parts.append((mat.offset_net, 1.0))
    return parts, mat.macs_per_texel


def sgemm_gflops(n: int, repeats: int) -> float:
    """numpy float32 ``n x n @ n x n``: best of ``repeats`` (at least 5) timings, each of
    enough products to last about 50 ms, so that one hiccup of a shared machine during a
    sub-millisecond product cannot pass for the roofline (2 n^3 FLOP per product). A load that
    lasts the whole measurement (other processes on the cores numpy's threads use) still
    lowers it: :func:`run_kernels` measures it before and after the kernels, keeps the better
    one and flags a kernel measured above it."""
    rng = np.random.default_rng(0)
    a = rng.standard_normal((n, n), dtype=np.float32)
    b = rng.standard_normal((n, n), dtype=np.float32)
    for _ in range(3):  # warm-up: BLAS threads, caches, clocks
        a @ b
    k = max(1, int(0.05 / max(min(wall_ms(lambda: a @ b) for _ in range(3)) / 1e3, 1e-6)))

    def batch():
        for _ in range(k):
            a @ b

    best = min(wall_ms(batch) for _ in range(max(repeats, 5))) / 1e3 / k
    return 2 * n**3 / best / 1e9


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

    nets, xs = [], []
    for layers, f in parts:
        rows = max(1, int(texels * f))
        nets.append(torch_net(layers))
        xs.append(torch.from_numpy(rng.standard_normal((rows, layers[0].n_in), np.float32)))

    def run():
        with torch.no_grad():
            for net, x in zip(nets, xs, strict=True):
                net(x)

    return median_ms(run, repeats)


def run_kernels(cfg: KernelsConfig) -> dict:
    from vrneural.gpu.device import adapter_summary

    c = cfg.resolved()
    check_range("--texels", c.texels, 64, 1 << 22)
    check_range("--repeats", c.repeats, 1, 100)
    check_range("--sgemm-n", c.sgemm_n, 16, 8192)
    check_range("--threads", c.threads, 0, 1024)
    nets, precs = c.networks, c.precisions
    if "f16" in precs and not adapter_summary().features.get("shader-f16"):
        raise VrnError("--precisions: f16 needs the shader-f16 feature, which the adapter lacks")
    # torch loaded before the output folder exists: a signal in the middle of its C++
    # extension's import ends the process by std::terminate, not as an interrupt
    import torch

    with rp.prepare_out(cfg.out, cfg.force, "kernels") as root:
        t0 = time.perf_counter()
        doc = rp.header("kernels", c)
        threads_before = torch.get_num_threads()
        try:
            if c.threads:
                torch.set_num_threads(c.threads)
            return _run(c, doc, nets, precs, root, t0)
        finally:
            torch.set_num_threads(threads_before)  # `bench all` goes on in this process


def _sgemm(c: KernelsConfig) -> float:
    """:func:`sgemm_gflops` with ``--threads`` BLAS threads: numpy's thread pool is sized when
    numpy loads, so a set count runs it in a child process started with that count."""
    if not c.threads:
        return sgemm_gflops(c.sgemm_n, c.repeats)

    n = str(c.threads)
    env = dict(os.environ, OMP_NUM_THREADS=n, OPENBLAS_NUM_THREADS=n, MKL_NUM_THREADS=n)
    code = (
        "from vrneural.bench.kernels import sgemm_gflops; "
        f"print(sgemm_gflops({c.sgemm_n}, {c.repeats}))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return float(out.stdout.split()[-1])


def _run(c: KernelsConfig, doc: dict, nets, precs, root, t0) -> dict:
    import torch

    sg_runs = [_sgemm(c)]
    doc["torch_threads"] = torch.get_num_threads()
    doc["sgemm_threads"] = c.threads or "default"
    jobs = [(n, v, p) for n in nets for v in ("constants", "buffer") for p in precs]
    jobs += [(n, "torch", "f32") for n in nets]
    bar = tqdm(total=len(jobs), desc="bench kernels", unit="kernel", disable=not c.progress)
    for name, var, prec in jobs:
        parts, macs = network(name)
        rng = np.random.default_rng(0)
        if var == "torch":
            ms = _torch_ms(parts, c.texels, c.repeats, rng)
        else:
            ms = _gpu_ms(parts, c.texels, prec, var == "buffer", c.repeats, rng)
        s = ms / 1e3
        doc["records"].append(
            {
                "network": name,
                "variant": var,
                "precision": prec,
                "texels": c.texels,
                "macs_per_texel": macs,
                "ms": ms,
                "texels_per_s": c.texels / s,
                "gflops": 2 * macs * c.texels / s / 1e9,
            }
        )
        bar.update()
    bar.close()
    sg_runs.append(_sgemm(c))  # again: a load may have passed
    doc["sgemm_gflops_runs"] = sg_runs
    doc["sgemm_gflops"] = sg = max(sg_runs)
    for r in doc["records"]:
        r["fraction_of_sgemm"] = r["gflops"] / sg
    add_speedups(doc)
    # the Markdown's two warnings, for scripts reading the JSON: sgemm varied more than 2x in
    # this run; a kernel measured above the sgemm roofline (so `fraction_of_sgemm` overstates)
    doc["sgemm_varied"] = max(sg_runs) > 2 * min(sg_runs)
    doc["roofline_unreliable"] = bool(roofline_exceeded(doc))
    return rp.finish(root, doc, markdown(doc), t0, [("kernels.png", "kernels", plot)])


def add_speedups(doc: dict) -> str:
    """Give every record ``speedup_vs_constants`` and ``speedup_vs_constants_<p>`` (the same
    value, the same network's constants kernel's ms over the record's ms; None when that
    network has no constants record) and set
    ``doc["speedup_reference"]``: constants in f32 when f32 was measured, else in the first GPU
    precision measured (f16 alone: torch, always f32, is then compared with an f16 kernel)."""
    precs = [r["precision"] for r in doc["records"] if r["variant"] == "constants"]
    prec = "f32" if "f32" in precs or not precs else precs[0]
    doc["speedup_reference"] = f"constants {prec}"
    ref = {
        r["network"]: r["ms"]
        for r in doc["records"]
        if r["variant"] == "constants" and r["precision"] == prec
    }
    for r in doc["records"]:
        base = ref.get(r["network"])
        v = None if base is None else base / r["ms"]
        r[f"speedup_vs_constants_{prec}"] = v  # the name says which precision: as before
        r["speedup_vs_constants"] = v  # the same under one name ("speedup_reference" says it)
    return prec


def roofline_exceeded(doc: dict) -> list[dict]:
    """Records measured above the numpy sgemm roofline, on a CPU adapter (where the kernels run
    on the same cores, so none should; on a GPU the CPU's sgemm is no roofline)."""
    if not doc["adapter"].get("is_cpu"):
        return []
    return [r for r in doc["records"] if r["gflops"] > doc["sgemm_gflops"]]


def markdown(doc: dict) -> list[str]:
    c = doc["config"]
    sg, runs = doc["sgemm_gflops"], doc.get("sgemm_gflops_runs", [doc["sgemm_gflops"]])
    ref = doc.get("speedup_reference", "constants f32")
    key = "speedup_vs_" + ref.replace(" ", "_")
    md = [
        "# Kernels: generated constants vs storage buffer vs PyTorch CPU, f32 vs f16",
        "",
        rp.adapter_line(doc),
        f"{c['texels']} texels per evaluation, median of "
        f"{count(c['repeats'], 'timed repeat')} (GPU: "
        f"timestamps). numpy sgemm ({c['sgemm_n']}^2, float32): **{sg:.1f} GFLOP/s** (our "
        "roofline on a CPU adapter; the better of "
        + " and ".join(f"{g:.1f}" for g in runs)
        + f" measured before and after the kernels); torch threads: {doc['torch_threads']}"
        + (f", sgemm threads: {doc['sgemm_threads']}" if "sgemm_threads" in doc else "")
        + "."
        + (" **Quick run.**" if c["quick"] else ""),
        "",
    ]
    if len(runs) > 1 and max(runs) > 2 * min(runs):
        md += [
            f"numpy sgemm varied {min(runs):.1f} to {max(runs):.1f} GFLOP/s within this run: "
            "the machine was loaded, so every timing here is rough.",
            "",
        ]
    over = roofline_exceeded(doc)
    if over:
        worst = max(over, key=lambda r: r["gflops"])
        md += [
            f"**Roofline unreliable:** {len(over)} kernel(s) measured above numpy sgemm (up to "
            f"{worst['gflops']:.1f} GFLOP/s, {worst['network']} {worst['variant']} "
            f"{worst['precision']}), which on a CPU adapter they cannot beat: sgemm ran while "
            "the machine was loaded, so the `of sgemm` column overstates every kernel.",
            "",
        ]

    md += rp.record_table(
        doc["records"],
        [
            ("network", "network"),
            ("variant", "variant"),
            ("precision", "precision"),
            ("MACs/texel", "macs_per_texel"),
            ("ms", "ms"),
            ("Mtexel/s", lambda r: r["texels_per_s"] / 1e6),
            ("GFLOP/s", "gflops"),
            ("of sgemm", "fraction_of_sgemm"),
            (f"speed vs {ref}", lambda r: "-" if r.get(key) is None else r[key]),
        ],
    )
    note = (
        f"speed vs {ref}: the same network's {ref} kernel's ms over this row's ms (> 1 = faster)."
    )
    if ref != "constants f32":
        note += (
            f" No f32 kernel was measured, so the reference is {ref.split()[1]}: the torch rows "
            "(always f32) are compared with it."
        )
    md += ["", note]
    return md


def plot(doc: dict, path) -> None:
    recs = doc["records"]
    nets = list(dict.fromkeys(r["network"] for r in recs))
    labels = list(dict.fromkeys(f"{r['variant']} {r['precision']}" for r in recs))
    fig, (ax,) = rp.figure(8, 3.6)
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
    # outside the axes, right: inside, it covered the top of the tallest bars
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    ax.set_title(f"bench kernels on {doc['adapter']['name']}", fontsize=9)
    rp.save_png(fig, path)
