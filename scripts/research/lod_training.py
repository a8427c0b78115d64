"""Research script (docs/quality-research.md, "Prefiltered neural textures"): the student's
neural textures as pyramids, trained two ways, against no pyramid.

For each preset: a BTF, a teacher, and three students at one budget: no pyramid (``--lod-levels
1``), the filter-aware latent pyramid (``--lod-levels 4 --lod-kind filter``: levels are box
averages of level 0) and NeuMIP's per-level textures (``--lod-kind levels``). Scored on the
test slices at level 0 and at each prefiltered level k (the BTF averaged over 2^k x 2^k texels,
at the level's texel centres); the pyramid-less student is scored at level k with its textures
box-averaged (naive linear downsampling of the latents).

    .venv/bin/python scripts/research/lod_training.py WORKDIR [--presets leather,fabric]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

LEVELS = 4
VARIANTS = {"none": [], "filter": ["--lod-levels", "4"],
            "levels": ["--lod-levels", "4", "--lod-kind", "levels"]}  # fmt: skip


def vrn(*args) -> None:
    code = "import sys; from vrneural.cli import main; sys.exit(main(sys.argv[1:]))"
    subprocess.run([sys.executable, "-c", code, *map(str, args)], check=True)


def level_l1(mat, btf, pairs, level: int) -> float:
    """Mean L1 over ``pairs`` of the material at pyramid level ``level`` (naively pooled
    latents where it has no pyramid) against the BTF averaged over the level's texels."""
    import torch

    from vrneural.distill.data import to_blocks
    from vrneural.distill.lookups import avg_pool_levels
    from vrneural.material import NeuralMaterial, material_forward, pool_level

    if level and mat.lod_levels <= level:  # no pyramid: pool level 0's latents
        mat = NeuralMaterial(mat.arch, mat.networks, mat.textures, mat.output, mat.meta,
                             mat.dir_range,
                             {k: [pool_level(t, j) for j in range(1, level + 1)]
                              for k, t in mat.textures.items()})  # fmt: skip
    _, V, H, W = btf.shape
    h, w = H >> level, W >> level
    ys, xs = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    uv = to_blocks(torch.from_numpy(np.stack([(xs + 0.5) / w, (ys + 0.5) / h], -1))).numpy()
    n = uv.shape[0]
    out = []
    for p in pairs:
        li, vi = divmod(p, V)
        wi = np.repeat(btf.light_dirs[li][None], n, 0)
        wo = np.repeat(btf.view_dirs[vi][None], n, 0)
        y = material_forward(mat, wi, wo, uv.astype(np.float32),
                             lod=np.full(n, level, np.float32) if level else None)  # fmt: skip
        gt = avg_pool_levels(torch.from_numpy(btf.slice(li, vi).astype(np.float32)), level)
        out.append(float(np.abs(y - to_blocks(gt).numpy()).mean()))
    return float(np.mean(out))


def main() -> None:
    from vrneural.btf import read_btf
    from vrneural.distill.checkpoint import load_checkpoint
    from vrneural.formats.vrnm import read_vrnm

    ap = argparse.ArgumentParser()
    ap.add_argument("work", type=Path)
    ap.add_argument("--presets", default="leather,fabric")
    ap.add_argument("--epochs", type=int, default=12)
    a = ap.parse_args()
    out = {}
    for preset in a.presets.split(","):
        d = a.work / preset
        d.mkdir(parents=True, exist_ok=True)
        btf = d / "btf.btf"
        if not btf.exists():
            vrn("btf", "synth", "--preset", preset, "--res", 48, "--dirs", 24, "--seed", 0,
                "-o", btf, "--no-progress")  # fmt: skip
        if not (d / "teacher.pt").exists():
            vrn("teach", btf, "-o", d / "teacher.pt", "--epochs", 8, "--no-progress")
        b = read_btf(btf)
        test = load_checkpoint(d / "teacher.pt")["split"]["test"]
        for name, flags in VARIANTS.items():
            pack = d / f"{name}.vrnm"
            if not pack.exists():
                vrn("distill", d / "teacher.pt", "-o", d / f"{name}.pt", "--epochs", a.epochs,
                    "--no-progress", *flags)  # fmt: skip
            mat = read_vrnm(pack)
            rec = {f"l1_level{k}": level_l1(mat, b, test, k) for k in range(LEVELS)}
            out[f"{preset}/{name}"] = rec
            print(preset, name, json.dumps(rec), flush=True)
    (a.work / "results.json").write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
