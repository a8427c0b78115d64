"""`vrneural eval`: score runtime packs (``.vrnm``) against a BTF, with numpy alone.

Each pack is evaluated as the shader evaluates it: :func:`vrneural.material.material_forward`,
the numpy twin of the WGSL kernels (float16 textures; float32, or float16 arithmetic emulated
by rounding every layer's result), at the texel centres of each ``(light, view)`` slice of the
BTF, in the 2x2 blocks training uses (a coarse-to-fine pack shares one coarse latent per block).
So the numbers include what exporting costs (float16 textures) and, with ``--precision f16``,
what the runtime's half-precision path costs. Per pack and precision:

- **L1**: mean ``|pack - BTF|`` over texels and RGB, linear BTF units (the whole-BTF L1 that
  ``bench quality`` reports for checkpoints), over the slices scored, over the held-out ones
  and over the training ones (the split the pack records), and relative to the mean value
  of the BTF slices scored;
- **RMSE**, linear;
- **PSNR** (dB) and **SSIM** of each slice *as displayed*, averaged over slices: each slice at
  its own exposure (the BTF slice's 99th percentile of the max channel maps to 1), then the
  runtime's tone map ``x / (1 + x)`` and the sRGB curve (:func:`vrneural.scoring.metrics.display`),
  so dim and bright slices count alike;
- the **worst slices** by L1, with their angles.

A BTF too large to score whole (UBO2014: 151^2 slices of 400^2 texels) is scored on a sample of
its slices drawn with a fixed seed (``--slices``); the output says how many.
"""

from __future__ import annotations

import math
import numbers

import numpy as np
from tqdm import tqdm

from vrneural.btf.sheet import dir_angles, fmt_angle
from vrneural.errors import VrnError
from vrneural.material import NeuralMaterial, material_forward
from vrneural.scoring.config import AUTO_TEXELS, EvalConfig  # noqa: F401 (EvalConfig: its old home)
from vrneural.scoring.metrics import display, psnr, ssim

#: seed of the slices drawn when not all are scored
SAMPLE_SEED = 0
#: slices listed as the worst of each pack
N_WORST = 5


