"""`vrneural bench materials`: 1 to 4 materials rendered at once (the paper's Table 3).

k upright squares side by side, each with a distinct random neural material (its own generated
kernel), three point lights, 1024^2 radiance textures, N = 7, both eyes at the quest3 eye
resolution. Radiance textures are RGBA float16 here (8 B/texel): ``res^2 * 8 * eyes`` bytes each.
"""

from __future__ import annotations

from vrneural.bench import report as rp
from vrneural.bench import timing
from vrneural.bench.configs import MaterialsConfig
from vrneural.errors import check_range, count
from vrneural.material import random_material
from vrneural.runtime.config import LIGHTS_MAX
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
    check_range("--lights", c.lights, 1, LIGHTS_MAX)

    def report(recs):
        per = c.texture_res**2 * 8 * c.loop.eyes / 2**20  # rgba16float, per eye
        for k, rec in zip(c.materials, recs, strict=True):
            rec["radiance_texture_mb_per_material"] = per
            rec["radiance_texture_mb"] = per * k  # every material's textures, as the table shows
        columns = [
            ("materials", "materials"),
            ("FPS (mean frame ms)", "fps"),
            ("frame ms median", "frame_ms.median"),
            ("frame ms p99", "frame_ms.p99"),
            ("shading ms/frame", "shading_ms_per_frame"),
            ("forward ms", "forward_ms"),
            ("radiance textures MiB", "radiance_texture_mb"),
        ]
        setting = (
            f"k squares with distinct materials, {count(c.lights, 'light')}, "
            f"{count(c.loop.eyes, 'eye')} at {c.loop.eye_res}, "
            f"texture {c.texture_res}^2 per material"
        )
        title = "# Materials: several materials at once (paper Table 3)"
        return title, setting, columns, [], [("materials.png", "materials", plot)]

    def setup(k):
        return squares_scene(k, c.lights), c.lights

    return timing.count_bench(c, "materials", c.materials, setup, "count", report)


def plot(doc: dict, path) -> None:
    """Frame and shading ms against the number of materials."""
    fig, (ax,) = rp.figure(5, 3.5)
    recs = doc["records"]
    ks = [r["materials"] for r in recs]
    ax.plot(ks, [r["frame_ms"]["median"] for r in recs], "o-", label="frame ms (median)")
    ax.plot(ks, [r["shading_ms_per_frame"] for r in recs], "s-", label="shading ms/frame")
    ax.set_xlabel("materials")
    ax.set_ylabel("ms")
    ax.set_xticks(ks)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    ax.set_title(f"bench materials on {doc['adapter']['name']}", fontsize=9)
    rp.save_png(fig, path)
