"""The H200 page's figure from its JSON: ``python docs/results/h200/plot.py`` writes
``main-job.png``: ms per frame by configuration, the GPU's passes beside the wall time (left),
and render passes that only cover the main job's targets against compute passes writing the
same texels (right)."""

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = Path(__file__).parent
runs = json.loads((HERE / "main-job.json").read_text())["runs"]
ROWS = [  # label in main-job.json, label on the plot
    ("e90c611", "e90c611 (#41 filed)"),
    ("682f982_in_flight_1", "682f982, 1 in flight"),
    ("682f982", "682f982 (session start)"),
    ("depth_discarded", "682f982+ depth discarded"),
    ("depth24plus", "682f982+ depth24plus"),
    ("depth16unorm", "682f982+ depth16unorm"),
    ("display_srgb_target", "682f982+ 8-bit sRGB target"),
    ("compute_clear_trial", "682f982+ compute clear"),
    ("now", "6004025: colour cleared in compute"),
    ("now_display", "6004025, --target display"),
    ("depth_pass", "now, --depth-clear pass (= 6004025)"),
    ("depth_slices", "now: depth cleared 1 frame in 4"),
    ("depth_slices_in_flight_3", "now, 3 frames in flight"),
    ("depth_slices_display", "now, --target display"),
    ("release_sixth_call", "now, sixth call"),
    ("release_msaa4", "now, --msaa 4"),
    ("half_eyes_1032x1104", "682f982+, 1/4 of the pixels"),
]
fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.6), gridspec_kw={"width_ratios": [1.15, 1]})
y = range(len(ROWS))
wall = [runs[k]["wall_ms_median"] for k, _ in ROWS]
fwd = [runs[k]["rounds"][0]["gpu_ms"]["forward"] for k, _ in ROWS]
tex = [runs[k]["rounds"][0]["gpu_ms"].get("texture", 0.0) for k, _ in ROWS]
a1.barh([i + 0.2 for i in y], wall, 0.4, color="C0", label="wall per frame (median)")
a1.barh([i - 0.2 for i in y], fwd, 0.4, color="C1", label="GPU: forward pass")
a1.barh([i - 0.2 for i in y], tex, 0.4, left=fwd, color="C2", label="GPU: texture-space pass")
for i, w in enumerate(wall):
    a1.text(w + 0.05, i + 0.2, f"{w:.2f} ms, {1e3 / w:.0f} FPS", va="center", fontsize=7)
a1.axvline(7.11 / 2.5, color="0.4", ls="--", lw=1)
a1.text(7.11 / 2.5, -0.75, " 2.5x e90c611", fontsize=7, color="0.3")
a1.set_yticks(list(y), [lab for _, lab in ROWS], fontsize=8)
a1.invert_yaxis()
a1.set_xlabel("ms")
a1.set_xlim(0, 15.5)
a1.legend(fontsize=7, loc="upper right")
a1.set_title("the main job (quest3, 2 eyes, N = 4, 3 lights) on an NVIDIA H200", fontsize=9)

floor = json.loads((HERE / "raster_floor.json").read_text())["rows"]
FLOORS = [
    ("renderer colour (rgba16float, storage usage) + depth32float", "clear both + triangle"),
    ("colour loaded, not cleared + depth32float (discard)", "colour loaded + triangle"),
    ("compute clear, then colour loaded + depth32float (discard); both passes",
     "compute clear + colour loaded + triangle"),
    ("compute clear, then colour loaded + depth32float in 4 slices (3 passes in 4 load it)",
     "... + depth cleared 1 pass in 4"),
    ("compute clear, then colour loaded + depth32float loaded, never cleared",
     "... + depth never cleared"),
    ("clear alone: rgba16float + depth32float", "clear both, no draw"),
    ("clear alone: rgba16float", "clear colour, no draw"),
    ("clear alone: depth32float", "clear depth, no draw"),
    ("depth32float only", "depth only + triangle"),
    ("compute: store rgba16float", "compute: store every texel"),
    ("fragment: 256 FMAs per pixel, rgba16float + depth32float", "fragment: 256 FMAs/pixel"),
    ("compute: 256 FMAs per texel + store", "compute: 256 FMAs/texel"),
]  # fmt: skip
ms = [floor[k]["timestamp_ms"] for k, _ in FLOORS]
colours = ["C4" if lab.startswith("compute:") else "0.55" for _, lab in FLOORS]
a2.barh(range(len(FLOORS)), ms, color=colours)
for i, v in enumerate(ms):
    a2.text(v * 1.08, i, f"{v:.2f}", va="center", fontsize=7)
a2.set_xscale("log")
a2.set_xlim(0.05, 80)
a2.set_yticks(range(len(FLOORS)), [lab for _, lab in FLOORS], fontsize=8)
a2.invert_yaxis()
a2.set_xlabel("ms (GPU timestamps), log scale")
a2.set_title("passes that only cover 4128x2208 px\n(grey: render pass, purple: compute)",
              fontsize=9)
fig.tight_layout()
fig.savefig(HERE / "main-job.png", dpi=110)
