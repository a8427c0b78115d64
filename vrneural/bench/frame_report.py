"""`vrneural bench frame`'s summary (ratios per round, medians over rounds), Markdown and PNG."""

from __future__ import annotations

import numpy as np

from vrneural.bench import report as rp

#: (ratio name, numerator pass, denominator pass): passes timed alone (clock: see summarise)
PASS_RATIOS = (
    ("forward_vs_sample_floor", "forward", "forward_floor_sample"),
    ("forward_vs_constant_floor", "forward", "forward_floor_constant"),
    ("sample_floor_vs_constant_floor", "forward_floor_sample", "forward_floor_constant"),
    # the raster floor (one triangle over each viewport) and the same texels stored in compute
    ("forward_vs_screen_floor", "forward", "forward_floor_screen"),
    ("screen_floor_vs_colour_store", "forward_floor_screen", "colour_store"),
    ("display_vs_hdr_forward", "forward_display", "forward"),
    ("texture_vs_bare", "texture_full", "texture_bare"),
    ("texture_vs_loads_floor", "texture_full", "texture_loads"),
    ("loads_floor_vs_bare", "texture_loads", "texture_bare"),
    ("texture_slice_vs_bare", "texture_slice", "texture_slice_bare"),
    # the neural textures filtered exactly in the shader (Settings.neural_filter "exact")
    ("exact_texture_vs_bare", "texture_full_exact", "texture_bare"),
    ("exact_loads_floor_vs_bare", "texture_loads_exact", "texture_bare"),
    ("hardware_vs_exact_full", "texture_full", "texture_full_exact"),
    ("hardware_vs_exact_slice", "texture_slice", "texture_slice_exact"),
    # --parallax-steps: the same update with height-field parallax
    ("parallax_vs_texture", "texture_full_parallax", "texture_full"),
    ("parallax_slice_vs_texture_slice", "texture_slice_parallax", "texture_slice"),
    ("parallax_block_vs_texture", "texture_full_parallax_block", "texture_full"),
    ("parallax_block_slice_vs_texture_slice", "texture_slice_parallax_block", "texture_slice"),
    ("parallax_auto_vs_texture", "texture_full_parallax_auto", "texture_full"),
    ("parallax_auto_slice_vs_texture_slice", "texture_slice_parallax_auto", "texture_slice"),
    # --neural-offset: the same update with NeuMIP's neural offset module
    ("offset_vs_texture", "texture_full_offset", "texture_full"),
    ("offset_slice_vs_texture_slice", "texture_slice_offset", "texture_slice"),
    ("offset_block_vs_texture", "texture_full_offset_block", "texture_full"),
    ("offset_block_slice_vs_texture_slice", "texture_slice_offset_block", "texture_slice"),
    ("offset_auto_vs_texture", "texture_full_offset_auto", "texture_full"),
    ("offset_auto_slice_vs_texture_slice", "texture_slice_offset_auto", "texture_slice"),
)


def _med(x) -> float:
    return float(np.median(np.asarray(x, np.float64)))


def _covered(p: dict, empty_ms: float) -> bool:
    """Whether a pass's own timestamps agree with its wall time (runtime/timecheck.py's rule;
    checked per pass: on lavapipe a kernel that reads no texture is not timed by them)."""
    from vrneural.runtime.timecheck import HIGH, LOW, MIN_MS

    if p["timestamp_ms"] is None:
        return False
    work = max(p["wall_ms"] - empty_ms, 0.0)
    return work >= MIN_MS and LOW * work <= p["timestamp_ms"] <= HIGH * p["wall_ms"]


