"""The timing helpers of :mod:`vrneural.bench.runtime` and its ``schedules`` measurement:
the frame-time distribution of the burst and staggered schedules beside a constant-work
control, and the quality each schedule shows."""

from __future__ import annotations

import math
import time

import numpy as np

from vrneural.runtime.scene import builtin_scene


def wall_ms(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return (time.perf_counter() - t0) * 1e3


def median_ms(fn, repeats: int) -> float:
    fn()  # warm-up / compile
    return float(np.median([wall_ms(fn) for _ in range(repeats)]))


def make_renderer(mode, texture_res, eye_res, reuse=0, schedule="burst"):
    """A renderer of the built-in scene (3 lights, both eyes); frame 0 not yet rendered."""
    from vrneural.runtime.renderer import Renderer, Settings

    s = Settings(reuse=reuse, texture_res=texture_res, eye_res=eye_res, frames=1, n_lights=3,
                 mode=mode, schedule=schedule)  # fmt: skip
    return Renderer(builtin_scene(3), s)


def _timed_frames(r, frames: int) -> dict:
    """Frame wall ms, texture GPU ms and MLP evaluations of frames 1 .. frames - 1 of renderer
    ``r``, rendered back to back (nothing else between frames; frame 0 compiles)."""
    out = {"wall": [], "cpu": [], "tex": [], "work": []}
    for f in range(frames):
        c0 = time.process_time()
        st = r.frame(f)
        if f:
            out["cpu"].append((time.process_time() - c0) * 1e3)
            out["wall"].append(st.wall_ms)
            out["tex"].append(st.gpu_ms.get("texture", 0.0))
            out["work"].append(st.mlp_coarse + st.mlp_fine)
    return out


def _summary(x, *stats: str, series: bool = True) -> dict:
    """``{"median", *stats, "series"}`` of ``x`` (a stat ``pN``: the Nth percentile, ``max``;
    the series rounded to 3 decimals, in frame order)."""
    out = {"median": float(np.median(x))}
    for k in stats:
        out[k] = float(np.max(x) if k == "max" else np.percentile(x, int(k[1:])))
    return out | ({"series": [round(float(v), 3) for v in x]} if series else {})


def _distribution(t: dict) -> dict:
    w, work = np.asarray(t["wall"]), np.asarray(t["work"], np.float64)
    return {
        "frame_wall_ms": _summary(w, "p95", "p99"),  # frames 1.. in order
        "p99_over_median": float(np.percentile(w, 99) / np.median(w)),
        # CPU time of the whole process (all llvmpipe threads) per frame: on a CPU adapter the
        # frame's cost without the time other jobs on the machine took from it
        "frame_cpu_ms": _summary(t["cpu"], "p99"),
        "cpu_p99_over_median": float(np.percentile(t["cpu"], 99) / np.median(t["cpu"])),
        "texture_gpu_ms": _summary(t["tex"], "max"),
        # the work per frame from the counters (MLP evaluations), immune to CPU contention
        "mlp_evals_per_frame": _summary(work, "p99", series=False),
        "work_p99_over_median": float(np.percentile(work, 99) / max(np.median(work), 1.0)),
    }


def schedules(texture_res=1200, eye_res=(256, 256), reuse=4, frames=91, quality_frames=41) -> dict:
    """Frame-time distribution of burst and staggered (each renderer's frames back to back,
    ``frames - 1`` timed), with a constant-work control of about the staggered frame's cost (a
    full update every frame, N = 0, of a texture with 1 / (N + 1) of the texels) that shows this
    machine's own frame-time noise; then, in a separate untimed run, their displayed-frame error
    vs rendering with an update every frame, on the built-in scene."""
    out = {}
    kinds = ("burst", "staggered")
    for k in kinds:
        out[k] = _distribution(
            _timed_frames(make_renderer("texture", texture_res, eye_res, reuse, k), frames)
        )
    # constant work per frame of about the staggered frame's size: a full update every frame
    # (N = 0) of a texture with 1 / (N + 1) of the texels (at least 64^2, for the atlas packer)
    ctl_res = max(64, round(texture_res / math.sqrt(reuse + 1) / 2) * 2)
    ctl = _distribution(_timed_frames(make_renderer("texture", ctl_res, eye_res, 0), frames))
    keep = ("frame_wall_ms", "p99_over_median", "frame_cpu_ms", "cpu_p99_over_median")
    out["control_every_frame"] = {
        "texture_res": ctl_res,
        "mlp_evals_per_frame": ctl["mlp_evals_per_frame"],
        **{k: ctl[k] for k in keep},
    }
    ref = make_renderer("texture", texture_res, eye_res, 0, "burst")
    runs = {k: make_renderer("texture", texture_res, eye_res, reuse, k) for k in kinds}
    err = {k: [] for k in runs}
    for f in range(quality_frames):
        ref.frame(f)
        want = np.concatenate(ref.read_eyes(), 1)[..., :3]
        for k, r in runs.items():
            r.frame(f)
            got = np.concatenate(r.read_eyes(), 1)[..., :3]
            if f >= reuse + 1:  # after the first complete staggered cycle
                err[k].append(float(np.abs(got - want).mean()))
    for k in runs:
        out[k]["mean_abs_error_vs_every_frame"] = float(np.mean(err[k]))
    out["config"] = {
        "texture_res": texture_res,
        "eye_res": list(eye_res),
        "reuse": reuse,
        "frames": frames,
        "quality_frames": quality_frames,
        "mean_displayed_radiance": float(want.mean()),
    }
    out["target_staggered_p99_over_median"] = 1.2
    return out
