"""`vrneural bench materials`: 1 to 4 materials rendered at once (the paper's Table 3).

k upright squares side by side, each with a distinct random neural material (its own generated
kernel), three point lights, 1024^2 radiance textures, N = 7, both eyes at the quest3 eye
resolution. Radiance textures are RGBA float16 here (8 B/texel): ``res^2 * 8 * eyes`` bytes each.
"""

from __future__ import annotations

import time

from vrneural.bench import report as rp
from vrneural.bench import timing
from vrneural.bench.configs import MaterialsConfig
from vrneural.errors import check_range, count
from vrneural.material import random_material
from vrneural.runtime.config import LIGHTS_MAX, REUSE_MAX
from vrneural.runtime.lights import default_lights
from vrneural.runtime.scene import MaterialDesc, ObjectDesc, Scene, model_matrix


def squares_scene(k: int, n_lights: int):
    """k upright squares (0.3 m) in a row facing the built-in head path, distinct materials."""
    objs = []
    for i in range(k):
        x = (i - (k - 1) / 2) * 0.34
        model = model_matrix((x, 0.85, 0.0), (70, 0, 0), 0.15)  # plane mesh spans [-1, 1]
        mat = MaterialDesc("neural", random_material(100 + i), f"random:{100 + i}", 1.0)
        objs.append(ObjectDesc(f"square{i}", "plane", model, mat))
    return Scene(f"squares{k}", objs, default_lights(n_lights), None, None, "orbit")


def run_materials(cfg: MaterialsConfig) -> dict:
    c = cfg.resolved()
    counts = c.materials
    rp.check_texture_res(c.texture_res)
    check_range("--reuse", c.reuse, 0, REUSE_MAX)
    check_range("--lights", c.lights, 1, LIGHTS_MAX)
    eye_res = c.loop.check()
    with rp.prepare_out(cfg.out, cfg.force, "materials") as root:
        t0 = time.perf_counter()
        doc = rp.header("materials", c)
        doc["records"], n = timing.count_sweep(
            c, eye_res, counts, "bench materials", lambda k: (squares_scene(k, c.lights), c.lights)
        )
        per = c.texture_res**2 * 8 * c.loop.eyes / 2**20  # rgba16float, per eye
        for k, rec in zip(counts, doc["records"], strict=True):
            rec["radiance_texture_mb_per_material"] = per
            rec["radiance_texture_mb"] = per * k  # every material's textures, as the table shows
        recs = doc["records"]
        md = [
            "# Materials: several materials at once (paper Table 3)",
            "",
            rp.adapter_line(doc),
            f"k squares with distinct materials, {count(c.lights, 'light')}, "
            f"{count(c.loop.eyes, 'eye')} at {c.loop.eye_res}, "
            f"texture {c.texture_res}^2 per material, N = {c.reuse} ({c.schedule}), {n} frames per "
            f"count after frame 0 and {c.loop.warmup} s of unmeasured frames."
            + (" **Quick run: reduced grid.**" if c.quick else ""),
            "",
        ]
        md += rp.record_table(
            recs,
            [
                ("materials", "materials"),
                ("FPS (mean frame ms)", "fps"),
                ("frame ms median", "frame_ms.median"),
                ("frame ms p99", "frame_ms.p99"),
                ("shading ms/frame", "shading_ms_per_frame"),
                ("forward ms", "forward_ms"),
                ("radiance textures MiB", "radiance_texture_mb"),
            ],
        )
        md += [
            "",
            rp.FPS_NOTE,
            "",
            "![materials](materials.png)",
        ]
        fig, (ax,) = rp.figure(5, 3.5)
        ks = [r["materials"] for r in recs]
        ax.plot(ks, [r["frame_ms"]["median"] for r in recs], "o-", label="frame ms (median)")
        ax.plot(ks, [r["shading_ms_per_frame"] for r in recs], "s-", label="shading ms/frame")
        ax.set_xlabel("materials")
        ax.set_ylabel("ms")
        ax.set_xticks(ks)
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
        ax.set_title(f"bench materials on {doc['adapter']['name']}", fontsize=9)
        rp.save_png(fig, root / "materials.png")
        return rp.finish(root, doc, md, t0)
