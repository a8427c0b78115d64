"""A/B of the neural-texture filters (issue #41): a full texture-space update of bench frame's
scene with the sampler's filtering (run --neural-filter hardware) against the exact filter in
the shader (exact), for the plain materials, with height-field parallax (8 steps; marched per
texel and "auto") and with the neural offset, in interleaved rounds, by the CPU time of all of
the process's threads (bench frame's clock on a CPU adapter).

    python docs/results/frame-ab/sampler_ab.py [texture side] [rounds] [out.json]
"""
import json, sys
import numpy as np
from vrneural.bench import timing
from vrneural.bench.frame import texture_update, time_passes
from vrneural.runtime.profiles import get_profile

prof = get_profile("quest3")
res = int(sys.argv[1]) if len(sys.argv) > 1 else 512
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 5
mats = {"plain": None, "height8": timing.parallax_materials("height", 8),
        "offset": timing.parallax_materials("neural")}
rs = {}
for kind, m in mats.items():
    for march in (("texel", "auto") if kind != "plain" else ("pack",)):
        for filt in ("exact", "hardware"):
            sc = timing.bench_scene(1, m)
            rs[kind, march, filt] = timing.make_renderer(
                sc, eyes=2, reuse=4, texture_res=res, eye_res=(516, 552), fps=prof.fps,
                fov_y=prof.fov_y, n_lights=1, schedule="staggered", parallax_march=march,
                neural_filter=filt)
out = {}
for rnd in range(rounds):
    for key, r in rs.items():
        t = time_passes(r, texture_update(r, "main", 0, 1, 10 + rnd), 3)
        out.setdefault(key, []).append(t["cpu_ms"])
rows = {}
for kind, m in mats.items():
    for march in (("texel", "auto") if kind != "plain" else ("pack",)):
        e, h = np.array(out[kind, march, "exact"]), np.array(out[kind, march, "hardware"])
        ratio = h / e
        rows[f"{kind}/{march}"] = dict(exact_ms=float(np.median(e)), hardware_ms=float(np.median(h)),
                                       ratio=float(np.median(ratio)), range=[float(ratio.min()), float(ratio.max())])
        print(f"{kind:8s} {march:6s} exact {np.median(e):7.1f} hw {np.median(h):7.1f}  hw/exact {np.median(ratio):.3f} [{ratio.min():.3f}, {ratio.max():.3f}]")
out_path = sys.argv[3] if len(sys.argv) > 3 else f"sampler_ab_{res}.json"
with open(out_path, "w") as f:
    json.dump({"res": res, "rounds": rounds, "rows": rows}, f, indent=1)
