"""Torch twins of :mod:`vrneural.material`: the same function, trainable.

Every model maps one angular condition ``(wi, wo)`` and the material UVs of 2x2 texel blocks
``uv: [N, 4, 2]`` to BTF values ``[N, 4, 3]`` exactly as :func:`vrneural.material.material_forward`
does for the exported pack:

- ``single``: ``y_k = out(M([wi, wo, h, U(u_k)]))`` per texel;
- ``coarse_fine``: ``z_c = M_c([wi, wo, h, U_c(u_c)])`` at the block mean ``u_c``, then
  ``y_k = out(M_f([z_c, U_f(u_k)]))``.

Neural textures are float32 parameters rounded to float16 in the forward pass (straight-through
gradient), so the trained model *is* the f16 pack. A model is described by a plain ``spec`` dict
(stored in checkpoints; no pickled classes).
"""

from __future__ import annotations

import itertools

import numpy as np
import torch
from torch import nn

from vrneural.grazing import boundary_consts
from vrneural.material import DIR_INPUTS, HALF_EPS2, NeuralMaterial
from vrneural.mlp import Layer


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
    from vrneural.neural_offset import VIEW_INPUTS

    u = uv.mean(1, keepdim=True) if march == "block" else uv  # [N, 1 or 4, 2]
    psi = sample_bilinear_wrap(tex, u)
    view = wo[:VIEW_INPUTS].to(psi.dtype).expand(*psi.shape[:-1], VIEW_INPUTS)
    r, _ = mlp(torch.cat([psi, view], -1))
    return r.expand(uv.shape[0], 4, 1)


def offset_uv(mlp, tex: torch.Tensor, wo: torch.Tensor, uv: torch.Tensor, march: str = "texel"):
    """Twin of :func:`vrneural.neural_offset.offset_uv` for one view ``wo: [3]``: the blocks'
    UVs ``uv: [N, 4, 2]`` moved by NeuMIP's neural offset (offset texture ``tex: [H, W, C]``,
    offset MLP ``mlp``) -> ``[N, 4, 2]``; differentiable in both (trained with the rest)."""
    from vrneural.neural_offset import MIN_COS

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


