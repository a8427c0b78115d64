"""Losses and L1 metrics shared by the stages and the quality bench."""

from __future__ import annotations

import torch

from vrneural.distill.data import SliceData, from_blocks
from vrneural.distill.models import NeuralModel


def to_space(y: torch.Tensor, space: str) -> torch.Tensor:
    """Linear BTF values -> the loss space (``log`` means ``log(1 + y)``)."""
    return torch.log1p(y) if space == "log" else y


def space_l1(raw: torch.Tensor, target: torch.Tensor, space: str) -> torch.Tensor:
    """L1 between a model's raw output and linear targets, in the output's space.

    The raw value (before the ``max(r, 0)`` of the output transform) is used: its L1 bounds
    the clamped one from above and keeps a gradient where the clamp is inactive.
    """
    return (raw - to_space(target, space)).abs().mean()


def test_pairs(data: SliceData, max_slices: int) -> list[int]:
    """The held-out pairs used per epoch: all, or ``max_slices`` evenly spaced ones."""
    t = data.test
    if max_slices <= 0 or len(t) <= max_slices:
        return list(t)
    idx = torch.linspace(0, len(t) - 1, max_slices).round().long().tolist()
    return [t[i] for i in idx]


@torch.no_grad()
def predict_slice(model: NeuralModel, data: SliceData, pair: int) -> torch.Tensor:
    """The model's BTF slice ``[H, W, 3]`` at texel centres (linear)."""
    wi, wo = data.dirs(pair)
    return from_blocks(model.predict(wi, wo, data.uv(None, shard=False)), data.res)


@torch.no_grad()
def mean_l1(model: NeuralModel, data: SliceData, pairs: list[int]) -> float:
    """Mean absolute error (linear BTF units) over ``pairs``, all texels and channels."""
    uv = data.uv(None, shard=False)
    total = 0.0
    for p in pairs:
        wi, wo = data.dirs(p)
        total += float((model.predict(wi, wo, uv) - data.target(p, shard=False)).abs().mean())
    return total / max(len(pairs), 1)


def mean_value(data: SliceData, pairs: list[int]) -> float:
    """Mean absolute value of the targets over ``pairs``: the L1 of a model that predicts
    black, the scale against which a test L1 reads as a fraction."""
    total = 0.0
    for p in pairs:
        total += float(data.target(p, shard=False).abs().mean())
    return total / max(len(pairs), 1)
