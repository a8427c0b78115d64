"""The method of the paper's section 4 as it is trained here, over in-memory objects alone
(no path, lock, checkpoint or output is seen here), with :mod:`vrneural.distill.models` (4.1,
Eq. 3-4: the coarse-to-fine neural material :class:`~vrneural.distill.models.NeuralModel`):

- 4.3, Eq. 5, distillation: :class:`DistillNet`, the student's loss against the ground truth,
  the teacher's output and two of its latent vectors through the learnt maps T_1, T_2.
- 4.4, training: one ``(wi, wo)`` slice per step (:func:`epoch_steps`) in a seeded order
  (:func:`epoch_order`), Adam (optionally averaged: :class:`~vrneural.distill.averages.Ema`).
"""

from __future__ import annotations

import math

import torch
from torch import nn

from vrneural.distill.averages import mean_over_ranks
from vrneural.distill.data import SliceData
from vrneural.distill.evaluate import space_l1, to_space
from vrneural.distill.lookups import apply_output
from vrneural.distill.specs import latent_widths


class DistillNet(nn.Module):
    """Student + T maps; ``forward`` returns the Eq. 5 loss of one slice (this rank's share).
    Without a ``teacher`` (``teach``) or with ``cfg.distill`` off (``--no-distill``) the loss
    is the ground truth's L1 alone (in the output's space)."""

    def __init__(self, model, teacher, data: SliceData, cfg):
        super().__init__()
        self.model = model
        self.data = data
        self.cfg = cfg
        self.space = cfg.space
        self.teacher = [teacher]  # a list: not a submodule (frozen, not synchronised by DDP)
        self.distill = teacher is not None and cfg.distill
        if self.distill:
            dt, ds = latent_widths(teacher.spec), latent_widths(model.spec)  # z_t, z_s widths
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
        if not self.distill:
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
        both_neural = self.model.parallax_kind == "neural" == teacher.parallax_kind
        if getattr(c, "offset_weight", 0.0) and both_neural:
            # the student's neural-offset depth against the teacher's (texels, L1)
            with torch.no_grad():
                rt = teacher.depth(wi, wo, uv)
            depth = (self.model.depth(wi, wo, uv) - rt).abs().mean()
            loss = loss + c.offset_weight * depth
            parts["depth"] = depth.detach()
        return loss, parts


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
    ema=None,
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
        value = mean_over_ranks(loss.detach(), world)
        if not math.isfinite(value):
            raise NonFiniteLossError(value)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        if ema is not None:
            ema.update()
        yield value