class NeuralModel(nn.Module):
    """A ``single`` or ``coarse_fine`` neural material built from ``spec`` (see :func:`make_spec`).

    ``forward(wi [3], wo [3], uv [N, 4, 2])`` returns ``raw [N, 4, 3]`` (before the output
    transform) and ``latents``: the two hidden vectors distillation matches (``[N, 4, D]`` each).
    """

    def __init__(self, spec: dict, seed: int = 0):
        super().__init__()
        self.spec = dict(spec)
        torch.manual_seed(seed)
        g = torch.Generator().manual_seed(seed + 1)
        self.arch = spec["arch"]
        self.output = spec["output"]

        def tex(res, c):
            return nn.Parameter(torch.randn(res[0], res[1], c, generator=g) * spec["tex_init"])

        if self.arch == "single":
            c = spec["channels"]
            self.mlp = MLP([DIR_INPUTS + c, *spec["hidden"], 3])
            self.tex = nn.ParameterDict({"features": tex(spec["tex_res"], c)})
            with torch.no_grad():  # unused direction inputs: zero weights, never updated
                self.mlp.layers[0].weight[:, :DIR_INPUTS] *= dir_mask(spec)
        elif self.arch == "coarse_fine":
            cc, cf = spec["coarse_channels"], spec["fine_channels"]
            self.coarse = MLP([DIR_INPUTS + cc, *spec["coarse_hidden"]], last_act="relu")
            self.fine = MLP([spec["coarse_hidden"][-1] + cf, *spec["fine_hidden"], 3])
            self.tex = nn.ParameterDict(
                {"coarse": tex(spec["coarse_res"], cc), "fine": tex(spec["fine_res"], cf)}
            )
        else:
            raise ValueError(f"unknown arch {self.arch!r}")
        #: prefiltered neural textures (issue #39): ``levels`` pyramid levels, either the box
        #: averages of level 0 (``"filter"``: the filter-aware MIP maps paper's linear latent
        #: downsampling, no parameters added) or trained per level (``"levels"``: NeuMIP's)
        lod = spec.get("lod") or {"levels": 1, "kind": "filter"}
        self.lod_levels, self.lod_kind = int(lod["levels"]), lod["kind"]
        if self.lod_kind == "levels":
            for name in list(self.tex):
                t = self.tex[name]
                for k in range(1, self.lod_levels):
                    self.tex[f"{name}@{k}"] = tex((t.shape[0] >> k, t.shape[1] >> k), t.shape[2])
        self.latent_layers = spec["latent_layers"]
        self.register_buffer("dir_mask", dir_mask(spec), persistent=False)
        #: height-field parallax (vrneural.parallax): spec ``{"kind": "height", "steps": n,
        #: "res": [H, W]}``; the field itself is a buffer set by :meth:`set_height` (float16
        #: values, UV units) and saved with the weights
        par = spec.get("parallax") or {"kind": "off"}
        self.parallax_steps = int(par["steps"]) if par["kind"] == "height" else 0
        self.parallax_march = par.get("march", "texel")
        self.parallax_kind = par["kind"]
        if par["kind"] == "neural":  # NeuMIP's offset module (vrneural.neural_offset)
            from vrneural.neural_offset import VIEW_INPUTS

            oc = int(par["channels"])
            self.offset_mlp = MLP([oc + VIEW_INPUTS, *par["hidden"], 1])
            self.offset_tex = tex(tuple(par["res"]), oc)
            with torch.no_grad():  # starts as no offset: the depth is trained up from 0
                self.offset_mlp.layers[-1].weight.zero_()
                self.offset_mlp.layers[-1].bias.zero_()
        if self.parallax_steps:
            self.register_buffer("height", torch.zeros(tuple(par["res"])))
            from vrneural.grazing import boundary_consts
            from vrneural.parallax import slope_max

            cs = boundary_consts(par["theta_o_max"])
            self.parallax_t_max = float(slope_max(*cs, tuple(par["res"])))
        #: (theta_i_max, theta_o_max) degrees of the training data, set for evaluation
        #: (:func:`vrneural.distill.checkpoint.model_from_checkpoint`); None while training on
        #: the BTF's own directions, where the extension beyond them is the identity
        self.dir_range: tuple[float, float] | None = None

    def texture_parameters(self) -> list[nn.Parameter]:
        """The neural textures' parameters (trained at the texture learning rate): the
        textures and their levels, and the neural offset's texture where it has one."""
        extra = [self.offset_tex] if self.parallax_kind == "neural" else []
        return [*self.tex.parameters(), *extra]

    def depth(self, wi: torch.Tensor, wo: torch.Tensor, uv: torch.Tensor) -> torch.Tensor:
        """The neural offset's ray depth ``[N, 4, 1]`` (texels) at the blocks ``uv`` along the
        (extended) view ``wo`` (distillation matches the student's to the teacher's)."""
        wo = self._extended(wi, wo)[1]
        tex = f16_round(self.offset_tex)
        return offset_depth(self.offset_mlp, tex, wo, uv, self.parallax_march)

    def set_height(self, height: np.ndarray) -> None:
        """The height field ``[H, W]`` (UV units) parallax marches, rounded to float16 (the
        pack's)."""
        h = torch.from_numpy(np.asarray(height, np.float16).astype(np.float32))
        if h.shape != self.height.shape:
            raise ValueError(f"height field {list(h.shape)} != {list(self.height.shape)}")
        self.height.copy_(h)

    def _extended(self, wi: torch.Tensor, wo: torch.Tensor):
        """``(wi, wo, light weight)`` as :func:`vrneural.grazing.extend` gives them."""
        if self.dir_range is None:
            return wi, wo, None
        ci, si = (float(x) for x in boundary_consts(self.dir_range[0]))
        co, so = (float(x) for x in boundary_consts(self.dir_range[1]))
        weight = torch.clamp(wi[..., 2] / ci, 0.0, 1.0)
        return to_range(wi, ci, si), to_range(wo, co, so), weight

    def texture(self, name: str, level: int = 0) -> torch.Tensor:
        """Neural texture ``name`` at pyramid level ``level`` (float16-rounded: the pack)."""
        if level == 0:
            return f16_round(self.tex[name])
        if self.lod_kind == "filter":
            return f16_round(avg_pool_levels(f16_round(self.tex[name]), level))
        return f16_round(self.tex[f"{name}@{level}"])

    def forward(self, wi: torch.Tensor, wo: torch.Tensor, uv: torch.Tensor, level: int = 0):
        raw, acts = self.activations(wi, wo, uv, level)
        if self.arch == "single":
            hs = acts["mlp"]
        else:
            n = uv.shape[0]
            hs = [h[:, None].expand(n, 4, h.shape[-1]) for h in acts["coarse"]] + acts["fine"]
        return raw, [hs[i] for i in self.latent_layers]

    def activations(self, wi: torch.Tensor, wo: torch.Tensor, uv: torch.Tensor, level: int = 0):
        """``raw [N, 4, 3]`` and every layer's output per network: ``{"mlp": [...]}``
        (``[N, 4, D]`` each) or ``{"coarse": [...] ([N, D], once per block), "fine": [...]}``;
        the neural textures at pyramid level ``level``."""
        n = uv.shape[0]
        wi, wo, _ = self._extended(wi, wo)
        if self.parallax_steps:
            uv = parallax_uv(
                self.height, wo, uv, self.parallax_steps, self.parallax_t_max, self.parallax_march
            )
        elif self.parallax_kind == "neural":
            uv = offset_uv(self.offset_mlp, f16_round(self.offset_tex), wo, uv, self.parallax_march)
        dirs = torch.cat([wi, wo, half_vector(wi, wo)]) * self.dir_mask  # [9]
        if self.arch == "single":
            f = sample_bilinear_wrap(self.texture("features", level), uv)  # [N, 4, C]
            x = torch.cat([dirs.expand(n, 4, DIR_INPUTS), f], -1)
            raw, hs = self.mlp(x)
            return raw, {"mlp": hs}
        fc = sample_bilinear_wrap(self.texture("coarse", level), uv.mean(1))  # [N, Cc]
        z, hc = self.coarse(torch.cat([dirs.expand(n, DIR_INPUTS), fc], -1))  # [N, Z]
        ff = sample_bilinear_wrap(self.texture("fine", level), uv)  # [N, 4, Cf]
        zk = z[:, None].expand(n, 4, z.shape[-1])
        raw, hf = self.fine(torch.cat([zk, ff], -1))
        return raw, {"coarse": hc, "fine": hf}

    def predict(self, wi, wo, uv, level: int = 0) -> torch.Tensor:
        """BTF values ``[N, 4, 3]`` (output transform applied; beyond ``dir_range`` extended as
        :func:`vrneural.grazing.extend` does), neural textures at pyramid level ``level``."""
        y = apply_output(self(wi, wo, uv, level)[0], self.output)
        weight = self._extended(wi, wo)[2]
        return y if weight is None else y * weight

    def to_material(self, meta: dict | None = None) -> NeuralMaterial:
        """The runtime form (weights float32, textures float16, with their pyramid levels)."""
        names = [k for k in self.tex if "@" not in k]
        texs = {k: self.tex[k].detach().half().numpy() for k in names}
        levels = {
            k: [self.texture(k, lv).detach().half().numpy() for lv in range(1, self.lod_levels)]
            for k in names
        }
        if self.arch == "single":
            nets = {"mlp": self.mlp.to_layers()}
            nets["mlp"][0].weight[:, :DIR_INPUTS] *= self.dir_mask.cpu().numpy()  # unread: 0
        else:
            nets = {"coarse": self.coarse.to_layers(), "fine": self.fine.to_layers()}
        rng = {} if self.dir_range is None else {"dir_range": self.dir_range}
        if self.lod_levels > 1:
            rng["levels"] = levels
        if self.parallax_steps:
            rng["parallax"] = {
                "kind": "height",
                "steps": self.parallax_steps,
                "march": self.parallax_march,
            }
            rng["height"] = self.height.cpu().numpy().astype(np.float16)
        if self.parallax_kind == "neural":
            rng["parallax"] = {"kind": "neural", "march": self.parallax_march}
            rng["offset_net"] = self.offset_mlp.to_layers()
            rng["offset_tex"] = self.offset_tex.detach().cpu().half().numpy()
        return NeuralMaterial(self.arch, nets, texs, self.output, meta or {}, **rng)


