"""The neural material of the paper's section 4.1 (Eq. 3-4) as a trainable torch model: the
same function as :func:`vrneural.material.material_forward` computes for the exported pack.

Every model maps one angular condition ``(wi, wo)`` and the material UVs of 2x2 texel blocks
``uv: [N, 4, 2]`` to BTF values ``[N, 4, 3]``:

- ``coarse_fine`` (the student): ``z_c = M_c([wi, wo, h, U_c(u_c)])`` once per block, at its
  mean ``u_c`` (one texel of the half-resolution ``U_c`` per 2x2 block), then per texel
  ``y_k = out(M_f([z_c, U_f(u_k)]))``;
- ``single`` (the teacher, NeuMIP, the single-level ablation): ``y_k = out(M([wi, wo, h,
  U(u_k)]))`` per texel.

Neural textures are float32 parameters rounded to float16 in the forward pass (straight-through
gradient), so the trained model *is* the f16 pack. The lookups (bilinear, parallax, neural
offset), the MLP and the specs per method are in :mod:`~vrneural.distill.lookups` and
:mod:`~vrneural.distill.specs`.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

from vrneural.distill.lookups import (
    MLP,
    apply_output,
    avg_pool_levels,
    extend_dirs,
    f16_round,
    half_vector,
    offset_depth,
    sample_bilinear_wrap,
    setup_view_lookup,
    view_lookup,
)
from vrneural.distill.specs import dir_mask, make_spec, material_of  # noqa: F401 (make_spec: re-exported)
from vrneural.material import DIR_INPUTS, NeuralMaterial


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
        # the lookup moved along the view ray: none, height-field parallax or neural offset
        setup_view_lookup(self, spec.get("parallax") or {"kind": "off"}, tex)
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
        wo = extend_dirs(self.dir_range, wi, wo)[1]
        tex = f16_round(self.offset_tex)
        return offset_depth(self.offset_mlp, tex, wo, uv, self.parallax_march)

    def set_height(self, height: np.ndarray) -> None:
        """The height field ``[H, W]`` (UV units) parallax marches, rounded to float16 (the
        pack's)."""
        h = torch.from_numpy(np.asarray(height, np.float16).astype(np.float32))
        if h.shape != self.height.shape:
            raise ValueError(f"height field {list(h.shape)} != {list(self.height.shape)}")
        self.height.copy_(h)

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
        wi, wo, _ = extend_dirs(self.dir_range, wi, wo)  # beyond the training range
        uv = view_lookup(self, wo, uv)  # parallax or neural offset, where the spec has one
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
        weight = extend_dirs(self.dir_range, wi, wo)[2]
        return y if weight is None else y * weight

    def to_material(self, meta: dict | None = None) -> NeuralMaterial:
        """The runtime form (:func:`~vrneural.distill.specs.material_of`): the pack."""
        return material_of(self, meta)
