"""``vrneural bench extremes``: every numerical-extreme case of the pipeline, one report.

Each case (``vrneural/bench/extremes_*.py``) either works with its documented behaviour or is
rejected with a one-line error; anything else is a FAIL. The run writes ``results.json`` (one
record per case: outcome, message, measured values, seconds), ``results.md`` (the table) and
``f16_error.png`` (histogram of the f16-vs-f32 relative error). Heavy cases (1M triangles, the
largest accepted texture) run in full size only without ``--quick``. Exit code 1 on any FAIL.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from tqdm import tqdm

from vrneural.bench import extremes_geometry as geo
from vrneural.bench import extremes_precision as prec
from vrneural.bench import extremes_settings as sett
from vrneural.bench import extremes_shading as shd
from vrneural.bench import extremes_training as trn
from vrneural.bench import terminator as term
from vrneural.bench.extremes_fixtures import run_case
from vrneural.config import opt

W, R = "works", "rejected"
#: (case, group, function, expected outcome, what it checks)
CASES = [
    (
        "grazing_89.99deg",
        "directions",
        shd.case_dir_grazing,
        W,
        "finite, >= 0, Lipschitz-continuous",
    ),
    ("normal_and_wi=-wo", "directions", shd.case_dir_normal_and_opposite, W, "h fallback (0,0,1)"),
    ("horizon_twin", "directions", shd.case_dir_horizon, W, "tapers to 0, no jump; 0 below"),
    ("horizon_gpu", "directions", shd.case_dir_horizon_gpu, W, "same on the GPU, f32 + f16"),
    ("grazing_gpu", "directions", shd.case_dir_grazing_gpu, W, "GPU vs twin at 89.99 deg"),
    ("terminator", "directions", term.case_dir_terminator, W, "step <= 1% of peak, 3 modes"),
    ("unnormalized_frames", "directions", shd.case_dir_unnormalized, W, "scaled frames = unit"),
    ("f16_vs_f32", "precision", prec.case_prec_f16_vs_f32, W, "max / p99.9 relative error"),
    ("clamp_1e6_at_1e-4m", "precision", prec.case_prec_clamp, W, "clamped to 65504, finite"),
    ("no_flush_to_zero", "precision", prec.case_prec_no_flush, W, "values >= 2^-14 kept"),
    ("wide_rgba32float", "precision", prec.case_prec_wide_storage, W, "option: cost + error"),
    ("intensity_above_1e6", "precision", prec.case_intensity_limit, R, "scene loader limit"),
    ("zero_area_3d", "geometry", geo.case_geo_zero_area_3d, W, "skipped with a warning"),
    ("zero_area_uv", "geometry", geo.case_geo_zero_area_uv, W, "fallback tangent frame"),
    ("slivers_1e-5", "geometry", geo.case_geo_sliver, W, "atlas + kernel finite"),
    ("one_triangle", "geometry", geo.case_geo_one_triangle, W, "atlas + kernel"),
    ("non_manifold", "geometry", geo.case_geo_non_manifold, W, "fin + bow-tie"),
    ("nan_vertex", "geometry", geo.case_geo_nan_vertex, R, "make_mesh"),
    ("inf_vertex_obj", "geometry", geo.case_geo_inf_vertex_file, R, "load_mesh"),
    ("far_1e5m", "geometry", geo.case_geo_far_origin, W, "camera-relative = at origin"),
    ("many_triangles", "geometry", geo.case_geo_many_triangles, W, "1M (quick: 20k)"),
    ("far_1e5m_render", "geometry", sett.case_set_far_origin_render, W, "image = at origin"),
    ("tex_res_2_kernel", "settings", sett.case_set_kernel_res_2, W, "kernel alone, one block"),
    ("tex_res_2_run", "settings", sett.case_set_tex_res_2, R, "atlas needs R >= 8"),
    ("tex_res_odd", "settings", sett.case_set_tex_res_odd, R, "2x2 blocks"),
    ("tex_res_max", "settings", sett.case_set_tex_res_max, W, "largest accepted (quick: 1024)"),
    ("tex_res_above_max", "settings", sett.case_set_tex_res_above_max, R, "adapter max + 2"),
    ("reuse_N=0", "settings", sett.case_set_reuse_0, W, "update every frame"),
    ("reuse_N=1000", "settings", sett.case_set_reuse_1000, W, "staggered 1/1001"),
    ("lights_0", "settings", sett.case_set_lights_0, W, "black, no MLP work"),
    ("lights_16", "settings", sett.case_set_lights_16, W, "16 lights"),
    ("1_eye_1_frame", "settings", sett.case_set_one_eye_one_frame, W, "minimal run"),
    ("btf_all_zeros", "training", trn.case_train_zeros, W, "finite, loss falls"),
    ("btf_hdr_1e4", "training", trn.case_train_hdr, W, "finite (linear + log space)"),
    ("btf_nan", "training", trn.case_train_nan, R, "one-line error"),
    ("lr_floor", "training", trn.case_train_lr_floor, W, "reaches and keeps lr_min"),
    ("1_epoch", "training", trn.case_train_one_epoch, W, "one epoch"),
]


@dataclass
class ExtremesConfig:
    """``vrneural bench extremes`` settings."""

    quick: bool = opt(
        False, "small sizes for the heavy cases (1M triangles -> 20k, max texture -> 1024)"
    )
    only: str | None = opt(
        None,
        "comma-separated case names or groups to run: "
        f"{', '.join(sorted({c[1] for c in CASES}))} (default: all)",
    )
    force: bool = opt(False, "overwrite an existing --out directory")
    progress: bool = opt(True, "show a progress bar (--no-progress: none)")


def selected(only: str, given: bool = False) -> list:
    """The cases ``--only`` names (all of them when it is not ``given`` and empty)."""
    from vrneural.errors import VrnError

    if not only and not given:
        return CASES
    items = [t.strip() for t in only.split(",")]
    if not all(items):
        what = "is empty" if not any(items) else f"= {only!r} has an empty item"
        groups = ", ".join(sorted({c[1] for c in CASES}))
        raise VrnError(f"--only {what}; name cases or groups ({groups}), or leave it out")
    keys = set(items)
    known = {c[0] for c in CASES} | {c[1] for c in CASES}
    bad = sorted(keys - known)
    if bad:
        groups = ", ".join(sorted({c[1] for c in CASES}))
        raise VrnError(
            f"--only = {only!r}: unknown case or group {bad[0]!r}; groups: {groups}; "
            f"cases: {', '.join(c[0] for c in CASES)}"
        )
    return [c for c in CASES if c[0] in keys or c[1] in keys]


def run_extremes(cfg: ExtremesConfig, out: str) -> dict:
    """Run the cases, write the report into ``out``; returns the results document."""
    from vrneural.bench.extremes_report import write_report
    from vrneural.bench.report import header, prepare_out

    cases = selected(cfg.only or "", cfg.only is not None)
    with prepare_out(out, cfg.force, "extremes") as root:
        t0 = time.perf_counter()
        doc = header("extremes", cfg)
        bar = tqdm(cases, desc="bench extremes", unit="case", disable=not cfg.progress)
        for name, group, fn, expect, what in bar:
            rec = run_case(name, group, fn, expect, cfg.quick)
            rec["checks"] = what
            doc["records"].append(rec)
        return write_report(root, doc, t0)