DIR_MODES = {
    # which of the 9 direction inputs (wi, wo, h) a network reads
    "full": [1, 1, 1, 1, 1, 1, 1, 1, 1],
    # NeuMIP's own input: wi and wo as 2D points on the projected hemisphere (x, y)
    "xy": [1, 1, 0, 1, 1, 0, 0, 0, 0],
}


def dir_mask(spec: dict) -> torch.Tensor:
    """``[9]`` 0/1 mask of the direction inputs a model reads (``spec["dir_inputs"]``).

    A masked input is multiplied by zero; its first-layer weights start at zero, get exactly
    zero gradient (Adam never moves them) and are exported as zeros, so the runtime pack
    format is unchanged and the generated shaders skip them.
    Only ``single`` networks take a mask; specs without the field read all nine inputs.
    """
    mode = spec.get("dir_inputs", "full")
    if mode not in DIR_MODES or (mode != "full" and spec["arch"] != "single"):
        raise ValueError(f"dir_inputs {mode!r} not supported for arch {spec['arch']!r}")
    return torch.tensor(DIR_MODES[mode], dtype=torch.float32)


def spec_width(spec: dict) -> int:
    """The hidden width of a spec's network (its widest hidden layer; for the coarse-to-fine
    student, M_c's, which ``make_spec`` sets to M_f's)."""
    return max(spec.get("coarse_hidden") or spec["hidden"])


