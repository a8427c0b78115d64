"""The filtered ground truth of the benches: the teacher per pixel in f32, supersampled.

A frame of the reference is the mean of ``spp`` renders of ``--mode reference``, each with the
image shifted by a sub-pixel offset (``Renderer.jitter``): one offset in each cell of a
``k x k`` grid over the pixel (``spp = k^2``; a non-square count takes the first ``spp`` cells of
the next square grid), placed uniformly at random inside its cell (stratified sampling, seeded).
Same geometry, lights and head path as the renders it judges. Its own sampling noise is what two
references with different ``seed`` differ by (the benches' noise floor): a difference between a
render and the reference below that is not measurable.
"""

from __future__ import annotations

import math

import numpy as np

from vrneural.bench.parts import SPP_MAX
from vrneural.errors import check_int


def stratified_offsets(spp: int, seed: int) -> np.ndarray:
    """``[spp, 2]`` sub-pixel offsets in ``[-0.5, 0.5)^2`` pixels, one per cell of a
    ``ceil(sqrt(spp))``-square grid (row-major, the first ``spp`` cells), jittered in the cell."""
    k = math.isqrt(spp - 1) + 1 if spp > 1 else 1
    rng = np.random.default_rng([seed, spp])
    cells = np.stack(np.meshgrid(np.arange(k), np.arange(k), indexing="xy"), -1).reshape(-1, 2)
    cells = cells[:spp]
    return (cells + rng.random((spp, 2))) / k - 0.5


class SupersampledReference:
    """A ``--mode reference`` renderer that returns each frame averaged over ``spp`` jittered
    samples per pixel: ``frame(f) -> [eyes, H, W, 3]`` float32 linear radiance."""

    def __init__(self, scene, settings, spp: int = 16, seed: int = 0):
        from vrneural.runtime.renderer import Renderer

        check_int("--spp", spp, 1, SPP_MAX)
        self.r = Renderer(scene, settings)
        self.offsets = stratified_offsets(spp, seed)

    def frame(self, f: int) -> np.ndarray:
        acc = None
        for dx, dy in self.offsets:
            self.r.jitter = (float(dx), float(dy))
            self.r.frame(f)
            imgs = np.stack([e[..., :3] for e in self.r.read_eyes()]).astype(np.float64)
            acc = imgs if acc is None else acc + imgs
        self.r.jitter = (0.0, 0.0)
        return (acc / len(self.offsets)).astype(np.float32)
