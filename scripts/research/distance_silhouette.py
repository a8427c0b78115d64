"""How much of `bench distance`'s FLIP at a distance is the sphere's silhouette? (docs/lod.md)

The reference is supersampled per pixel, so its silhouette is antialiased; the runtime draws
one sample per pixel. This renders one condition's first scored frame: the teacher
supersampled (the bench's reference), the student supersampled with the same samples (its own
error), and the student through the runtime with the given features, plus a runtime render
without the sphere, whose difference from the one with it is the sphere's pixel mask. FLIP per
pixel (HDR, both eyes) is then averaged over three regions: the silhouette band (pixels within
``--band`` of the mask's edge), the sphere's interior and the rest, each with its share of
the whole image's FLIP sum.

    python scripts/research/distance_silhouette.py DIR [--distance 10] [--mips] [--screen-res]
        [--msaa 4]

DIR: a `bench distance` output folder (its packs are reused when the budget matches).
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np
from scipy import ndimage

from vrneural.bench import distance as dist
from vrneural.bench import trade_scene as ts
from vrneural.bench.packs import load_packs, train_packs
from vrneural.bench.train_configs import DistanceConfig


def flip_map(ref: np.ndarray, test: np.ndarray, ppd: float) -> np.ndarray:
    """HDR-FLIP per pixel of each eye, ``[eyes, H, W]``."""
    import flip_evaluator

    out = []
    for a, b in zip(ref, test, strict=True):
        a, b = (np.ascontiguousarray(np.maximum(np.nan_to_num(x[..., :3]), 0)) for x in (a, b))
        err, _, _ = flip_evaluator.evaluate(
            a, b, "HDR", inputsRGB=True, applyMagma=False, parameters={"ppd": float(ppd)}
        )
        out.append(np.asarray(err))
    return np.stack(out)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out", type=Path)
    ap.add_argument("--distance", type=float, default=10.0)
    ap.add_argument("--mips", action="store_true")
    ap.add_argument("--screen-res", action="store_true")
    ap.add_argument("--msaa", type=int, default=1, help="samples per pixel of the render")
    ap.add_argument("--band", type=int, default=1, help="pixels each side of the edge")
    a = ap.parse_args()
    c = DistanceConfig(out=str(a.out)).resolved()
    budget = c.budget.of(c.preset)
    mats = load_packs(train_packs(a.out / "packs", budget, True, only=dist.PACKS))
    prof, full, ppd = dist.quest3_view()
    cond = next(x for x in dist.conditions(c) if x.family == "distance" and x.value == a.distance)
    f = cond.scored[0]
    img = {
        k: dist.supersampled(c, cond, prof, full, mats[k], [f])[f] for k in ("teacher", "student")
    }
    pack = mats["student_pyr" if a.mips or a.screen_res else "student"]
    s = dist.settings(c, cond, prof, a.mips, a.screen_res, msaa=a.msaa)
    scene = ts.scene_for(cond, pack)
    img["rendered"] = ts.render(scene, s, cond, c.score.crop, full, {f})[0][f]
    bare = dataclasses.replace(scene, objects=scene.objects[1:])  # the floor alone
    s1 = dataclasses.replace(s, msaa=1)  # the mask from single-sample renders (no blending)
    img["bare"] = ts.render(bare, s1, cond, c.score.crop, full, {f})[0][f]
    img["single"] = ts.render(scene, s1, cond, c.score.crop, full, {f})[0][f]
    mask = np.abs(img["single"] - img["bare"]).max(-1) > 0  # [eyes, H, W]
    k = np.ones((2 * a.band + 1,) * 2, bool)
    band = np.stack([ndimage.binary_dilation(m, k) & ~ndimage.binary_erosion(m, k)
                     for m in mask])  # fmt: skip
    inner = mask & ~band
    rest = ~mask & ~band
    print(f"{cond.name}: sphere {mask.sum()} px, band {band.sum()} px of {mask.size}")
    for key in ("student", "rendered"):
        e = flip_map(img["teacher"], img[key], ppd)
        tot = e.sum()
        parts = ", ".join(
            f"{name} {e[r].mean():.4f} ({e[r].sum() / tot:.0%})"
            for name, r in (("silhouette band", band), ("interior", inner), ("rest", rest))
        )
        print(f"FLIP teacher vs {key}: all {e.mean():.4f}; {parts}")


if __name__ == "__main__":
    main()