def summarise(doc: dict, reuse: int) -> dict:
    """Medians over rounds: per pass its wall (timestamp, CPU) ms, the ratios of
    :data:`PASS_RATIOS` (each taken within a round: on a CPU adapter by CPU time, else by
    timestamps where this adapter's cover both passes, else by the wall clock), and per
    frames-in-flight depth the loop's wall, host CPU and GPU per frame and wall / max(host
    CPU, GPU)."""
    recs = doc["records"]
    # a CPU adapter's passes are this process's threads: their CPU time is the passes' work,
    # unlike the wall clock and timestamps not stretched by other processes on the cores
    cpu = doc["adapter"].get("is_cpu") and "cpu_ms" in recs[0]["passes"]["forward"]

    def clock(name: str) -> str:  # timestamps where they agree with the wall in every round
        ok = all(_covered(r["passes"][name], r["empty_submit_ms"]) for r in recs)
        return "timestamp_ms" if ok else "wall_ms"

    passes = {}
    for name in recs[0]["passes"]:
        ts = [r["passes"][name]["timestamp_ms"] for r in recs]
        passes[name] = {
            "wall_ms": _med([r["passes"][name]["wall_ms"] for r in recs]),
            "timestamp_ms": _med(ts) if None not in ts else None,
            "timestamps_agree": clock(name) == "timestamp_ms",
        }
        if cpu:
            passes[name]["cpu_ms"] = _med([r["passes"][name]["cpu_ms"] for r in recs])
    ratios = {}
    for key, a, b in PASS_RATIOS:
        if a not in recs[0]["passes"]:
            continue
        ck = "cpu_ms" if cpu else clock(a) if clock(a) == clock(b) else "wall_ms"
        per = [r["passes"][a][ck] / r["passes"][b][ck] for r in recs]
        ratios[key] = {"median": _med(per), "range": [float(min(per)), float(max(per))],
                       "clock": ck[:-3]}  # fmt: skip
    loops = {}
    for d in recs[0]["loop"]:
        gpu, rows = [], []
        for r in recs:
            p = r["passes"]
            g = p["texture_slice"]["wall_ms"] + p["forward"]["wall_ms"]  # a staggered frame
            lp = r["loop"][d]
            gpu.append(g)
            rows.append((lp["wall_ms"], lp["host_cpu_ms"], lp["in_flight"],
                         lp["wall_ms"] / max(lp["host_cpu_ms"], g),
                         lp.get("poll_cpu_ms", np.nan)))  # fmt: skip
        a = np.asarray(rows)
        loops[str(d)] = {
            "wall_ms": _med(a[:, 0]),
            "host_cpu_ms": _med(a[:, 1]),
            **({"poll_cpu_ms": _med(a[:, 4])} if not np.isnan(a[:, 4]).any() else {}),
            "in_flight": _med(a[:, 2]),
            "gpu_ms": _med(gpu),
            "wall_vs_bound": _med(a[:, 3]),
            "wall_vs_sum": _med(a[:, 0] / (a[:, 1] + np.asarray(gpu))),
        }
    return {"passes": passes, "ratios": ratios, "loops": loops, "reuse": reuse}


def markdown(doc: dict) -> list[str]:
    c, sm, tg = doc["config"], doc["summary"], doc["targets"]
    cov = doc.get("timestamp_check") or {}
    covered = ", ".join(f"{k}: {'yes' if v['covered'] else 'no'}" for k, v in cov.items())
    md = [
        "# Frame: where a frame's time goes, against the adapter's floors",
        "",
        rp.adapter_line(doc),
        f"Benchmark scene (2 neural objects, plain floor), {c['lights']} light(s), 2 eyes at "
        f"{c['eye_res']}, {c['texture_res']}^2 radiance textures, N = {c['reuse']} staggered; "
        f"{c['rounds']} interleaved rounds (medians), {c['frames']} frames per loop, "
        f"{c['repeats']} repeats per pass." + (" **Quick run.**" if c["quick"] else ""),
        "Each pass is submitted alone. On a CPU adapter two passes are compared by the CPU time "
        "of all of this process's threads from submit to completion (the passes' work, which "
        "other processes on the same cores stretch far less than the wall clock); on others by "
        "their timestamps where these agree with each one's wall time (less an empty submit) in "
        "every round, else by the wall clock (submit to completion). Timestamps marked "
        "(wrong) disagree with their pass's wall time and are not used. The renderer's own "
        "check of its passes inside a frame (runtime/timecheck.py): "
        f"{covered or 'no timestamps'}.",
        "Floors: `forward_floor_constant` / `forward_floor_sample`, the forward pass's draws "
        "with a constant colour / one bilinear sample per fragment; `forward_floor_screen`, "
        "its clears and one constant-colour triangle over each eye's viewport (the raster "
        "floor); `colour_store`, the compute pass storing black in every texel of the eyes' "
        "colour target; `texture_bare` / `texture_loads`, the texture-space kernel without "
        "shading / with only its neural-texture lookups.",
        "",
        "## Passes (each alone)",
        "",
    ]

    def stamp(name: str, v: dict):
        if v["timestamp_ms"] is None:
            return "-"
        return v["timestamp_ms"] if v["timestamps_agree"] else f"{v['timestamp_ms']:.3g} (wrong)"

    cpu = ["CPU ms (all threads)"] if "cpu_ms" in sm["passes"]["forward"] else []
    rows = [[k, v["wall_ms"], stamp(k, v), *([v["cpu_ms"]] if cpu else [])]
            for k, v in sm["passes"].items()]  # fmt: skip
    md += rp.table(["pass", "wall ms", "timestamp ms", *cpu], rows)
    md += ["", "## Ratios (per round, median [range])", ""]
    rows = []
    for k, v in sm["ratios"].items():
        target = tg.get(k)
        ok = "" if target is None else ("met" if v["median"] <= target else "missed")
        if ok and v["range"][0] <= target <= v["range"][1]:
            ok += " (the range crosses it)"
        rows.append([k, v["median"], f"[{v['range'][0]:.3g}, {v['range'][1]:.3g}]", v["clock"],
                     target if target is not None else "-", ok])  # fmt: skip
    md += rp.table(["ratio", "median", "range", "clock", "target", ""], rows)
    raster = sm["ratios"].get("screen_floor_vs_colour_store")
    if raster is not None:
        md += ["", f"Raster floor / colour store {raster['median']:.3g}: what covering every "
               "pixel once costs a forward pass here (its clears and one triangle per viewport) "
               "over what storing the eyes' colour texels costs a compute pass; where the clear "
               "of the colour "
               "is that compute pass (GPUs: `Settings.colour_clear`) the floor includes it"
               + (". By the wall clock, which adds a submit's own cost to each pass: a lower "
                  "bound where the compute pass is short" if raster["clock"] == "wall" else "")
               + "."]  # fmt: skip
    for kind, share in doc.get("auto_block_share", {}).items():
        md += ["", f"March auto ({kind}): {100 * share:.0f}% of the blocks march once per "
               "2x2 block (at most one texel of the grid wide), the rest per texel."]  # fmt: skip
    if "auto_block_share_by_side" in doc:
        sides = ", ".join(f"{s}^2: {100 * v:.0f}%"
                          for s, v in doc["auto_block_share_by_side"].items())  # fmt: skip
        md += ["", f"The same blocks with materials of other sizes (march auto, once per block): "
               f"{sides}."]  # fmt: skip
    md += ["", "## Frame loop (frames back to back)", ""]
    poll = all("poll_cpu_ms" in v for v in sm["loops"].values())  # results from before it: none
    rows = [
        [d, v["in_flight"], v["wall_ms"], v["host_cpu_ms"], *([v["poll_cpu_ms"]] if poll else []),
         v["gpu_ms"], v["wall_vs_bound"], v["wall_vs_sum"]]
        for d, v in sm["loops"].items()
    ]  # fmt: skip
    md += rp.table(
        ["frames in flight", "queued (mean)", "wall ms/frame", "host CPU ms/frame",
         *(["wgpu poll thread CPU ms/frame"] if poll else []),
         "GPU ms/frame (passes alone, wall)", "wall / max(host, GPU)", "wall / (host + GPU)"],
        rows,
    )  # fmt: skip
    poll_note = (
        "; the wgpu poll thread's is host work too, off the main thread (it polls the device "
        "and runs the read-backs' map callbacks)"
    )
    md += [
        "",
        "GPU ms/frame: a staggered update of every radiance texture plus both eyes' forward "
        "passes, each submitted alone and timed by the wall clock (each carries a submit's "
        "fixed cost, so their sum can exceed a frame's wall time in the loop). Host CPU: the "
        "main thread's CPU time in `frame()` and in "
        "reading the statistics"
        + (poll_note if poll else "")
        + f". Target for wall / max(host, GPU): <= {tg['wall_vs_bound']}. "
        "On a CPU adapter the GPU's work runs on the same cores as the host, so the two cannot "
        "fully overlap there.",
    ]
    return md


