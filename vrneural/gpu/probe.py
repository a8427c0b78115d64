"""Measured throughput of a small unrolled MLP kernel in f32 and f16, for `vrneural info`.

The network is the student's shape class (inputs 24 -> 8 -> 8 -> 8 -> 3): when f16 is emulated
(lavapipe) the f16 rate is far below the f32 rate; on native-f16 GPUs it is at or above it.
"""

from __future__ import annotations

import time

import numpy as np

from vrneural.gpu.mlp_kernel import MlpKernel
from vrneural.gpu.timing import GpuTimer
from vrneural.mlp import macs, random_mlp

PROBE_SIZES = [24, 8, 8, 8, 3]


def mlp_throughput(
    precision: str, n: int = 1 << 20, repeats: int = 4, buffer_weights: bool = False
) -> dict:
    """Evaluate ``n`` texels ``repeats`` times; report evaluations/s and GFLOP/s.

    Timed with GPU timestamps where available (median dispatch), else wall clock over the batch.
    """
    layers = random_mlp(PROBE_SIZES, seed=7)
    x = np.random.default_rng(0).standard_normal((n, PROBE_SIZES[0])).astype(np.float32)
    k = MlpKernel(layers, precision, buffer_weights)
    k.run(x[:1024])  # compile and warm up
    timer = GpuTimer(max_passes=repeats)
    t0 = time.perf_counter()
    k.run(x, repeats=repeats, timer=timer)
    wall = (time.perf_counter() - t0) / repeats
    ms = timer.read()
    if ms:
        per = ms["mlp"] / repeats / 1e3
        how = "gpu-timestamps"
    else:
        per, how = wall, "wall-clock"
    per = max(per, 1e-9)
    flops = 2.0 * macs(layers) * n
    return {
        "precision": precision,
        "weights": "buffer" if buffer_weights else "constants",
        "texels": n,
        "ms": per * 1e3,
        "evals_per_s": n / per,
        "gflops": flops / per / 1e9,
        "timed_by": how,
    }
