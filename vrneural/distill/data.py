"""BTF slices -> training batches.

One batch is one ``(wi, wo)`` slice: all texels of the BTF at one light/view pair, grouped in
2x2 blocks (``uv: [N, 4, 2]``, ``N = H W / 4``; block ``(by, bx)`` holds texels
``(2by, 2bx), (2by, 2bx+1), (2by+1, 2bx), (2by+1, 2bx+1)``). Texture lookups are stratified:
each texel's UV is jittered uniformly within the texel. A deterministic split holds out
``test_fraction`` of the pairs as test directions. Under DDP each rank takes an equal contiguous
share of the blocks, so the averaged gradient equals the full-slice gradient.
"""

from __future__ import annotations

import copy

import numpy as np
import torch

from vrneural.btf.format import Btf
from vrneural.distill.lookups import avg_pool_levels
from vrneural.errors import VrnError


class SliceData:
    """All slices of a BTF in memory (float16) plus block UVs; see the module docstring."""

    def __init__(
        self, btf: Btf, test: list[int], rank: int = 0, world: int = 1, device: str = "cpu"
    ):
        L, V, H, W = btf.shape
        if H % 2 or W % 2:
            raise VrnError(f"{btf.path}: resolution {H}x{W} must be even (2x2 blocks)")
        nb = H * W // 4
        if nb % world:
            raise VrnError(f"{nb} texel blocks cannot be split evenly over {world} processes")
        self.btf = btf
        self.res = (H, W)
        self.n_view = V
        self.values = torch.from_numpy(np.array(btf.values))  # [L, V, H, W, 3] f16
        bad = ~torch.isfinite(self.values)
        if bad.any():  # a NaN target would silently poison the weights (or the test L1)
            first = [int(i) for i in torch.nonzero(bad)[0]]
            raise VrnError(
                f"{btf.path}: BTF values contain {int(bad.sum())} NaN/Inf entries "
                f"(first at [light, view, y, x, rgb] = {first}); fix or re-import the BTF"
            )
        self.light = torch.from_numpy(np.array(btf.light_dirs, np.float32))
        self.view = torch.from_numpy(np.array(btf.view_dirs, np.float32))
        test_set = set(test)
        self.test = sorted(test_set)
        self.train = [p for p in range(L * V) if p not in test_set]
        ys, xs = torch.meshgrid(torch.arange(H), torch.arange(W), indexing="ij")
        centre = torch.stack([(xs + 0.5) / W, (ys + 0.5) / H], -1).float()  # [H, W, 2]
        self.centres = to_blocks(centre)  # [N, 4, 2]
        share = nb // world
        self.shard = slice(rank * share, (rank + 1) * share)
        self._place(device)

    def _place(self, device) -> None:
        """Serve slices on ``device``: ``_on`` holds the tensors there (the CPU ones on a CPU)."""
        self.device = torch.device(device)
        self._on = tuple(t.to(self.device) for t in (self.values, self.light, self.view))

    def on(self, device) -> SliceData:
        """The same data serving tensors on ``device`` (the CPU copy is kept and shared):
        training reads slices on the GPU, export and the numpy checks read them on the CPU."""
        new = copy.copy(self)
        new._place(device)
        return new

    def dirs(self, pair: int) -> tuple[torch.Tensor, torch.Tensor]:
        _, light, view = self._on
        return light[pair // self.n_view], view[pair % self.n_view]

    def target(self, pair: int, shard: bool = True) -> torch.Tensor:
        """Ground truth ``[N, 4, 3]`` float32 of one slice (this rank's blocks)."""
        v = self._on[0][pair // self.n_view, pair % self.n_view].float()
        y = to_blocks(v)
        return y[self.shard] if shard else y

    def target_level(self, pair: int, level: int) -> torch.Tensor:
        """The slice averaged over ``2^level`` texel squares, in blocks ``[N_level, 4, 3]``
        float32 (every rank: the levels are small and not sharded): the ground truth of a
        prefiltered pyramid level."""
        v = self._on[0][pair // self.n_view, pair % self.n_view].float()
        return to_blocks(avg_pool_levels(v, level))

    def uv_level(self, level: int, gen: torch.Generator | None) -> torch.Tensor:
        """Block UVs ``[N_level, 4, 2]`` of the level-``level`` texel grid, jittered within the
        level's texel when ``gen`` is set."""
        H, W = self.res[0] >> level, self.res[1] >> level
        ys, xs = torch.meshgrid(torch.arange(H), torch.arange(W), indexing="ij")
        uv = to_blocks(torch.stack([(xs + 0.5) / W, (ys + 0.5) / H], -1).float())
        if gen is not None:
            j = torch.rand(uv.shape, generator=gen) - 0.5
            uv = uv + j * torch.tensor([1.0 / W, 1.0 / H])
        return uv.to(self.device)

    def uv(self, gen: torch.Generator | None, shard: bool = True) -> torch.Tensor:
        """Block UVs ``[N, 4, 2]``: texel centres, jittered within the texel when ``gen`` is set.

        The jitter is drawn for the whole slice on every rank (same stream), then sharded.
        """
        uv = self.centres
        if gen is not None:
            H, W = self.res
            j = torch.rand(uv.shape, generator=gen) - 0.5
            uv = uv + j * torch.tensor([1.0 / W, 1.0 / H])
        return (uv[self.shard] if shard else uv).to(self.device)


def to_blocks(a: torch.Tensor) -> torch.Tensor:
    """``[H, W, ...]`` -> ``[H W / 4, 4, ...]`` 2x2 blocks in row-major block order."""
    H, W = a.shape[:2]
    rest = a.shape[2:]
    b = a.reshape(H // 2, 2, W // 2, 2, *rest).transpose(1, 2)
    return b.reshape(H * W // 4, 4, *rest)


def from_blocks(b: torch.Tensor, res: tuple[int, int]) -> torch.Tensor:
    """Inverse of :func:`to_blocks`."""
    H, W = res
    rest = b.shape[2:]
    return b.reshape(H // 2, W // 2, 2, 2, *rest).transpose(1, 2).reshape(H, W, *rest)
