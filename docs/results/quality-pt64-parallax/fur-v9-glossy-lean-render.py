"""fur variant: glossy strands (GGX alpha ALPHA, was 0.35) and tufts leaning more (sd LEAN, was
0.15), else the preset (fourth version).

    python fur-v9-glossy-lean-render.py btf render fur --res 64 --dirs 24 --spp 64 --bounces 5 -o fur.btf
"""
import sys
import numpy as np
from vrneural.btf import pt_presets as P
from vrneural.btf.pt_geometry import Part, Tile, heightfield, merge, tube
from vrneural.btf.heightfield import spectral_noise
from vrneural.btf.pt_presets import diffuse, plastic

ALPHA = 0.12
LEAN = 0.35


def fur_leaning(rng, tufts: int = 144, per_tuft: int = 40) -> Tile:
    k = round(np.sqrt(tufts))
    base = (np.stack(np.meshgrid(np.arange(k), np.arange(k)), -1).reshape(-1, 2) + 0.5) / k
    centres = (base + (rng.random(base.shape) - 0.5) * 0.6 / k) % 1.0
    cols = [(0.80, 0.72, 0.58), (0.60, 0.24, 0.06), (0.07, 0.05, 0.04)]
    # patches: a coarse periodic field looked up at each tuft's centre, cut into three bands
    field = spectral_noise(rng, 64, 2, 6, beta=2.0)
    ij = (centres * len(field)).astype(int) % len(field)  # nearest cell, (x, y)
    at = field[ij[:, 1], ij[:, 0]]
    colour = np.digitize(at, np.quantile(at, [0.4, 0.7]))
    tall = rng.uniform(0.07, 0.19, len(centres))
    groups: list[list] = [[] for _ in cols]
    t = np.linspace(0.0, 1.0, 7)
    for (cx, cy), c, top in zip(centres, colour, tall, strict=True):
        lean = rng.normal(0, LEAN, 2)
        for _ in range(per_tuft):
            p0 = np.array([cx, cy]) + rng.normal(0, 0.022, 2)
            h = top * rng.uniform(0.85, 1.0)
            tilt = lean + rng.normal(0, 0.12, 2)
            curl = rng.normal(0, 0.02, 2)
            xy = p0 + np.outer(t, tilt * h) + np.outer(t**2, curl)
            path = np.column_stack([xy, h * t])
            radius = 0.0035 * (1.0 - 0.7 * t)
            groups[int(c)].append(tube(path, radius, sides=5, ref=[1.0, 0.0, 0.0]))
    parts = [
        Part(merge(g), plastic(cols[i], ALPHA), name=f"yarn{i}") for i, g in enumerate(groups) if g
    ]
    back = heightfield(0.002 * spectral_noise(rng, 32, 2, 12))
    parts.append(Part(back, diffuse((0.20, 0.16, 0.11)), name="backing"))
    return Tile(parts, f"calico cut pile, {k * k} tufts of {per_tuft} strands")


P.PT_PRESETS["fur"] = fur_leaning
if __name__ == "__main__":
    from vrneural.cli import main
    sys.exit(main(sys.argv[1:]))