def plot(doc: dict, path) -> None:
    sm = doc["summary"]
    fig, (a1, a2) = rp.figure(11.0, 3.8, 2)
    groups = [
        ["colour_store", "forward_floor_screen", "forward_floor_constant", "forward_floor_sample",
         "forward", "forward_display"],
        ["texture_bare", "texture_loads", "texture_full", "texture_loads_exact",
         "texture_full_exact"],
        ["texture_slice_bare", "texture_slice", "texture_slice_exact"],
    ]  # fmt: skip
    key = "cpu_ms" if "cpu_ms" in sm["passes"]["forward"] else "wall_ms"  # the ratios' clock
    x, pos, labels = 0, [], []
    for names in groups:  # a gap of half a bar between the groups
        for n in (n for n in names if n in sm["passes"]):  # results from before *_exact too
            floor = "floor" in n or "bare" in n or "loads" in n or n == "colour_store"
            exact = n.endswith("_exact")
            colour = ("0.85" if floor else "C1") if exact else ("0.7" if floor else "C0")
            a1.bar(x, sm["passes"][n][key], color=colour)
            pos.append(x)
            labels.append(n.replace("forward_", "").replace("texture_", "tex ").replace("_", " "))
            x += 1
        x += 0.5
    a1.set_xticks(pos, labels, rotation=40, ha="right", fontsize=7)
    a1.set_ylabel(
        "ms, each pass alone (" + ("CPU, all threads" if key == "cpu_ms" else "wall") + ")"
    )
    a1.set_title("passes (grey: floors; orange, light grey: the exact neural filter)", fontsize=9)
    d = list(sm["loops"])
    for key, lab in (("wall_ms", "wall / frame"), ("host_cpu_ms", "host CPU / frame"),
                     ("gpu_ms", "GPU / frame (passes alone, wall)")):  # fmt: skip
        a2.plot(d, [sm["loops"][k][key] for k in d], "o-", label=lab)
    a2.set_xlabel("frames in flight")
    a2.set_ylabel("ms")
    a2.set_title("frame loop", fontsize=9)
    a2.legend(fontsize=7)
    fig.suptitle(f"bench frame on {doc['adapter']['name']}", fontsize=9)
    rp.save_png(fig, path)
