"""The method of the paper's section 4 as it is trained here, over in-memory objects alone
(no path, lock, checkpoint or output is seen in this module).

- 4.1, Eq. 3-4, the coarse-to-fine neural material: :class:`~vrneural.distill.models.NeuralModel`
  with ``arch="coarse_fine"`` (the coarse MLP M_c on the directions, the half vector and U_c
  gives z_c, shared by a 2x2 texel square; the fine MLP M_f on z_c and U_f gives each texel).
- 4.3, Eq. 5, distillation: :class:`DistillNet`, the student's loss against the ground truth,
  the teacher's output and two of its latent vectors through the learnt maps T_1, T_2.
- 4.4, training: one ``(wi, wo)`` slice per step (:func:`epoch_steps`) in a seeded order
  (:func:`epoch_order`), Adam; the weight average of :class:`Ema` is the exported network.
"""

from __future__ import annotations

import contextlib
import math

import torch
import torch.distributed as dist
from torch import nn

from vrneural.distill.data import SliceData
from vrneural.distill.evaluate import space_l1, to_space
from vrneural.distill.models import apply_output


def _latent_widths(spec: dict) -> list[int]:
    if spec["arch"] == "single":
        return [spec["hidden"][i] for i in spec["latent_layers"]]
    return [spec["coarse_hidden"][-1], spec["fine_hidden"][0]]


class DistillNet(nn.Module):
    """Student + T maps; ``forward`` returns the Eq. 5 loss of one slice (this rank's share)."""

    def __init__(self, model, teacher, data: SliceData, cfg):
        super().__init__()
        self.model = model
        self.data = data
        self.cfg = cfg
        self.space = cfg.space
        self.teacher = [teacher]  # a list: not a submodule (frozen, not synchronised by DDP)
        if cfg.distill:
            dt = [teacher.spec["hidden"][i] for i in teacher.latent_layers]
            ds = _latent_widths(model.spec)
            self.T1 = nn.Linear(dt[0], ds[0], bias=False)
            self.T2 = nn.Linear(dt[1], ds[1], bias=False)

    def lod_loss(self, wi, wo, pair):
        """The prefiltered levels' L1 (each level's output at its texel centres against the
        slice averaged over its texels), weighted by ``lod_weight`` shared by the levels; None
        with one level. No jitter: the level's lookups are the exact box averages of level 0's
        texels, and nothing random is drawn, so a resumed run stays bit for bit."""
        levels = self.model.lod_levels
        if levels <= 1:
            return None
        total = 0.0
        for k in range(1, levels):
            uv = self.data.uv_level(k, None)
            raw, _ = self.model(wi, wo, uv, k)
            total = total + space_l1(raw, self.data.target_level(pair, k), self.space)
        return self.cfg.lod_weight * total / (levels - 1)

    def forward(self, wi, wo, uv, pair):
        raw, zs = self.model(wi, wo, uv)
        gt = space_l1(raw, self.data.target(pair), self.space)
        lod = self.lod_loss(wi, wo, pair)
        gt_total = gt if lod is None else gt + lod
        if not self.cfg.distill:
            return gt_total, {"gt": gt.detach()}
        teacher = self.teacher[0]
        with torch.no_grad():
            raw_t, zt = teacher(wi, wo, uv)
            yt = to_space(apply_output(raw_t, teacher.output), self.space)
        out = (raw - yt).abs().mean()
        l1 = ((zs[0] - self.T1(zt[0])) ** 2).mean()
        l2 = ((zs[1] - self.T2(zt[1])) ** 2).mean()
        c = self.cfg
        loss = gt_total + c.sigma * out + c.lambda1 * l1 + c.lambda2 * l2
        parts = {"gt": gt.detach(), "teacher": out.detach()}
        if getattr(c, "offset_weight", 0.0) and self._both_neural():
            # the student's neural-offset depth against the teacher's (texels, L1)
            with torch.no_grad():
                rt = teacher.depth(wi, wo, uv)
            depth = (self.model.depth(wi, wo, uv) - rt).abs().mean()
            loss = loss + c.offset_weight * depth
            parts["depth"] = depth.detach()
        return loss, parts

    def _both_neural(self) -> bool:
        """Whether student and teacher both have a neural offset (its depth is distilled)."""
        return self.model.parallax_kind == "neural" == self.teacher[0].parallax_kind


class NonFiniteLossError(ArithmeticError):
    """A step's loss was NaN or infinite (raised before the step: the weights stay finite)."""

    def __init__(self, value: float):
        super().__init__(f"loss is {value}")
        self.value = value


def _seed(seed: int, epoch: int, salt: int) -> int:
    return (seed * 1_000_003 + epoch * 7_919 + salt) % (2**63)


def epoch_order(seed: int, epoch: int, n: int, gen: torch.Generator, step: int = 0):
    """The order of the ``n`` training slices in ``epoch`` (a permutation seeded by ``(seed,
    epoch)``); at the epoch's start (``step`` 0) the jitter generator ``gen`` is seeded too,
    so a run resumed mid-epoch (its ``gen`` state restored) replays the same draws."""
    order = torch.randperm(n, generator=torch.Generator().manual_seed(_seed(seed, epoch, 1)))
    if step == 0:
        gen.manual_seed(_seed(seed, epoch, 2))
    return order


def epoch_steps(
    model: nn.Module,
    opt: torch.optim.Optimizer,
    data: SliceData,
    order: torch.Tensor,
    start: int = 0,
    gen: torch.Generator | None = None,
    ema: Ema | None = None,
    world: int = 1,
):
    """One epoch of gradient steps, from step ``start``: one slice ``data.train[order[k]]``
    per step, its texel positions jittered by ``gen`` (None: texel centres); ``model(wi, wo,
    uv, pair) -> (loss, parts)`` is e.g. a :class:`DistillNet`. Yields each step's loss (the
    whole slice's, a mean over ``world`` ranks) after its step; :class:`NonFiniteLossError` before
    a step whose loss is not finite."""
    for step in range(start, len(order)):
        pair = data.train[int(order[step])]
        wi, wo = data.dirs(pair)
        uv = data.uv(gen)
        loss, _ = model(wi, wo, uv, pair)
        value = _mean_over_ranks(loss.detach(), world)
        if not math.isfinite(value):
            raise NonFiniteLossError(value)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        if ema is not None:
            ema.update()
        yield value


def _mean_over_ranks(loss: torch.Tensor, world: int) -> float:
    """The loss of the whole slice: each rank's is the mean over its equal share, so their
    mean (the curve, the checkpoint and the bar say what one process would; every rank sees a
    NaN together, so none waits for one that stopped)."""
    if world == 1:
        return float(loss)
    t = loss.reshape(1).clone()
    dist.all_reduce(t)
    return float(t) / world


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
