"""Averages in training: of the weights over steps (:class:`Ema`, ``--ema``: an addition to
the paper's section 4.4, off by default) and of a step's loss over the ranks of a ``torchrun``
(:func:`mean_over_ranks`)."""

from __future__ import annotations

import contextlib

import torch
import torch.distributed as dist
from torch import nn


class Ema:
    """Exponential moving average of the trainable parameters (Polyak averaging).

    With one ``(wi, wo)`` slice per step the weights jitter from step to step; the average is
    a better network than the last iterate and a steadier test L1 for ReduceLROnPlateau. The
    decay ramps up as ``min(decay, (1 + t) / (10 + t))`` so early averages do not remember the
    random initialisation. ``applied()`` swaps the average in (evaluation, export) and back.
    """

    def __init__(self, net: nn.Module, decay: float):
        self.decay = decay
        self.params = {k: p for k, p in net.named_parameters() if p.requires_grad}
        self.avg = {k: p.detach().clone() for k, p in self.params.items()}
        self.count = 0

    @torch.no_grad()
    def update(self) -> None:
        self.count += 1
        d = min(self.decay, (1 + self.count) / (10 + self.count))
        for k, p in self.params.items():
            self.avg[k].lerp_(p.detach(), 1.0 - d)

    @contextlib.contextmanager
    def applied(self):
        keep = {k: p.detach().clone() for k, p in self.params.items()}
        with torch.no_grad():
            for k, p in self.params.items():
                p.copy_(self.avg[k])
        try:
            yield
        finally:
            with torch.no_grad():
                for k, p in self.params.items():
                    p.copy_(keep[k])

    def state(self) -> dict:
        return {"avg": {k: v.clone() for k, v in self.avg.items()}, "count": self.count}

    def load(self, state: dict) -> None:
        for k in self.avg:
            self.avg[k].copy_(state["avg"][k])
        self.count = int(state["count"])


def mean_over_ranks(loss: torch.Tensor, world: int) -> float:
    """The loss of the whole slice: each rank's is the mean over its equal share, so their
    mean (the curve, the checkpoint and the bar say what one process would; every rank sees a
    NaN together, so none waits for one that stopped)."""
    if world == 1:
        return float(loss)
    t = loss.reshape(1).clone()
    dist.all_reduce(t)
    return float(t) / world
