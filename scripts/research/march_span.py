"""Research script (docs/parallax.md, "Where the march runs"): what marching once per 2x2 block
costs in accuracy as a function of how wide the block is in material texels.

A pack trained marching per texel (``distill --parallax height``) is evaluated with the numpy
twin (:func:`vrneural.material.material_forward`, the shader's arithmetic) on every (light,
view) pair of its BTF, at every texel centre, against the BTF's values. Each texel is taken as
one corner (chosen at random) of a 2x2 block whose texels lie ``span`` material texels apart:
marched once per block, its lookup moves by the shift at the block's centre, as in the
texture-space pass where one atlas texel covers ``span`` texels of the material. Reported: L1
(linear BTF units, as ``bench quality``) over the whole BTF and by view-angle bin for the
per-texel march, the block march at each span and the pack without parallax (the parallax's
own gain: the floor the block march's loss is measured against).

    .venv/bin/python scripts/research/march_span.py PACK.vrnm BTF OUT.json [--spans ...]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from pathlib import Path

import numpy as np

from vrneural.bench.quality_parallax import VIEW_BINS
from vrneural.btf.format import read_btf
from vrneural.formats.vrnm import read_vrnm
from vrneural.material import material_forward


def blocks(res: tuple[int, int], span: float, rng) -> tuple[np.ndarray, np.ndarray]:
    """Blocks ``[H*W, 4, 2]`` UV whose texel ``corner[i]`` (``[H*W]``) is texel centre ``i`` and
    whose other texels lie ``span`` texels away along u and v (order (0,0), (1,0), (0,1), (1,1))."""
    H, W = res
    y, x = np.mgrid[0:H, 0:W]
    c = np.stack([(x.ravel() + 0.5) / W, (y.ravel() + 0.5) / H], -1)  # [N, 2]
    corner = rng.integers(0, 4, len(c))
    off = np.array([[0, 0], [1, 0], [0, 1], [1, 1]], np.float64)  # texel offsets in a block
    step = np.array([span / W, span / H])
    uv = c[:, None, :] + (off[None] - off[corner][:, None, :]) * step
    return uv.astype(np.float32), corner


def l1_by_bin(mat, btf, uv, corner, march: str, pairs) -> dict:
    """Whole-BTF and per-bin L1 of ``mat`` marching ``march`` (``None``: parallax off)."""
    m = mat
    if march is None:
        m = dataclasses.replace(mat, parallax={"kind": "off"}, height=None)
    elif march != mat.parallax_march:
        m = dataclasses.replace(mat, parallax={**mat.parallax, "march": march})
    n = len(uv)
    per_pair = []
    for li, vi in pairs:
        wi = np.repeat(btf.light_dirs[li][None], n, 0)
        wo = np.repeat(btf.view_dirs[vi][None], n, 0)
        y = material_forward(m, wi, wo, uv)[np.arange(n), corner]  # [N, 3]
        ref = btf.slice(li, vi).reshape(-1, 3)
        per_pair.append(float(np.abs(y - ref).mean()))
    theta = [math.degrees(math.acos(float(btf.view_dirs[v][2]))) for _, v in pairs]
    bins = []
    for lo, hi in VIEW_BINS:
        sel = [e for e, t in zip(per_pair, theta, strict=True) if lo <= t < hi]
        bins.append(float(np.mean(sel)) if sel else None)
    return {"whole": float(np.mean(per_pair)), "bins": bins}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("pack")
    ap.add_argument("btf")
    ap.add_argument("out")
    ap.add_argument("--spans", default="0.125,0.25,0.5,1,2")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    mat, btf = read_vrnm(args.pack), read_btf(args.btf)
    if mat.parallax_kind != "height":
        raise SystemExit(f"{args.pack}: not a height-parallax pack")
    L, V = btf.shape[:2]
    pairs = [(li, vi) for li in range(L) for vi in range(V)]
    rng = np.random.default_rng(args.seed)
    doc = {"pack": args.pack, "btf": args.btf, "view_bins": VIEW_BINS, "pairs": len(pairs)}
    doc["spans"] = {}
    for span in (float(s) for s in args.spans.split(",")):
        # the same blocks for the three (the coarse latent is read at the block's mean too)
        uv, c = blocks(btf.resolution, span, rng)
        rec = doc["spans"][span] = {}
        for name, march in (("texel", "texel"), ("block", "block"), ("off", None)):
            rec[name] = l1_by_bin(mat, btf, uv, c, march, pairs)
            print(span, name, rec[name], flush=True)
    Path(args.out).write_text(json.dumps(doc, indent=1))
    plot(doc, Path(args.out).with_suffix(".png"))


def plot(doc: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    spans = [float(s) for s in doc["spans"]]
    recs = list(doc["spans"].values())
    labels = [f"{lo:g}-{hi:g} deg" for lo, hi in doc["view_bins"]] + ["whole BTF"]
    for i, lab in enumerate(labels):
        key = (lambda r: r["whole"]) if i == len(labels) - 1 else (lambda r, i=i: r["bins"][i])
        line = ax.plot(spans, [key(r["block"]) for r in recs], "o-", label=lab)[0]
        ax.plot(spans, [key(r["texel"]) for r in recs], "--", color=line.get_color(), lw=0.9)
        ax.plot(spans, [key(r["off"]) for r in recs], ":", color=line.get_color(), lw=0.9)
    ax.axvline(0.5, color="grey", lw=0.6)  # march auto's threshold
    ax.set_xscale("log", base=2)
    ax.set_xlabel("texels of the material between a block's texels (auto: <= 0.5 per block)")
    ax.set_ylabel("L1 against the BTF")
    ax.set_title(
        "Once per 2x2 block (solid), per texel (dashed), the pack without parallax (dotted)"
    )
    ax.title.set_fontsize(9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    main()
