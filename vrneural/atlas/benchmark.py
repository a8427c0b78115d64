"""Atlas benchmark: wall time of the unwrap, rasterization, sliver fixes and dilation.

``python -m vrneural.atlas.benchmark [--mesh highpoly] [--res 1200] [--repeats 3]
[-o atlas_bench.json]`` builds the atlas ``repeats`` times without the cache and writes JSON
(per-run stage times, the median per stage, the atlas stats, the machine) plus a PNG bar
chart beside it. Times are wall-clock seconds on the CPU that runs it (the atlas stage does not
use the GPU); on a shared machine, compare medians from one run only.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

from vrneural.atlas.build import build_atlas
from vrneural.atlas.builtin import BUILTIN_MESHES, builtin_mesh
from vrneural.atlas.config import (
    MAX_PADDING,
    MAX_RESOLUTION,
    MIN_RESOLUTION,
    check_texture_resolution,
)
from vrneural.errors import ArgumentParser, VrnError, check_range
from vrneural.outputs import check_output, write_json
from vrneural.presentation import pyplot, save_png

STAGES = ("unwrap_s", "raster_s", "sliver_s", "dilate_s", "total_s")


def run_benchmark(mesh_name: str, resolution: int, padding: int, repeats: int) -> dict:
    """Build ``repeats`` uncached atlases; returns the JSON-ready result."""
    t = time.perf_counter()
    mesh = builtin_mesh(mesh_name)
    mesh_s = time.perf_counter() - t
    runs = []
    for _ in range(repeats):
        cpu = time.process_time()
        atlas = build_atlas(mesh, resolution, padding, cache=False, progress=True)
        runs.append({k: atlas.stats[k] for k in STAGES} | {"cpu_s": time.process_time() - cpu})
    median = {k: float(np.median([r[k] for r in runs])) for k in (*STAGES, "cpu_s")}
    keep = (
        "charts",
        "coverage_pct",
        "filled_pct",
        "texels_per_triangle_min",
        "texels_per_triangle_median",
        "triangles_without_texels",
        "density_spread",
    )
    return {
        "mesh": mesh_name,
        "triangles": len(mesh.faces),
        "resolution": resolution,
        "padding": padding,
        "mesh_build_s": mesh_s,
        "median": median,
        "runs": runs,
        "stats": {k: atlas.stats[k] for k in keep},
        "machine": {
            "cpu_count": os.cpu_count(),
            "load_avg_1m": os.getloadavg()[0],
            "python": platform.python_version(),
            "processor": platform.processor() or platform.machine(),
        },
    }


def plot(result: dict, path: Path) -> None:
    """A horizontal stacked bar of the median stage times (PNG)."""
    fig, ax = pyplot().subplots(figsize=(7, 2.4))
    left = 0.0
    for k in STAGES[:-1]:
        v = result["median"][k]
        ax.barh([0], [v], left=left, label=f"{k[:-2]} {v:.2f} s")
        left += v
    ax.set_yticks([])
    ax.set_xlabel("seconds (median)")
    ax.set_title(f"atlas {result['mesh']} ({result['triangles']} tris) at {result['resolution']}^2")
    ax.legend(ncol=4, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.6))
    fig.subplots_adjust(left=0.04, right=0.97, top=0.82, bottom=0.5)
    save_png(fig, path, dpi=120, bbox=None)


def main(argv: list[str] | None = None) -> int:
    """The command line; a user error (:class:`VrnError`, a bad option) prints one line and
    returns (argparse: exits with) 2."""
    prog = "python -m vrneural.atlas.benchmark"
    p = ArgumentParser(
        prog=prog,
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "--mesh",
        default="highpoly",
        choices=BUILTIN_MESHES,
        help="built-in mesh to unwrap (default: %(default)s)",
    )
    p.add_argument(
        "--res",
        type=int,
        default=1200,
        help=f"atlas resolution R, even, in [{MIN_RESOLUTION}, {MAX_RESOLUTION}] "
        "(default: %(default)s)",
    )
    p.add_argument(
        "--padding",
        type=int,
        default=2,
        help=f"gutter width in texels around charts, in [0, {MAX_PADDING}] (default: %(default)s)",
    )
    p.add_argument(
        "--repeats",
        type=int,
        default=3,
        help="uncached builds timed, >= 1; the JSON reports their median (default: %(default)s)",
    )
    p.add_argument(
        "-o",
        "--output",
        default="atlas_bench.json",
        help="JSON written here, the PNG chart beside it with suffix .png (default: %(default)s)",
    )
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    a = p.parse_args(argv)
    try:
        out = _check_args(a)
        result = run_benchmark(a.mesh, a.res, a.padding, a.repeats)
    except VrnError as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
        return e.exit_code

    write_json(out, result)
    plot(result, out.with_suffix(".png"))
    m = result["median"]
    print(
        f"{a.mesh} ({result['triangles']} tris) {a.res}^2: unwrap {m['unwrap_s']:.2f} s, raster "
        f"{m['raster_s']:.2f} s, slivers {m['sliver_s']:.3f} s, dilate {m['dilate_s']:.2f} s, "
        f"total {m['total_s']:.2f} s (median of {len(result['runs'])}) -> {out}"
    )
    return 0


def _check_args(a: argparse.Namespace) -> Path:
    """Validate the options before any work (one-line :class:`VrnError`); returns the JSON
    path."""
    check_texture_resolution("--res", a.res)
    check_range("--padding", a.padding, 0, MAX_PADDING)
    check_range("--repeats", a.repeats, 1, 1000)
    if Path(a.output).suffix.lower() == ".png":
        raise VrnError(
            f"--output {a.output}: the PNG chart is written beside the JSON, with suffix .png; "
            "name a .json file"
        )
    out = check_output(a.output, a.force)
    check_output(out.with_suffix(".png"), a.force)
    return out


if __name__ == "__main__":
    sys.exit(main())
