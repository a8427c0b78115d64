"""One `bench distance` condition and one variant, quickly: FLIP against the supersampled
teacher and flicker (the frame-to-frame change over the reference's own), with the reference
cached in DIR (a few minutes the first time, then seconds per variant). For trying a filtering
rule before it becomes a bench variant (docs/lod.md).

    python scripts/research/distance_variant.py DIR --cond "3 m" [--mips] [--screen-res]
        [--pack student_pyr] [--msaa 4] [--lod-footprint auto|pixel|texel]

DIR: a `bench distance` output folder (its packs are reused when the budget matches).
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

from vrneural.bench import distance as dist
from vrneural.bench import trade_scene as ts
from vrneural.bench import tradeoff as tr
from vrneural.bench.packs import load_packs, train_packs
from vrneural.bench.train_configs import DistanceConfig


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out", type=Path)
    ap.add_argument("--cond", default="10 m", help='a condition\'s name: "3 m", "tiling 8"')
    ap.add_argument("--mips", action="store_true")
    ap.add_argument("--screen-res", action="store_true")
    ap.add_argument("--pack", default="student_pyr", choices=dist.PACKS)
    ap.add_argument("--msaa", type=int, default=4)
    ap.add_argument("--lod-footprint", default="auto")
    a = ap.parse_args()
    c = DistanceConfig(out=str(a.out)).resolved()
    mats = load_packs(train_packs(a.out / "packs", c.budget.of(c.preset), True, only=dist.PACKS))
    prof, full, ppd = dist.quest3_view()
    cond = next(x for x in dist.conditions(c) if x.name == a.cond)
    cached = a.out / f"reference-{cond.name.replace(' ', '_')}.npz"  # written by this script
    if cached.exists():
        with np.load(cached) as z:
            ref = {int(k): z[k] for k in z.files}
    else:
        t = time.perf_counter()
        rs = dist.settings(c, cond, prof, False, False, "reference", mats["teacher"])
        scene = ts.scene_for(cond, mats["student"], mats["teacher"])
        ref = ts.reference(scene, rs, cond, c.score.crop, full, cond.scored, c.score.spp, 0)
        np.savez(cached, **{str(f): v for f, v in ref.items()})
        print(f"reference: {time.perf_counter() - t:.0f} s")
    s = dist.settings(c, cond, prof, a.mips, a.screen_res, msaa=a.msaa)
    s = dataclasses.replace(s, lod_footprint=a.lod_footprint)
    scene = ts.scene_for(cond, mats[a.pack])
    imgs, st = ts.render(scene, s, cond, c.score.crop, full, set(cond.scored))
    sc = tr.scores(ref, imgs, None, ppd, cond.scored, {})
    side = int(np.median([x.object_res[0] for x in st[1:]]))
    scale = float(np.median([x.object_lod_scale[0] for x in st[1:]]))
    print(f"{cond.name}: FLIP {sc['flip']['mean']:.4f}, flicker "
          f"{sc['change'] / sc['change_ref']:.2f}, side {side}, lod x {scale:.2f}")  # fmt: skip


if __name__ == "__main__":
    main()
