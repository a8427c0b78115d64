"""What a GPU sampler's sub-texel precision costs the neural textures (issue #41's filter
through the sampler, docs/runtime.md).

`run --neural-filter hardware` (the default) leaves the bilinear weights of the neural-texture
lookups to the sampler. llvmpipe computes them in float (the exact filter's frames to float
rounding); a GPU truncates the texel coordinate to a few fractional bits first (Vulkan's
``subTexelPrecisionBits``: at least 4, 8 on desktop GPUs and D3D11's requirement). This
script emulates that in the numpy twin (every bilinear lookup of the neural textures, the
height field and the offset texture with its weights truncated to B bits) and shades each
bundled pack's texture-space pass on the sphere's atlas at the demo's tiling, exactly and at 4,
6 and 8 bits. It reports the mean |difference| relative to the mean radiance, and for scale
the same measure between the student and its own teacher pack (the student's error that the
runtime renders anyway).

    python scripts/research/subtexel_precision.py [-o OUT.json] [--res 256]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from vrneural import sampling
from vrneural.atlas import build_atlas
from vrneural.formats.vrnm import read_vrnm
from vrneural.runtime import reference as ref
from vrneural.runtime.assets import get_mesh

PACKS = Path(__file__).resolve().parents[2] / "vrneural" / "data" / "materials"
EXACT = sampling.sample_bilinear_wrap


def quantised(bits: int):
    """``sample_bilinear_wrap`` with the texel coordinate truncated to ``bits`` fractional
    bits before the weights are taken (a GPU sampler's sub-texel precision)."""
    q = float(2**bits)

    def sample(tex, uv):
        t = np.asarray(tex, np.float32)
        H, W = t.shape[:2]
        x = np.floor((np.asarray(uv[..., 0], np.float64) * W - 0.5) * q) / q
        y = np.floor((np.asarray(uv[..., 1], np.float64) * H - 0.5) * q) / q
        u = np.stack([(x + 0.5) / W, (y + 0.5) / H], -1)  # on the grid: EXACT's weights are q's
        return EXACT(t, u)

    return sample


def patch(fn) -> None:
    import vrneural.material as material
    import vrneural.neural_offset as neural_offset
    import vrneural.parallax as parallax

    for mod in (sampling, material, neural_offset, parallax):
        mod.sample_bilinear_wrap = fn


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--out", default=None)
    ap.add_argument("--res", type=int, default=256, help="atlas side")
    a = ap.parse_args()
    at = build_atlas(get_mesh("sphere"), a.res)
    eye = np.float32([0.0, 0.4, 1.6])
    lp = np.float32([[0.8, 1.2, 1.5], [-1.0, 0.5, 0.8]])
    lc = np.float32([[2.0, 2.0, 2.0], [1.0, 0.9, 0.8]])
    tl = (2.0, 2.0, 0.0, 0.0)
    rows = {}
    for name in ("leather", "fabric", "wood"):
        student = read_vrnm(PACKS / f"{name}.vrnm")
        teacher = read_vrnm(PACKS / f"{name}.teacher.vrnm")
        patch(EXACT)
        base, _ = ref.shade_texture_space(at, student, np.eye(4), eye, lp, lc, tiling=tl)
        mask = base[..., 3] > 0
        mean = float(np.abs(base[mask, :3]).mean())
        t, _ = ref.shade_texture_space(at, teacher, np.eye(4), eye, lp, lc, tiling=tl)
        row = {
            "mean_radiance": mean,
            "student_vs_teacher": float(np.abs(t[mask, :3] - base[mask, :3]).mean()) / mean,
        }
        for bits in (4, 6, 8):
            patch(quantised(bits))
            got, _ = ref.shade_texture_space(at, student, np.eye(4), eye, lp, lc, tiling=tl)
            d = np.abs(got[mask, :3] - base[mask, :3])
            row[f"bits{bits}"] = {"mean": float(d.mean()) / mean,
                                  "p99": float(np.quantile(d, 0.99)) / mean,
                                  "max": float(d.max()) / mean}  # fmt: skip
        patch(EXACT)
        rows[name] = row
        print(name, json.dumps(row))
    if a.out:
        doc = {"res": a.res, "tiling": tl[:2], "packs": rows}
        Path(a.out).write_text(json.dumps(doc, indent=1))


if __name__ == "__main__":
    main()
