"""A model's plain forms: the ``spec`` dict it is built from (stored in checkpoints; no
pickled classes), per method (:func:`make_spec`: the teacher, the NeuMIP and single-level
baselines, the student), and the :class:`~vrneural.material.NeuralMaterial` it exports to
(:func:`material_of`)."""

from __future__ import annotations

import numpy as np
import torch

from vrneural.material import DIR_INPUTS, NeuralMaterial

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


def latent_widths(spec: dict) -> list[int]:
    """The widths of the two hidden vectors of a spec's network that distillation matches
    (``latent_layers``; the student's: z_c, M_c's output, and M_f's hidden layer)."""
    if spec["arch"] == "single":
        return [spec["hidden"][i] for i in spec["latent_layers"]]
    return [spec["coarse_hidden"][-1], spec["fine_hidden"][0]]


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


def material_of(model, meta: dict | None = None) -> NeuralMaterial:
    """The runtime form of ``model`` (a :class:`~vrneural.distill.models.NeuralModel`): weights
    float32, textures float16 with their pyramid levels, the view lookup's field or network."""
    names = [k for k in model.tex if "@" not in k]
    texs = {k: model.tex[k].detach().half().numpy() for k in names}
    levels = {
        k: [model.texture(k, lv).detach().half().numpy() for lv in range(1, model.lod_levels)]
        for k in names
    }
    if model.arch == "single":
        nets = {"mlp": model.mlp.to_layers()}
        nets["mlp"][0].weight[:, :DIR_INPUTS] *= model.dir_mask.cpu().numpy()  # unread: 0
    else:
        nets = {"coarse": model.coarse.to_layers(), "fine": model.fine.to_layers()}
    rng = {} if model.dir_range is None else {"dir_range": model.dir_range}
    if model.lod_levels > 1:
        rng["levels"] = levels
    if model.parallax_steps:
        rng["parallax"] = {
            "kind": "height",
            "steps": model.parallax_steps,
            "march": model.parallax_march,
        }
        rng["height"] = model.height.cpu().numpy().astype(np.float16)
    if model.parallax_kind == "neural":
        rng["parallax"] = {"kind": "neural", "march": model.parallax_march}
        rng["offset_net"] = model.offset_mlp.to_layers()
        rng["offset_tex"] = model.offset_tex.detach().cpu().half().numpy()
    return NeuralMaterial(model.arch, nets, texs, model.output, meta or {}, **rng)
