"""Torch twins of :mod:`vrneural.material`'s lookups and layers, from which
:class:`~vrneural.distill.models.NeuralModel` is built: the half vector, the direction range,
the bilinear wrap lookup, the lookups moved along the view ray (height-field parallax and
NeuMIP's neural offset), the box prefilter of a texture's pyramid, float16 rounding and the
MLP. Each computes what its numpy twin computes for the exported pack, differentiably.
"""

from __future__ import annotations

import itertools

import numpy as np
import torch
from torch import nn

from vrneural.grazing import boundary_consts
from vrneural.material import HALF_EPS2
from vrneural.mlp import Layer
from vrneural.neural_offset import MIN_COS, VIEW_INPUTS


def half_vector(wi: torch.Tensor, wo: torch.Tensor) -> torch.Tensor:
    """``normalize(wi + wo)`` ``[..., 3]``; ``(0, 0, 1)`` where ``|wi + wo|^2 < 1e-12``."""
    s = wi + wo
    n2 = (s * s).sum(-1, keepdim=True)
    ok = n2 >= HALF_EPS2
    up = torch.tensor([0.0, 0.0, 1.0], dtype=s.dtype, device=s.device)
    return torch.where(ok, s / torch.sqrt(torch.where(ok, n2, torch.ones_like(n2))), up)


def to_range(w: torch.Tensor, cos_max: float, sin_max: float) -> torch.Tensor:
    """Twin of :func:`vrneural.grazing.to_range` for ``w: [..., 3]``: a direction below polar
    angle ``acos(cos_max)`` moved onto it at the same azimuth (``+x`` where undefined)."""
    r2 = (w[..., :2] * w[..., :2]).sum(-1, keepdim=True)
    ok = r2 >= 1e-20
    fallback = torch.tensor([sin_max, 0.0], dtype=w.dtype, device=w.device)
    xy = torch.where(ok, w[..., :2] * (sin_max / torch.sqrt(torch.where(ok, r2, 1.0))), fallback)
    edge = torch.cat([xy, torch.full_like(r2, cos_max)], -1)
    return torch.where(w[..., 2:] >= cos_max, w, edge)


def extend_dirs(dir_range: tuple[float, float] | None, wi: torch.Tensor, wo: torch.Tensor):
    """``(wi, wo, light weight)`` as :func:`vrneural.grazing.extend` gives them for a model
    trained on directions up to ``dir_range = (theta_i_max, theta_o_max)`` degrees: moved onto
    that range (:func:`to_range`); unchanged, with weight None, where ``dir_range`` is None."""
    if dir_range is None:
        return wi, wo, None
    ci, si = (float(x) for x in boundary_consts(dir_range[0]))
    co, so = (float(x) for x in boundary_consts(dir_range[1]))
    weight = torch.clamp(wi[..., 2] / ci, 0.0, 1.0)
    return to_range(wi, ci, si), to_range(wo, co, so), weight


def sample_bilinear_wrap(tex: torch.Tensor, uv: torch.Tensor) -> torch.Tensor:
    """Bilinear wrap lookup of ``tex: [H, W, C]`` at ``uv: [..., 2]`` -> ``[..., C]``.

    The formula of :func:`vrneural.material.sample_bilinear_wrap` (texel centres at
    ``(x + 0.5) / W``; coordinates in float64, weights in float32); differentiable in ``tex``.
    """
    H, W = tex.shape[:2]
    x = uv[..., 0].double() * W - 0.5
    y = uv[..., 1].double() * H - 0.5
    x0 = torch.floor(x)
    y0 = torch.floor(y)
    fx = (x - x0).float()[..., None]
    fy = (y - y0).float()[..., None]
    xi0 = x0.long() % W
    yi0 = y0.long() % H
    xi1 = (xi0 + 1) % W
    yi1 = (yi0 + 1) % H
    top = tex[yi0, xi0] * (1 - fx) + tex[yi0, xi1] * fx
    bot = tex[yi1, xi0] * (1 - fx) + tex[yi1, xi1] * fx
    return top * (1 - fy) + bot * fy


