"""Noise floor of `btf render` by Mitsuba sampler: for each preset, 4 views x 4 lights at 64^2
texels and 64 samples rendered with two sample seeds, per sampler; the L1 between the two
(relative to the mean value) and the wall and CPU seconds. Writes JSON.

    .venv/bin/python scripts/research/pt_sampler_noise.py -o docs/results/pt-sampler-noise.json

Measured on 2026-12-04 (docs/quality-research.md, "A stratified sampler"): the multi-jittered
sampler's L1 is 1.3-2.6x lower than the independent one's on the five presets.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np


def measure(preset: str, samplers, spp: int = 64, res: int = 64) -> list[dict]:
    from vrneural.btf import pathtrace as pt
    from vrneural.btf.config import RenderConfig
    from vrneural.btf.dirs import direction_set
    from vrneural.btf.pt_render import build

    ps, _, _ = build(RenderConfig(preset=preset, res=res, dirs=24, spp=spp))
    dirs = direction_set(24)
    out = []
    for kind in samplers:
        t, c = time.perf_counter(), time.process_time()
        diff = total = 0.0
        n = 0
        for v in (0, 9, 18, 23):
            cam = pt.sensor(ps, dirs[v], res, spp, kind)
            for li in (0, 5, 13, 21):
                a, b = (
                    pt.render_slice(ps, cam, dirs[li], spp, pt.slice_seed(s, li, v)).astype(
                        np.float64
                    )
                    for s in (1, 2)
                )
                diff += float(np.abs(a - b).sum())
                total += float(a.sum())
                n += a.size
        rec = {
            "preset": preset,
            "sampler": kind,
            "spp": spp,
            "l1": diff / n,
            "relative": diff / total,
            "wall_s": time.perf_counter() - t,
            "cpu_s": time.process_time() - c,
        }
        print(rec, file=sys.stderr, flush=True)
        out.append(rec)
    return out


def main() -> int:
    from vrneural.btf.config import PT_PRESET_NAMES, SAMPLERS
    from vrneural.outputs import write_json

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--presets", default=",".join(PT_PRESET_NAMES))
    p.add_argument("-o", "--out", required=True)
    a = p.parse_args()
    rows = [r for name in a.presets.split(",") for r in measure(name, SAMPLERS)]
    write_json(a.out, {"benchmark": "pt-sampler-noise", "records": rows})
    print(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
