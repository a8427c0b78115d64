"""Research script (docs/quality-research.md, "Parallax where a material has relief"): does the
height field carried by a BTF explain how its slices move with the view?

For every light and the four most grazing views, the slice seen from the most normal view is
warped to where :func:`vrneural.parallax.parallax_uv` says each texel's view ray meets the
height field, and correlated (grey levels, Pearson) with the grazing slice: unwarped, warped
with the parallax as defined, and warped with the shift reversed (a sign check of the
convention: local x = material u, y = v, rays rectified on the reference plane). Seconds.

    .venv/bin/python scripts/research/parallax_alignment.py BTF [--steps 32]
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from vrneural.btf.format import read_btf
from vrneural.material import sample_bilinear_wrap
from vrneural.parallax import height_at_texels, parallax_uv, relief_texels


def _corr(a: np.ndarray, b: np.ndarray) -> float:
    a, b = a - a.mean(), b - b.mean()
    return float((a * b).sum() / np.sqrt((a * a).sum() * (b * b).sum()))


def alignment(path: str, steps: int = 32) -> dict:
    """Mean correlation per grazing view: ``{"none", "parallax", "reversed"}``."""
    b = read_btf(path)
    H, W = b.resolution
    h = height_at_texels(b.height, (H, W)).astype(np.float16)
    vz = b.view_dirs[:, 2]
    v0 = int(np.argmax(vz))
    ys, xs = np.mgrid[0:H, 0:W]
    uv = np.stack([(xs + 0.5) / W, (ys + 0.5) / H], -1).reshape(-1, 1, 2).repeat(4, 1)
    uv = uv.astype(np.float32)
    out = {"btf": str(path).rsplit("/", 1)[-1], "relief_texels": relief_texels(h), "views": []}
    for v in np.argsort(vz)[:4]:
        row = {"view": int(v), "theta_deg": float(np.degrees(np.arccos(vz[v])))}
        for name, sign in (("none", 0.0), ("parallax", 1.0), ("reversed", -1.0)):
            wo = b.view_dirs[v].copy()
            wo[:2] *= sign if sign else 1.0
            warp = uv if not sign else parallax_uv(h, np.tile(wo, (len(uv), 1)), uv, steps, 0.1)
            cs = []
            for light in range(b.shape[0]):
                s0 = sample_bilinear_wrap(b.slice(light, v0), warp[:, 0]).reshape(H, W, 3)
                cs.append(_corr(s0.mean(-1), b.slice(light, v).mean(-1)))
            row[name] = float(np.mean(cs))
        out["views"].append(row)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("btf")
    ap.add_argument("--steps", type=int, default=32)
    a = ap.parse_args()
    print(json.dumps(alignment(a.btf, a.steps), indent=1))


if __name__ == "__main__":
    main()