def parallax_uv(
    height: torch.Tensor,
    wo: torch.Tensor,
    uv: torch.Tensor,
    steps: int,
    t_max: float,
    march: str = "texel",
) -> torch.Tensor:
    """Twin of :func:`vrneural.parallax.parallax_uv` for one view ``wo: [3]`` (``wo.z > 0``):
    the blocks' UVs ``uv: [N, 4, 2]`` moved to where the view ray meets ``height: [H, W]``
    (float16-valued, UV units) -> ``[N, 4, 2]``. No gradient (the field is data)."""
    with torch.no_grad():
        H, W = height.shape
        d = torch.stack([wo[0] / wo[2], wo[1] / wo[2] * (W / H)]).to(uv.dtype)  # [2]
        if march == "block":
            hit = march_hits(height, uv.mean(1), d, steps, t_max)  # [N]
            return uv + (hit[:, None] * d)[:, None, :]
        u = uv.reshape(-1, 2)
        return (u + march_hits(height, u, d, steps, t_max)[:, None] * d).reshape(uv.shape)


def march_hits(height, u: torch.Tensor, d: torch.Tensor, steps: int, t_max: float):
    """Twin of :func:`vrneural.parallax.march_hits` for one slope ``d: [2]``: ``[M]``."""
    tex = height[..., None]
    hmin, hmax = height.min(), height.max()
    t = torch.sqrt((d * d).sum())
    n = int(torch.clamp(torch.ceil(float(steps) * t / np.float32(t_max)), 1, steps))
    dz = (hmax - hmin) / n

    def field(z):
        return sample_bilinear_wrap(tex, u + z[:, None] * d)[:, 0]

    z_prev = hmax.expand(len(u)).clone()
    h_prev = field(z_prev)
    done = h_prev >= z_prev
    hit = torch.where(done, hmax, hmin)
    for k in range(1, n + 1):
        z = (hmax - float(k) * dz).expand(len(u))
        h = field(z)
        now = ~done & (z <= h)
        a = z_prev - h_prev
        tt = a / torch.where(now, a - (z - h), torch.ones_like(a))
        hit = torch.where(now, z_prev + tt * (z - z_prev), hit)
        done = done | now
        z_prev, h_prev = z, h
    return hit


def offset_depth(mlp, tex: torch.Tensor, wo: torch.Tensor, uv: torch.Tensor, march: str = "texel"):
    """The neural offset's ray depth (texels) per texel ``[N, 4, 1]`` of the blocks ``uv:
    [N, 4, 2]`` seen along ``wo: [3]`` (once per block and repeated for ``march = "block"``)."""
    u = uv.mean(1, keepdim=True) if march == "block" else uv  # [N, 1 or 4, 2]
    psi = sample_bilinear_wrap(tex, u)
    view = wo[:VIEW_INPUTS].to(psi.dtype).expand(*psi.shape[:-1], VIEW_INPUTS)
    r, _ = mlp(torch.cat([psi, view], -1))
    return r.expand(uv.shape[0], 4, 1)


def offset_uv(mlp, tex: torch.Tensor, wo: torch.Tensor, uv: torch.Tensor, march: str = "texel"):
    """Twin of :func:`vrneural.neural_offset.offset_uv` for one view ``wo: [3]``: the blocks'
    UVs ``uv: [N, 4, 2]`` moved by NeuMIP's neural offset (offset texture ``tex: [H, W, C]``,
    offset MLP ``mlp``) -> ``[N, 4, 2]``; differentiable in both (trained with the rest)."""
    H, W = tex.shape[:2]
    c = torch.clamp(wo[2], min=MIN_COS)
    s = torch.stack([wo[0] / W / c, wo[1] / H / c]).to(uv.dtype)  # [2]
    return uv + offset_depth(mlp, tex, wo, uv, march) * s