def pick_slices(spec: str, n_pairs: int, texels_per_slice: int) -> list[int]:
    """The pair indices ``l * V + v`` scored: ``'all'``, ``'auto'`` or a count N (N distinct
    pairs drawn at random with the fixed :data:`SAMPLE_SEED`, so reruns score the same ones)."""
    s = str(spec).strip().lower()
    if s == "all":
        return list(range(n_pairs))
    if s == "auto":
        n = max(1, AUTO_TEXELS // max(texels_per_slice, 1))
    else:
        try:
            n = int(s)
        except ValueError:
            raise VrnError(
                f"--slices = {spec!r}: expected 'all', 'auto' or a whole number of slices"
            ) from None
        if not 1 <= n <= n_pairs:
            raise VrnError(
                f"--slices = {n} is out of range; allowed [1, {n_pairs}] (the BTF's slices)"
            )
    if n >= n_pairs:
        return list(range(n_pairs))
    # drawn, not strided: pair index l * V + v in even steps would pair few views with lights
    return sorted(np.random.default_rng(SAMPLE_SEED).choice(n_pairs, n, replace=False).tolist())


def texel_blocks(H: int, W: int) -> np.ndarray:
    """Texel-centre UVs of an ``H x W`` slice in 2x2 blocks, ``[H W / 4, 4, 2]``, in the order
    of :func:`vrneural.distill.data.to_blocks` (row-major blocks, texels row-major inside)."""
    if H % 2 or W % 2 or H < 2 or W < 2:
        raise VrnError(f"texel_blocks: {H}x{W} texels; both sides must be even (2x2 blocks)")
    ys, xs = np.meshgrid(np.arange(H), np.arange(W), indexing="ij")
    uv = np.stack([(xs + 0.5) / W, (ys + 0.5) / H], -1).astype(np.float32)  # [H, W, 2]
    return to_blocks(uv)


def to_blocks(a: np.ndarray) -> np.ndarray:
    """``[H, W, ...]`` -> ``[H W / 4, 4, ...]`` (numpy twin of the torch one in training)."""
    H, W = a.shape[:2]
    b = a.reshape(H // 2, 2, W // 2, 2, *a.shape[2:]).swapaxes(1, 2)
    return b.reshape(H * W // 4, 4, *a.shape[2:])


def from_blocks(b: np.ndarray, H: int, W: int) -> np.ndarray:
    """Inverse of :func:`to_blocks`."""
    return b.reshape(H // 2, W // 2, 2, 2, *b.shape[2:]).swapaxes(1, 2).reshape(H, W, -1)


def predict_slice(
    mat: NeuralMaterial, wi: np.ndarray, wo: np.ndarray, uv: np.ndarray, H: int, W: int, prec: str
) -> np.ndarray:
    """The pack's slice ``[H, W, 3]`` float32 (linear) at one light ``wi`` and view ``wo``
    (unit ``[3]`` vectors, the BTF's local frame); ``uv`` from :func:`texel_blocks`."""
    n = uv.shape[0]
    for name, d in (("wi", wi), ("wo", wo)):
        if np.shape(d) != (3,):
            raise VrnError(
                f"predict_slice: {name} has shape {list(np.shape(d))}, expected [3] (one "
                "direction for the whole slice)"
            )
    d_i = np.broadcast_to(np.asarray(wi, np.float32), (n, 3))
    d_o = np.broadcast_to(np.asarray(wo, np.float32), (n, 3))
    return from_blocks(material_forward(mat, d_i, d_o, uv, prec), H, W)


def slice_exposure(gt: np.ndarray) -> float:
    """The exposure that maps the slice's 99th percentile (of each texel's max channel) to 1."""
    return 1.0 / max(float(np.percentile(gt.max(-1), 99.0)), 1e-6)


def _l1(acc: dict, idx: list[int], per_slice: int) -> float | None:
    return float(np.sum([acc["abs"][i] for i in idx]) / (len(idx) * per_slice)) if idx else None


def score(
    mats: list[NeuralMaterial],
    btf,
    pairs: list[int],
    precs: list[str],
    tests: list[list[int] | None] | None = None,
    progress: bool = False,
    trainer_tests: list[list[int] | None] | None = None,
) -> dict:
    """Score ``mats`` on the ``pairs`` of ``btf``. ``tests``: per pack, the held-out pair
    indices of its training (None: no split known); ``trainer_tests``: per pack, the subset
    of them its trainer's test L1 was measured on (``l1_trainer_test``). Returns
    ``{"slices": {...}, "scores": [[{...} per precision] per pack]}`` (see the module
    docstring for the metrics)."""
    L, V, H, W = btf.shape
    if H % 2 or W % 2:
        raise VrnError(f"{btf.path}: resolution {H}x{W} must be even (packs shade 2x2 blocks)")
    for p in pairs:  # an index beyond L V was an IndexError, a negative one wrapped around
        if not isinstance(p, numbers.Integral) or isinstance(p, bool) or not 0 <= p < L * V:
            raise VrnError(
                f"score: pair {p!r} is out of range; allowed whole numbers [0, {L * V - 1}] "
                f"(light * {V} + view)"
            )
    uv = texel_blocks(H, W)
    # per (pack, precision), per slice: sum |e|, sum e^2 (float64), PSNR and SSIM
    accs = [[{k: [] for k in ("abs", "sq", "psnr", "ssim")} for _ in precs] for _ in mats]
    gt_sum = 0.0
    bar = tqdm(pairs, desc="vrneural eval", unit="slice", disable=not progress)
    for p in bar:
        li, vi = divmod(p, V)
        gt = np.asarray(btf.slice(li, vi), np.float32)  # [H, W, 3]
        if not np.isfinite(gt).all():
            raise VrnError(
                f"{btf.path}: slice light {li}, view {vi} holds NaN/Inf values; fix or "
                "re-import the BTF"
            )
        gt_sum += float(gt.sum(dtype=np.float64))
        ex = slice_exposure(gt)
        gt_disp = display(gt * ex)
        for m, mat in enumerate(mats):
            for k, prec in enumerate(precs):
                y = predict_slice(mat, btf.light_dirs[li], btf.view_dirs[vi], uv, H, W, prec)
                e = (y - gt).astype(np.float64)
                a = accs[m][k]
                a["abs"].append(float(np.abs(e).sum()))
                a["sq"].append(float((e * e).sum()))
                y_disp = display(y * ex)
                a["psnr"].append(psnr(gt_disp, y_disp))
                a["ssim"].append(ssim(gt_disp, y_disp))
    bar.close()
    per_slice = H * W * 3
    pos = {p: i for i, p in enumerate(pairs)}
    mean_gt = gt_sum / (len(pairs) * per_slice)
    scores = []
    for m in range(len(mats)):
        test = (tests or [None] * len(mats))[m]
        sub = (trainer_tests or [None] * len(mats))[m]
        held = [pos[p] for p in (test or []) if p in pos]
        # the trainer's subset counts only when all of it was scored (else it is another mean)
        sub_idx = [pos[p] for p in sub] if sub and all(p in pos for p in sub) else []
        trained = sorted(set(range(len(pairs))) - set(held)) if test is not None else []
        rows = []
        for k, prec in enumerate(precs):
            a = accs[m][k]
            l1 = _l1(a, list(range(len(pairs))), per_slice)
            order = np.argsort(a["abs"])[::-1][:N_WORST]
            rows.append(
                {
                    "precision": prec,
                    "held_out_slices": len(held) if test is not None else None,
                    "l1": l1,
                    "l1_held_out": _l1(a, held, per_slice),
                    "l1_train": _l1(a, trained, per_slice),
                    "l1_trainer_test": _l1(a, sub_idx, per_slice),
                    "l1_relative": l1 / mean_gt if mean_gt > 0 else None,
                    "rmse": math.sqrt(sum(a["sq"]) / (len(pairs) * per_slice)),
                    "psnr_db": float(np.mean(a["psnr"])),
                    "ssim": float(np.mean(a["ssim"])),
                    "worst": [
                        _slice_record(btf, pairs[int(i)], a["abs"][int(i)] / per_slice)
                        for i in order
                    ],
                }
            )
        scores.append(rows)
    return {
        "slices": {
            "scored": len(pairs),
            "of": L * V,
            "texels_per_slice": H * W,
            "btf_mean": mean_gt,
        },
        "scores": scores,
    }


def _slice_record(btf, pair: int, l1: float) -> dict:
    V = btf.shape[1]
    li, vi = divmod(pair, V)
    wi = fmt_angle(*dir_angles(btf.light_dirs[li]))
    wo = fmt_angle(*dir_angles(btf.view_dirs[vi]))
    return {"light": li, "view": vi, "angles": f"wi={wi} wo={wo}", "l1": l1}
