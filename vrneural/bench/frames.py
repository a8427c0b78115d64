"""`vrneural bench frames`: the paper's Table 2 on this adapter.

Frame time of the benchmark scene (a neural sphere and a neural tile on a plain floor, one point
light, both eyes at the quest3 eye resolution) over radiance-texture resolution x update interval
N, for the burst and staggered schedules, plus per-pixel screen-space shading of the same
student. Shown as FPS (from the mean frame time) and ms (median, p99).
"""

from __future__ import annotations

import time

from vrneural.bench import report as rp
from vrneural.bench import timing
from vrneural.bench.configs import FramesConfig
from vrneural.errors import check_range, count
from vrneural.runtime.config import LIGHTS_MAX
from vrneural.runtime.profiles import get_profile


def run_frames(cfg: FramesConfig) -> dict:
    c = cfg.resolved()
    texs, reuses, scheds = rp.texture_list(c.texture_res), c.reuse, c.schedules
    eye_res = c.loop.check()
    check_range("--lights", c.lights, 1, LIGHTS_MAX)
    check_range("--min-frames", c.min_frames, 1, 1000)
    with rp.prepare_out(cfg.out, cfg.force, "frames") as root:
        t0 = time.perf_counter()
        prof = get_profile("quest3")
        doc = rp.header("frames", c)
        scene = timing.bench_scene(c.lights)
        kw = dict(
            eye_res=eye_res, eyes=c.loop.eyes, n_lights=c.lights, fps=prof.fps, fov_y=prof.fov_y
        )
        per_res = sum(timing.frames_for(n, c.loop.cycles, c.min_frames) for n in reuses) * len(
            scheds
        )
        total = per_res * len(texs) + (c.min_frames if c.screen else 0)
        bar = timing.progress(total, "bench frames", c.progress)
        for res in texs:
            r = timing.make_renderer(scene, texture_res=res, **kw)
            for sched in scheds:
                for n in reuses:
                    rec = timing.measured_record(
                        r, n, sched, c.loop.cycles, c.min_frames, bar.update, c.loop.warmup
                    )
                    rec["schedule"], rec["reuse"] = sched, n
                    doc["records"].append(rec)
            del r
        if c.screen:
            r = timing.make_renderer(scene, mode="screen", texture_res=texs[0], **kw)
            rec = timing.measured_record(r, 0, "burst", 1, c.min_frames, bar.update, c.loop.warmup)
            doc["records"].append(rec)
        bar.close()
        md = markdown(doc)
        plot(doc, root / "frames.png")
        md += ["", "![frame time](frames.png)"]
        return rp.finish(root, doc, md, t0)


def _cell(rec: dict) -> str:
    f = rec["frame_ms"]
    return f"{rec['fps']:.1f} FPS ({f['median']:.1f} / {f['p99']:.1f} ms)"


def markdown(doc: dict) -> list[str]:
    recs = doc["records"]
    c = doc["config"]
    tex = [r for r in recs if r["mode"] == "texture"]
    texs = sorted({r["texture_res"] for r in tex})
    md = [
        "# Frames: frame time over texture resolution x update interval (paper Table 2)",
        "",
        rp.adapter_line(doc),
        "Benchmark scene (2 neural objects with random student weights + plain floor), "
        f"{count(c['lights'], 'light')}, {count(c['eyes'], 'eye')} at {c['eye_res']}; "
        f">= {c['min_frames']} frames and {count(c['cycles'], 'update cycle')} per configuration "
        "after "
        f"{c.get('warmup', 0)} s of unmeasured frames (frame 0 of each renderer excluded)."
        + (" **Quick run: reduced grid.**" if c["quick"] else ""),
        "Cells: FPS from the mean frame time (median / p99 frame ms, wall clock incl. GPU wait).",
    ]
    for sched in dict.fromkeys(r["schedule"] for r in tex):
        md += ["", f"## Schedule: {sched}", ""]
        rows = []
        for n in sorted({r["reuse"] for r in tex}):
            row = [n]
            for t in texs:
                m = [
                    r
                    for r in tex
                    if r["schedule"] == sched and r["reuse"] == n and r["texture_res"] == t
                ]
                row.append(_cell(m[0]) if m else "-")
            rows.append(row)
        md += rp.table(["N \\ texture"] + [f"{t}^2" for t in texs], rows)
    scr = [r for r in recs if r["mode"] == "screen"]
    if scr:
        md += [
            "",
            f"Screen space (per pixel, every frame): {_cell(scr[0])}; shading "
            f"{scr[0]['shading_ms_per_frame']:.1f} ms/frame.",
        ]
    md += ["", "## Neural shading GPU ms per displayed frame (amortised) and forward ms", ""]
    md += rp.record_table(
        tex,
        [
            ("schedule", "schedule"),
            ("texture", "texture_res"),
            ("N", "reuse"),
            ("shading ms/frame", "shading_ms_per_frame"),
            ("shading ms max", "shading_ms_max"),
            ("forward ms", "forward_ms"),
            ("MLP evals/frame", "mlp_evals_per_frame"),
        ],
    )
    return md


def plot(doc: dict, path) -> None:
    from matplotlib.ticker import MaxNLocator

    recs = doc["records"]
    tex = [r for r in recs if r["mode"] == "texture"]
    scheds = list(dict.fromkeys(r["schedule"] for r in tex))
    fig, axes = rp.figure(5.0 * len(scheds), 3.8, len(scheds), sharey=True)
    scr = [r for r in recs if r["mode"] == "screen"]
    for ax, sched in zip(axes, scheds, strict=True):
        for t in sorted({r["texture_res"] for r in tex}):
            rr = sorted(
                (r for r in tex if r["schedule"] == sched and r["texture_res"] == t),
                key=lambda r: r["reuse"],
            )
            x = [r["reuse"] for r in rr]
            ax.plot(x, [r["frame_ms"]["median"] for r in rr], "o-", label=f"{t}^2 median")
            ax.plot(x, [r["frame_ms"]["p99"] for r in rr], "x:", color=ax.lines[-1].get_color())
        if scr:
            ax.axhline(scr[0]["frame_ms"]["median"], color="k", ls="--", label="screen space")
        ax.set_title(f"{sched} (o median, x p99)")
        ax.set_xlabel("update interval N")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))  # N is a whole number of frames
        ax.set_yscale("log")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("frame ms (wall)")
    axes[-1].legend(fontsize=7)
    fig.suptitle(f"bench frames on {doc['adapter']['name']}", fontsize=9)
    rp.save_png(fig, path)
