"""`vrneural bench lights`: frame time over the number of point lights (the paper's Fig. 10:
1 to 8, the default; up to 64).

The benchmark scene (:func:`vrneural.bench.timing.bench_scene`) with its first k of 8 circling
point lights (the same 8 positions for every k; a list reaching beyond 8 spreads max(k) lights
around the circle instead), both eyes at the quest3 eye resolution, 1200^2
radiance textures, N = 4. Each light costs one more evaluation of the networks per texel, so the
shading work grows linearly with k.
"""

from __future__ import annotations

from vrneural.bench import report as rp
from vrneural.bench import timing
from vrneural.bench.configs import LightsConfig
from vrneural.errors import count


def run_lights(cfg: LightsConfig) -> dict:
    c = cfg.resolved()
    scene = timing.bench_scene(max(8, *c.lights))  # light k stays put for any list up to 8

    def report(recs):
        first = min(recs, key=lambda r: r["lights"])  # the fewest lights measured, in any order
        base = first["shading_ms_per_frame"] / first["lights"]
        columns = [
            ("lights", "lights"),
            ("FPS (mean frame ms)", "fps"),
            ("frame ms median", "frame_ms.median"),
            ("frame ms p99", "frame_ms.p99"),
            ("shading ms/frame", "shading_ms_per_frame"),
            ("shading / linear", lambda r: r["shading_ms_per_frame"] / (base * r["lights"])),
            ("forward ms", "forward_ms"),
            ("MLP evals/frame", "mlp_evals_per_frame"),
        ]
        notes = [
            "",
            f"shading / linear: shading ms over (shading ms per light at {first['lights']} "
            "light(s) x lights); 1 = linear.",
        ]
        setting = (
            f"Benchmark scene, {count(c.loop.eyes, 'eye')} at {c.loop.eye_res}, "
            f"texture {c.texture_res}^2"
        )
        plots = [("lights.png", "lights", lambda d, path: plot(d, base, path))]
        title = "# Lights: frame time over the number of point lights (paper Fig. 10)"
        return title, setting, columns, notes, plots

    return timing.count_bench(c, "lights", c.lights, lambda k: (scene, k), "light count", report)


def plot(doc: dict, base: float, path) -> None:
    """FPS and GPU ms per frame against the light count; ``base``: shading ms per light of
    the linear reference."""
    from matplotlib.ticker import MaxNLocator

    fig, (ax, ax2) = rp.figure(9, 3.6, 2)
    recs = doc["records"]
    ks = [r["lights"] for r in recs]
    ax.plot(ks, [r["fps"] for r in recs], "o-")
    ax.set_xlabel("point lights")
    ax.set_ylabel("FPS (mean frame time)")
    ax.grid(alpha=0.3)
    ax2.plot(ks, [r["shading_ms_per_frame"] for r in recs], "o-", label="neural shading")
    ax2.plot(ks, [base * k for k in ks], "k:", label="linear in lights")
    ax2.plot(ks, [r["forward_ms"] for r in recs], "s-", label="forward")
    ax2.set_xlabel("point lights")
    ax2.set_ylabel("GPU ms per displayed frame")
    ax2.legend(fontsize=7)
    ax2.grid(alpha=0.3)
    for a in (ax, ax2):  # light counts are whole: no 1.5 or 2.5 ticks
        a.xaxis.set_major_locator(MaxNLocator(integer=True))
    fig.suptitle(f"bench lights on {doc['adapter']['name']}", fontsize=9)
    rp.save_png(fig, path)
