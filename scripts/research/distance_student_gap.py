"""How far is `bench distance`'s student from its teacher before any filtering? (docs/lod.md,
"The student's own error")

Trains (or reuses) the bench's packs at a given budget, then renders the 1 m condition's first
scored frame three ways at the quest3 pixel density: the teacher per pixel supersampled (the
bench's reference), the student per pixel supersampled (level 0), and the student through the
runtime (texture space, all level-of-detail features off). Prints their FLIP against the
reference and writes ``gap.png`` (left eye: teacher, student supersampled, student rendered,
tone-mapped, 2x). Score the packs on their BTF with `vrneural eval DIR/packs/*.vrnm --btf
DIR/packs/btf.btf`.

    python scripts/research/distance_student_gap.py DIR [--btf-dirs 10] [--epochs 24]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import imageio.v3 as iio
import numpy as np

from vrneural.bench import distance as dist
from vrneural.bench import trade_scene as ts
from vrneural.bench.packs import load_packs, train_packs
from vrneural.bench.parts import PackBudget
from vrneural.bench.train_configs import DistanceConfig
from vrneural.scoring import metrics


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out", type=Path)
    ap.add_argument("--btf-dirs", type=int, default=10)
    ap.add_argument("--epochs", type=int, default=None)
    ap.add_argument("--distance", type=float, default=1.0)
    a = ap.parse_args()
    c = DistanceConfig(
        out=str(a.out), budget=PackBudget(btf_dirs=a.btf_dirs, epochs=a.epochs)
    ).resolved()
    budget = c.budget.of(c.preset)
    print("budget", budget)
    mats = load_packs(train_packs(a.out / "packs", budget, True, only=("student",)))
    prof, full, ppd = dist.quest3_view()
    cond = next(x for x in dist.conditions(c) if x.family == "distance" and x.value == a.distance)
    f = cond.scored[0]
    img = {
        k: dist.supersampled(c, cond, prof, full, mats[k], [f])[f] for k in ("teacher", "student")
    }
    s = dist.settings(c, cond, prof, False, False)
    img["rendered"] = ts.render(ts.scene_for(cond, mats["student"]), s, cond, c.score.crop,
                                full, {f})[0][f]  # fmt: skip
    for k in ("student", "rendered"):
        flip = metrics.flip_hdr_eyes(img["teacher"], img[k], ppd)
        print(f"FLIP teacher vs student {k}: {flip:.4f}")

    def tm(x):
        x = np.clip(x / (1 + x), 0, 1) ** (1 / 2.2)
        return (x * 255).astype(np.uint8)

    row = np.concatenate([tm(img[k][0]) for k in ("teacher", "student", "rendered")], axis=1)
    iio.imwrite(a.out / "gap.png", np.kron(row, np.ones((2, 2, 1), np.uint8)))
    print("wrote", a.out / "gap.png")


if __name__ == "__main__":
    main()