def avg_pool_levels(t: torch.Tensor, level: int) -> torch.Tensor:
    """``t: [H, W, C]`` averaged over ``2^level x 2^level`` texel squares -> ``[H >> level,
    W >> level, C]`` (the box prefilter of a tileable texture; twin of
    :func:`vrneural.material.pool_level`)."""
    s = 1 << level
    H, W, C = t.shape
    return t.reshape(H // s, s, W // s, s, C).mean((1, 3))


def f16_round(t: torch.Tensor) -> torch.Tensor:
    """Round to float16 in the forward pass, identity gradient (straight-through)."""
    return t + (t.detach().half().float() - t.detach())


class MLP(nn.Module):
    """ReLU MLP ``sizes[0] -> ... -> sizes[-1]``; the last layer uses ``last_act``.

    ``forward`` returns the output and the list of every layer's post-activation value.
    """

    def __init__(self, sizes: list[int], last_act: str = "none"):
        super().__init__()
        self.layers = nn.ModuleList(nn.Linear(a, b) for a, b in itertools.pairwise(sizes))
        self.acts = ["relu"] * (len(sizes) - 2) + [last_act]

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, list[torch.Tensor]]:
        hs = []
        for lin, act in zip(self.layers, self.acts, strict=True):
            x = lin(x)
            if act == "relu":
                x = torch.relu(x)
            hs.append(x)
        return x, hs

    def to_layers(self) -> list[Layer]:
        return [
            Layer(
                lin.weight.detach().numpy().astype(np.float32).copy(),
                lin.bias.detach().numpy().astype(np.float32).copy(),
                act,
            )
            for lin, act in zip(self.layers, self.acts, strict=True)
        ]


def apply_output(raw: torch.Tensor, output: str) -> torch.Tensor:
    """The pack's output transform: ``max(r, 0)`` or ``expm1(max(r, 0))``."""
    r = torch.relu(raw)
    return torch.expm1(r) if output == "log1p" else r


def setup_view_lookup(model: nn.Module, par: dict, tex) -> None:
    """Give ``model`` the lookup along the view ray of its spec's ``parallax`` entry: none
    (``{"kind": "off"}``), height-field parallax (:mod:`vrneural.parallax`; ``{"kind":
    "height", "steps": n, "res": [H, W], "theta_o_max": deg}``: the field is a buffer set by
    ``set_height``, float16 values in UV units, saved with the weights) or NeuMIP's neural
    offset (:mod:`vrneural.neural_offset`; its MLP and texture, ``tex(res, channels)``)."""
    model.parallax_steps = int(par["steps"]) if par["kind"] == "height" else 0
    model.parallax_march = par.get("march", "texel")
    model.parallax_kind = par["kind"]
    if par["kind"] == "neural":
        oc = int(par["channels"])
        model.offset_mlp = MLP([oc + VIEW_INPUTS, *par["hidden"], 1])
        model.offset_tex = tex(tuple(par["res"]), oc)
        with torch.no_grad():  # starts as no offset: the depth is trained up from 0
            model.offset_mlp.layers[-1].weight.zero_()
            model.offset_mlp.layers[-1].bias.zero_()
    if model.parallax_steps:
        model.register_buffer("height", torch.zeros(tuple(par["res"])))
        from vrneural.parallax import slope_max

        cs = boundary_consts(par["theta_o_max"])
        model.parallax_t_max = float(slope_max(*cs, tuple(par["res"])))


def view_lookup(model: nn.Module, wo: torch.Tensor, uv: torch.Tensor) -> torch.Tensor:
    """The blocks' UVs ``uv: [N, 4, 2]`` moved along the view ``wo: [3]`` by ``model``'s
    lookup (:func:`setup_view_lookup`) -> ``[N, 4, 2]``; unmoved without one."""
    if model.parallax_steps:
        steps, t_max, march = model.parallax_steps, model.parallax_t_max, model.parallax_march
        return parallax_uv(model.height, wo, uv, steps, t_max, march)
    if model.parallax_kind == "neural":
        tex = f16_round(model.offset_tex)
        return offset_uv(model.offset_mlp, tex, wo, uv, model.parallax_march)
    return uv
