"""Checkpoint -> runtime pack (``.vrnm``), with f16 range report, provenance and metrics.

The ranges follow the NVIDIA real-time neural appearance paper's Fig. 7: per layer the largest
``|value|`` (weights, biases, pre-activations over the training data) against the float16
maximum 65504, and the fraction of non-zero values below the float16 normal minimum 6.1e-5
(which an f16 shader would flush or store as subnormals).
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import torch

from vrneural.btf.format import read_btf
from vrneural.btf.identity import btf_fingerprint, check_btf_record
from vrneural.distill.checkpoint import model_from_checkpoint, recorded_btf
from vrneural.distill.data import SliceData
from vrneural.distill.specs import spec_width
from vrneural.errors import VrnError
from vrneural.formats.f16 import F16_MAX, F16_MIN_NORMAL
from vrneural.formats.vrnm import write_vrnm
from vrneural.grazing import directions_range
from vrneural.material import NeuralMaterial, half_vector, material_forward, sample_bilinear_wrap
from vrneural.outputs import check_output, check_outputs, file_sha256

RANGE_PAIRS = 16  # training slices used for activation ranges


def value_range(a: np.ndarray) -> dict:
    """``max_abs``, ``headroom`` (65504 / max_abs) and ``frac_below_f16_normal`` of ``a``."""
    a = np.abs(np.asarray(a, np.float64)).ravel()
    nz = a[a > 0]
    m = float(a.max(initial=0.0))
    return {
        "max_abs": m,
        "headroom": float(F16_MAX / m) if m > 0 else None,
        "frac_below_f16_normal": float((nz < F16_MIN_NORMAL).mean()) if nz.size else 0.0,
        "frac_zero": float(1 - nz.size / max(a.size, 1)),
    }


def _run_layers(x: np.ndarray, layers, tag: str, out: dict) -> np.ndarray:
    for i, lay in enumerate(layers):
        pre = x @ lay.weight.T + lay.bias
        out[f"act.{tag}.{i}"] = value_range(pre)
        x = np.maximum(pre, 0) if lay.act == "relu" else pre
    return x


def activation_ranges(mat: NeuralMaterial, wi: np.ndarray, wo: np.ndarray, uv: np.ndarray):
    """Ranges of every layer's input and pre-activation for ``wi, wo: [N, 3]``, ``uv: [N, 4, 2]``
    (the computation of :func:`~vrneural.material.material_forward`, float32)."""
    out: dict = {}
    if mat.parallax_kind == "neural":  # the offset MLP at the unmoved texels, then the shift
        from vrneural.neural_offset import VIEW_INPUTS, offset_uv

        psi = sample_bilinear_wrap(mat.offset_tex, uv.reshape(-1, 2))
        x = np.concatenate([psi, np.repeat(wo[:, :VIEW_INPUTS], 4, 0)], -1)
        _run_layers(x, mat.offset_net, "offset", out)
        uv = offset_uv(mat.offset_net, mat.offset_tex, wo, uv, mat.parallax_march)
    dirs = np.concatenate([wi, wo, half_vector(wi, wo)], -1)
    if mat.arch == "coarse_fine":
        fc = sample_bilinear_wrap(mat.textures["coarse"], uv.mean(1))
        z = _run_layers(np.concatenate([dirs, fc], -1), mat.networks["coarse"], "coarse", out)
        ff = sample_bilinear_wrap(mat.textures["fine"], uv.reshape(-1, 2))
        _run_layers(np.concatenate([np.repeat(z, 4, 0), ff], -1), mat.networks["fine"], "fine", out)
    else:
        f = sample_bilinear_wrap(mat.textures["features"], uv.reshape(-1, 2))
        x = np.concatenate([np.repeat(dirs, 4, 0), f], -1)
        _run_layers(x, mat.networks["mlp"], "mlp", out)
    return out


def material_ranges(mat: NeuralMaterial, data: SliceData, pairs: list[int]) -> dict:
    """Weights, textures and activations (over ``pairs`` of the training data) vs f16."""
    r: dict = {}
    nets, texs = dict(mat.networks), dict(mat.textures)
    if mat.offset_net is not None:
        nets["offset"], texs["offset"] = mat.offset_net, mat.offset_tex
    for name, layers in nets.items():
        for i, lay in enumerate(layers):
            r[f"weight.{name}.{i}"] = value_range(np.concatenate([lay.weight.ravel(), lay.bias]))
    for name, t in texs.items():
        r[f"texture.{name}"] = value_range(np.asarray(t, np.float32))
    uv = data.uv(None, shard=False).numpy()
    n = uv.shape[0]
    wi = np.concatenate([np.repeat(data.dirs(p)[0].numpy()[None], n, 0) for p in pairs])
    wo = np.concatenate([np.repeat(data.dirs(p)[1].numpy()[None], n, 0) for p in pairs])
    r.update(activation_ranges(mat, wi, wo, np.concatenate([uv] * len(pairs))))
    return r


def pack_material(ck: dict, data: SliceData, source: str | None = None, lod_levels: int = 0):
    """Build the :class:`NeuralMaterial` of a checkpoint with meta (ranges, provenance,
    metrics) and check the numpy forward against torch. Returns ``(mat, max_abs_diff)``.
    ``lod_levels`` > 1 for a checkpoint trained without a pyramid: give the pack one of box
    averages of level 0 (the ``filter`` pyramid, untrained)."""
    from vrneural import __version__

    model = model_from_checkpoint(ck, source)
    if lod_levels > 1 and model.lod_levels == 1:
        from vrneural.distill.config import check_lod_levels

        check_lod_levels(SimpleNamespace(lod_levels=lod_levels), data.res, source or "the BTF")
        model.lod_levels, model.lod_kind = lod_levels, "filter"
    elif lod_levels > 1 and lod_levels != model.lod_levels:
        raise VrnError(
            f"--lod-levels = {lod_levels}: {source or 'the checkpoint'} was trained with a "
            f"{model.lod_levels}-level pyramid; drop --lod-levels to export it as trained"
        )
    if "dir_range" not in ck["btf"]:  # a checkpoint from before it was recorded: the BTF's
        model.dir_range = directions_range(data.btf.light_dirs, data.btf.view_dirs)
    for k, v in model.state_dict().items():
        if not torch.isfinite(v).all():
            raise VrnError(f"{source or 'checkpoint'}: refusing to export: '{k}' has NaN/Inf")
    mat = model.to_material()
    for k, t in mat.textures.items():
        if not np.isfinite(t.astype(np.float32)).all():
            raise VrnError(f"{source}: refusing to export: texture '{k}' overflows float16")
    train = ck["split"]["train"]
    step = max(1, len(train) // RANGE_PAIRS)
    pairs = train[::step][:RANGE_PAIRS]
    ranges = material_ranges(mat, data, pairs)
    uv = data.uv(None, shard=False)
    diff = 0.0
    for p in pairs[:2]:
        wi, wo = data.dirs(p)
        for k in range(mat.lod_levels):  # each pyramid level at its own texel centres
            uvk = uv if k == 0 else data.uv_level(k, None)
            n = uvk.shape[0]
            lod = None if k == 0 else np.full(n, k, np.float32)
            wik, wok = (np.repeat(d.numpy()[None], n, 0) for d in (wi, wo))
            ref = material_forward(mat, wik, wok, uvk.numpy(), lod=lod)
            got = model.predict(wi, wo, uvk, k).numpy()
            diff = max(diff, float(np.abs(ref - got).max()))
    hist = ck["history"]
    cfg = ck["config"]
    mat.meta = {
        "name": ck["btf"]["name"],
        "method": ck["method"],
        "provenance": {
            "btf": ck["btf"],
            "checkpoint": str(source) if source else None,
            # identifies this pack's checkpoint, so `run --pack` can tell a student's teacher
            "checkpoint_sha256": file_sha256(source) if source and Path(source).is_file() else None,
            "teacher": ck.get("teacher", {}).get("sha256"),
            "teacher_path": ck.get("teacher", {}).get("resolved"),
            "seed": cfg["seed"],
            "split_seed": cfg["split_seed"],
            "epochs": ck["epoch"],
            # --init-from / --wide-start: the wide run it was pruned from (None: random init)
            "init_from": init_record(ck.get("init_from")),
            "config": cfg,
            "vrneural": __version__,
            "torch": str(torch.__version__),
        },
        "metrics": {
            "test_l1": hist[-1]["test_l1"] if hist else None,
            "test_l1_curve": [h["test_l1"] for h in hist],
            "train_seconds": ck.get("train_seconds"),
            "pack_vs_torch_max_abs": diff,
            "weight_bytes": mat.weight_bytes,
            "texture_bytes": mat.texture_bytes,
            "macs_per_texel": mat.macs_per_texel,
        },
        "ranges": ranges,
        # parallax (height field or neural offset): the kind chosen and why (setup_parallax)
        "parallax": ck.get("parallax") or {"kind": "off", "why": "trained before parallax"},
    }
    return mat, diff


def export_checkpoint(
    ck: dict,
    out,
    data: SliceData | None = None,
    force: bool = False,
    source: str | None = None,
    btf: str | None = None,
    lod_levels: int = 0,
) -> tuple[Path, dict]:
    """Write the ``.vrnm`` of a loaded checkpoint. Returns ``(path, meta)``."""
    out = check_output(out, force)
    if data is None:
        path = btf or recorded_btf(ck, source or "the checkpoint")
        check_outputs([out], True, [path])  # (checked above; now against the BTF)
        b = read_btf(path)
        mismatch = f"does not match the one {source} was trained on"
        check_btf_record(b.path, btf_fingerprint(b), ck["btf"], mismatch, "the checkpoint has")
        data = SliceData(b, ck["split"]["test"])
    mat, _ = pack_material(ck, data, source, lod_levels)
    write_vrnm(out, mat)
    return out, mat.meta


def ranges_table(ranges: dict) -> str:
    """A text table of :func:`material_ranges` (one row per tensor)."""
    rows = [f"{'tensor':<22} {'max|v|':>10} {'65504/max':>10} {'<6.1e-5':>8} {'zero':>6}"]
    for k, r in ranges.items():
        head = "-" if r["headroom"] is None else f"{r['headroom']:.3g}"
        rows.append(
            f"{k:<22} {r['max_abs']:>10.4g} {head:>10} {r['frac_below_f16_normal']:>8.2%} "
            f"{r['frac_zero']:>6.1%}"
        )
    return "\n".join(rows)


def init_record(init: dict | None) -> dict | None:
    """A checkpoint's ``init_from`` (``--init-from``/``--wide-start``) in short: the wide run's
    file, hash, width and epochs; None for a run from random weights."""
    if not init:
        return None
    return {
        "path": init["path"],
        "sha256": init["sha256"],
        "width": spec_width(init["spec"]),
        "epochs": int(init["epochs"]),
    }