def make_spec(method: str, res: tuple[int, int], space: str = "linear", **kw) -> dict:
    """Architecture of each method, as a plain dict. ``res = (H, W)`` of the BTF.

    teacher: 4 linear layers, 128 wide, 8-channel full-res texture (``single``);
    neumip: 4 x 25, 7 channels, log(1+y) output, direction inputs ``kw["neumip_dirs"]``
    (default ``xy``: wi.xy and wo.xy as in NeuMIP, no half vector; ``full``: wi, wo, h)
    (``single``); single8: 4 x 8, 8 channels;
    student: M_c 2 x 8 (the second layer's output is z_c), M_f 8 -> 3, U_c 8 ch at half
    resolution (one texel per 2x2 block), U_f 8 ch at full resolution (``coarse_fine``).
    ``kw["width"]`` (default 8) sets the hidden width of single8 and the student.
    """
    out = "log1p" if space == "log" else "linear"
    H, W = res
    narrow = kw.get("width", 8)  # single8 and the student
    if method == "teacher":
        width, layers = kw.get("width", 128), kw.get("layers", 4)
        hidden = [width] * (layers - 1)
        return dict(
            arch="single",
            output=out,
            channels=kw.get("channels", 8),
            tex_res=[H, W],
            hidden=hidden,
            latent_layers=[len(hidden) - 2, len(hidden) - 1],
            tex_init=0.1,
        )
    if method in ("neumip", "single8"):
        width, c = (25, 7) if method == "neumip" else (narrow, 8)
        if method == "neumip":
            out = "log1p"
        return dict(
            arch="single",
            output=out,
            channels=c,
            tex_res=[H, W],
            hidden=[width] * 3,
            latent_layers=[1, 2],
            tex_init=0.1,
            dir_inputs=kw.get("neumip_dirs", "xy") if method == "neumip" else "full",
        )
    if method == "student":
        return dict(
            arch="coarse_fine",
            output=out,
            coarse_channels=kw.get("coarse_channels", 8),
            coarse_res=[H // 2, W // 2],
            fine_channels=kw.get("fine_channels", 8),
            fine_res=[H, W],
            coarse_hidden=[narrow] * 2,
            fine_hidden=[narrow],
            latent_layers=[1, 2],
            tex_init=0.1,
        )
    raise ValueError(f"unknown method {method!r}")
