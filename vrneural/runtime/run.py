"""The `vrneural run` stage: resolve the config, render the frames, write outputs and
``summary.json``, return the summary dict."""

from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from vrneural.config import config_dict, given, resolved
from vrneural.errors import VrnError, check_int, check_range, count
from vrneural.formats.vrnm import read_vrnm
from vrneural.interrupt import Stop, interrupt_saying
from vrneural.outputs import OUTPUT_MARK, OutputDir, write_json
from vrneural.outputs.files import make_dirs, why
from vrneural.runtime.config import LIGHTS_MAX, RunConfig, resolve
from vrneural.runtime.output import (
    VideoWriter,
    check_video,
    downscale,
    tonemap,
    write_exr,
    write_png,
)
from vrneural.runtime.pack_teacher import teacher_beside
from vrneural.runtime.scene import (
    MaterialDesc,
    Scene,
    builtin_lights,
    builtin_scene,
    load_scene,
)


def selected_frames(spec: str, frames: int) -> list[int]:
    """Parse ``--save-frames``: 'first,last', 'all', 'none' or comma-separated indices."""
    spec = spec.strip().lower()
    if spec == "all":
        return list(range(frames))
    if spec == "none":
        return []
    if not spec:
        raise VrnError("--save-frames is empty; pass none to save no frames")
    out = set()
    for tok in spec.split(","):
        tok = tok.strip()
        if tok == "first":
            out.add(0)
        elif tok == "last":
            out.add(frames - 1)
        else:
            try:
                k = int(tok)
            except ValueError:
                raise VrnError(
                    f"--save-frames: {tok!r} is not first, last, all or an index"
                ) from None
            if not 0 <= k < frames:
                raise VrnError(
                    f"--save-frames = {spec!r}: frame {k} is out of range; "
                    f"allowed [0, {frames - 1}]"
                )
            out.add(k)
    return sorted(out)


def atlas_summary(atlas) -> dict:
    """Per-object atlas facts for summary.json (neural objects; plain ones have no atlas)."""
    if atlas is None:
        return {}
    st = atlas.stats
    return {
        "texture_res": int(atlas.resolution),
        "triangles": len(atlas.mesh.faces),
        "triangles_without_texels": int(st.get("triangles_without_texels", 0)),
        "coverage_pct": st.get("coverage_pct"),
    }


def use_pack(scene, path: str) -> None:
    """Give every neural object of ``scene`` the runtime pack at ``path`` (``--pack``), each
    object keeping its tiling. Its teacher pack (:func:`teacher_beside`) becomes the ``--mode
    reference``; a teacher pack is its own, so ``--pack teacher.vrnm --mode reference`` renders
    it."""
    p = Path(path)
    if not p.is_file():
        what = "a directory, not a pack file" if p.is_dir() else "file not found"
        raise VrnError(f"--pack = {path!r}: {what}")
    mat = read_vrnm(p)
    if mat.meta.get("method") == "teacher":  # a teacher is its own per-pixel reference
        ref, source, looked = mat, str(p.resolve()), ""
    else:
        found, ref, tried = teacher_beside(p, mat)
        source = str(found.resolve()) if found else ""
        looked = "" if found else "looked for " + ", ".join(tried)
    for o in scene.objects:
        if o.material.kind == "neural":
            if scene.name == "builtin":  # "leather sphere" would name a material not shown
                o.name = f"{p.stem} {o.mesh}"
            o.material = MaterialDesc(
                "neural",
                mat,
                str(p.resolve()),
                o.material.tiling,
                reference=ref,
                reference_source=source,
                reference_hint=looked,
            )


def load_run_scene(cfg: RunConfig, scene=None) -> Scene:
    """The scene `run` renders: ``scene`` (a :class:`~vrneural.runtime.scene.Scene` or a scene
    file; default ``cfg.scene``), else the built-in one with ``--lights`` and ``--pack``
    applied. ``--pack`` with a scene of one's own is refused."""
    scene = scene if scene is not None else cfg.scene or None
    if scene is not None and cfg.pack:
        raise VrnError(
            f"--pack = {cfg.pack!r} replaces the built-in scene's materials; with a SCENE file, "
            "set pack = ... in its [[objects]] instead"
        )
    if isinstance(scene, Scene):
        return scene
    if scene is not None:
        return load_scene(scene)
    # its three lights (more generated for --lights N > 3); the profile shades the first
    if cfg.lights is not None:  # named as the option, before the scene would name it
        check_int("--lights", cfg.lights, 0, LIGHTS_MAX)
    sc = builtin_scene(max(len(builtin_lights()), cfg.lights or 0))
    if cfg.pack:
        use_pack(sc, cfg.pack)
    return sc


def default_out() -> Path:
    """Create a new ``out/run-YYYYmmdd-HHMMSS`` (suffixed ``-2``, ``-3``... if taken; claimed
    by an exclusive mkdir, so two runs started in the same second get two directories)."""
    base = time.strftime("out/run-%Y%m%d-%H%M%S")
    k = 1
    while True:
        p = Path(base if k == 1 else f"{base}-{k}")
        try:
            make_dirs(p.parent)
            p.mkdir()
            return p
        except OSError as e:
            if isinstance(e, FileExistsError) and p.parent.is_dir():  # taken: the next name
                k += 1
                continue
            raise VrnError(f"{p}: cannot create output directory ({why(p, e)})") from None


def percentiles(x) -> dict:
    """``{median, p95, p99, mean, max}`` of a sequence of numbers; ``{}`` for none."""
    a = np.asarray(x, np.float64)
    if not len(a):
        return {}
    return {
        "median": float(np.median(a)),
        "p95": float(np.percentile(a, 95)),
        "p99": float(np.percentile(a, 99)),
        "mean": float(a.mean()),
        "max": float(a.max()),
    }


def run(cfg: RunConfig, progress: bool = True) -> dict:
    """Render ``cfg``; returns the summary (also written to ``OUT/summary.json``)."""
    if cfg.out is not None and not cfg.out.strip():
        raise VrnError("--out is empty; name a directory, or leave --out out for out/run-<time>")
    if cfg.out:
        with OutputDir(cfg.out, "run", force=cfg.force) as od:
            return _run(cfg, od, progress)
    new_parent = not Path("out").exists()  # default_out makes out/ itself: then it goes too
    out = default_out()
    try:
        with OutputDir(out, "run", force=cfg.force) as od:
            return _run(cfg, od, progress)
    except BaseException:
        # failed or stopped before it wrote anything: leave nothing behind
        if out.is_dir() and all(c.name == OUTPUT_MARK for c in out.iterdir()):
            (out / OUTPUT_MARK).unlink(missing_ok=True)
            out.rmdir()
            if new_parent and not any(out.parent.iterdir()):
                out.parent.rmdir()
        raise


def _run(cfg: RunConfig, od: OutputDir, progress: bool) -> dict:
    from vrneural.gpu.device import adapter_summary
    from vrneural.runtime.renderer import Renderer

    out = od.path
    chosen = given(cfg)  # the fields given (None: not given): a knob that does nothing is named
    cfg = resolved(dataclasses.replace(cfg, out=str(out)))
    n_builtin = len(builtin_lights())
    scene = load_run_scene(cfg)
    adapter = adapter_summary()
    s = resolve(dataclasses.replace(cfg, scene=None, pack=None), scene, adapter)  # both applied
    save = selected_frames(cfg.save_frames, s.frames)
    video = None
    if cfg.video:  # every eye keeps at least 2 x 2 pixels (libx264's minimum, 2x2 blocks)
        top = max(1, min(s.eye_res) // 2)
        if "video_scale" not in chosen:  # the default adapts to small eyes: a video whose
            # eyes keep at least VIDEO_MIN_PX pixels on their short side (quest3: 4, tiny: 1)
            fit = max(1, min(s.eye_res) // VIDEO_MIN_PX)
            cfg = dataclasses.replace(cfg, video_scale=min(cfg.video_scale, fit, top))
        check_range("--video-scale", cfg.video_scale, 1, top)
        check_video()
    od.check()
    t_setup = time.perf_counter()
    # set-up stages (mesh load, atlas, shader compile per object) on one transient bar, on a
    # terminal only (a log or a captured stderr keeps its lines: errors stay one line)
    shown = progress and sys.stderr.isatty()
    with tqdm(
        total=None, desc="vrneural run set-up", unit="stage", disable=not shown, leave=False
    ) as setup_bar:

        def stage(text: str) -> None:
            setup_bar.set_postfix_str(text, refresh=False)
            setup_bar.update()

        # validates the packs: a failure here leaves --out untouched
        r = Renderer(scene, s, progress=stage if shown else None)
    setup_s = time.perf_counter() - t_setup
    if cfg.scene and cfg.lights is None and len(scene.lights) > s.n_lights:
        r.warnings.append(
            f"{scene.src}: the scene has {count(len(scene.lights), 'light')} and the "
            f"{cfg.profile or scene.profile or 'quest3'} profile shades the first "
            f"{s.n_lights}; --lights {len(scene.lights)} shades them all"
        )
    if r.neural and not scene.lights:
        r.warnings.append(f"{scene.src}: the scene has no [[lights]]: neural objects are black")
    elif r.neural and s.n_lights == 0:  # asked for (a timing baseline), but say what it gives
        r.warnings.append(
            f"--lights 0: none of the scene's {count(len(scene.lights), 'light')} is shaded, so "
            "neural objects are black (--lights N shades the first N)"
        )
    if not cfg.scene and s.n_lights > n_builtin:
        r.warnings.append(
            f"--lights {s.n_lights}: the built-in scene has {n_builtin} lights; "
            f"{count(s.n_lights - n_builtin, 'generated light')} added (a SCENE "
            "file has only the lights it defines)"
        )
    knobs = ("reuse", "schedule", "radiance", "reuse_budget", "mips", "screen_res")
    unused = [f"--{k.replace('_', '-')}" for k in knobs if k in chosen]
    if s.mode != "texture" and unused:  # texture space's knobs: say they do nothing here
        r.warnings.append(
            f"{' and '.join(unused)} only {'apply' if len(unused) > 1 else 'applies'} to "
            f"--mode texture; --mode {s.mode} shades every pixel every frame"
        )
    if not cfg.video and "video_scale" in chosen:  # does nothing: say so
        r.warnings.append("--video-scale only applies to the video, and --no-video writes none")
    for w in r.warnings:
        print(f"warning: {w}", file=sys.stderr)
    od.open()
    if cfg.video:
        video = VideoWriter(out / ("stereo.mp4" if s.eyes == 2 else "mono.mp4"), s.fps)
    stats, files = [], []
    interrupted = False
    bar = tqdm(range(s.frames), desc="vrneural run", unit="frame", disable=not progress)

    display = s.target == "display"  # 8-bit sRGB eyes: PNG frames and video, no EXR

    def read() -> list[np.ndarray]:  # the last frame's eyes: HDR radiance or display colours
        return r.read_display() if display else r.read_eyes()

    def write_frame(f: int, eyes) -> None:
        for e, img in enumerate(eyes):
            name = f"frame{f:04d}_eye{e}"
            files.append(str(write_png(out / f"{name}.png", img if display else tonemap(img))))
            if not display:
                files.append(str(write_exr(out / f"{name}.exr", img)))

    def video_frame(img) -> np.ndarray:  # an eye as the video shows it, uint8 sRGB
        if display:  # averaged in sRGB values (the HDR path averages radiance)
            return np.round(downscale(img, cfg.video_scale)).astype(np.uint8)
        return tonemap(downscale(img, cfg.video_scale))

    # Ctrl-C stops between frames (a second one at once): every frame counted in the summary
    # is in the video and its saved images, and the video stays playable
    try:
        with Stop() as stop:
            for f in bar:
                stop.second_raises = True  # a slow frame: a second Ctrl-C stops it at once
                st = r.frame(f)
                stop.second_raises = False  # writing: finish it, so saved files stay whole
                if f in save or video is not None:
                    eyes = read()
                    if f in save:
                        write_frame(f, eyes)
                    if video is not None:
                        video.add([video_frame(img) for img in eyes])
                stats.append(st)
                if stop.flag:
                    break
        interrupted = clean = stop.flag
    except KeyboardInterrupt:  # the second Ctrl-C, mid-frame: keep what was finished
        interrupted, clean = True, False
    except BaseException:  # an error (a full disk, say): no half-written video left behind
        if video is not None:
            video.abort()
        raise
    finally:
        bar.close()
    r.wait()  # the last frames' statistics (frames in flight)
    if interrupted and not stats:
        raise KeyboardInterrupt  # nothing rendered; the marked --out is replaced by --force
    if r.neural and not any(st.blocks_shaded or st.pixels_shaded for st in stats):
        r.warnings.append(  # frames all black where the neural objects should be
            "no texel or pixel of a neural object faced an eye in any frame (an eye inside an "
            "object, whose inside faces are culled, or every object out of view?)"
        )
        print(f"warning: {r.warnings[-1]}", file=sys.stderr)
    with Stop():  # more Ctrl-C while the video and summary are written: finish writing them
        last = len(stats) - 1
        if interrupted and clean and "last" in cfg.save_frames.lower() and last not in save:
            write_frame(last, read())  # --save-frames last: the last frame rendered
        if video is not None:
            try:
                files.append(str(video.close()))
            except Exception:
                if not interrupted:
                    raise
                # a second Ctrl-C inside the encoder: then there is no video to keep
        summary = make_summary(cfg, s, scene, adapter, stats, setup_s, files, r)
        summary["interrupted"] = interrupted
        write_json(out / "summary.json", summary)
        od.seal()
    if interrupted:
        kept = ["summary.json"]
        n_png = sum(f.endswith(".png") for f in files)
        if n_png:
            kept.append(f"{n_png} frame PNG(s)" + ("" if display else " + EXR"))
        if any(f.endswith(".mp4") for f in files):
            kept.append(f"{Path(video.path).name} ({len(stats)} frames)")
        raise interrupt_saying(
            f"after {len(stats)} of {s.frames} frames; {out} keeps {', '.join(kept)} "
            "(--force replaces them)"
        )
    return summary


#: the default --video-scale (4) is lowered so that each eye in the video keeps at least this
#: many pixels on its short side: a tiny profile's 96-pixel eyes were a 48 x 24 video
VIDEO_MIN_PX = 256


def make_summary(cfg, s, scene, adapter, stats, setup_s, files, r) -> dict:
    settings = dataclasses.asdict(dataclasses.replace(s, reference=None))
    settings["reference"] = cfg.reference
    settings["colour_clear"] = r.colour_clear  # "auto" resolved for this adapter
    settings["depth_clear"] = r.depth_clear
    warm = stats[1:] if len(stats) > 1 else stats  # frame 0 includes shader compilation
    atlases = {n.idx: n.atlas for n in r.neural}
    gpu_names = sorted({k for st in stats for k in st.gpu_ms})
    texture = s.mode == "texture"  # 2x2 blocks of texels; the other modes shade pixels
    unit = "blocks" if texture else "pixels"
    shaded = [st.blocks_shaded if texture else st.pixels_shaded for st in stats]
    per_frame = {
        "wall_ms": [round(st.wall_ms, 3) for st in stats],
        "updated_objects": [st.updated_objects for st in stats],
        "culled_objects": [st.culled_objects for st in stats],
        f"{unit}_shaded": shaded,
        f"{unit}_backfacing": [st.blocks_backfacing for st in stats],  # the shader's 2nd counter
        "mlp_coarse": [st.mlp_coarse for st in stats],  # a single-level network counts as fine
        "mlp_fine": [st.mlp_fine for st in stats],
        "gpu_ms": {k: [round(st.gpu_ms.get(k, 0.0), 4) for st in stats] for k in gpu_names},
        "host_ms": [round(st.host_ms, 3) for st in stats],
        "host_cpu_ms": [round(st.cpu_ms, 3) for st in stats],
    }
    if s.mode == "texture":  # per neural object: its side, texels allocated and shaded
        per_frame["object_res"] = [st.object_res for st in stats]
        per_frame["object_texels_allocated"] = [st.object_texels for st in stats]
        per_frame["object_texels_shaded"] = [[4 * b for b in st.object_blocks] for st in stats]
        per_frame["object_lod_scale"] = [[round(x, 4) for x in st.object_lod_scale]
                                         for st in stats]  # fmt: skip
    ref = str(Path(cfg.reference).resolve()) if cfg.reference else None
    evals = [a + b for a, b in zip(per_frame["mlp_coarse"], per_frame["mlp_fine"], strict=True)]
    return {
        "adapter": adapter.to_dict(),
        "config": config_dict(cfg),
        "resolved": settings,
        "scene": {
            "name": scene.name,
            "objects": [
                {
                    "name": o.name,
                    "mesh": o.mesh,
                    "material": o.material.kind,
                    "source": o.material.source,
                    # the teacher shaded in reference mode: --reference's, else the material's own
                    **(
                        {"reference": ref or o.material.reference_source or None}
                        if s.mode == "reference" and o.material.kind == "neural"
                        else {}
                    ),
                    "tiling": o.material.tiling,
                    **atlas_summary(atlases.get(i)),
                }
                for i, o in enumerate(scene.objects)
            ],
            "lights": len(r.lights),  # shaded: the first of the scene's
            "scene_lights": len(scene.lights),
        },
        "frames": len(stats),
        "updates": int(sum(st.updated_objects > 0 for st in stats)),
        "setup_s": round(setup_s, 3),
        "frame_wall_ms": percentiles([st.wall_ms for st in warm]),
        "host_cpu_ms": percentiles([st.cpu_ms for st in warm]),
        "frames_in_flight": s.frames_in_flight,
        "gpu_ms": {
            k: percentiles(per_frame["gpu_ms"][k][1:] or per_frame["gpu_ms"][k]) for k in gpu_names
        },
        # passes whose timestamps this adapter does not cover (runtime/timecheck.py)
        "gpu_untimed": dict.fromkeys(r.untimed, UNTIMED_NOTE),
        # the work of frame 0 is a full first update whatever the schedule: left out as well
        f"{unit}_shaded_per_frame": percentiles(shaded[1:] or shaded),
        "mlp_evaluations_per_frame": percentiles(evals[1:] or evals),
        "warnings": list(r.warnings),
        "per_frame": per_frame,
        "out": cfg.out,
        "files": files,
        "note": "the percentiles (frame_wall_ms, gpu_ms, *_shaded_per_frame, "
        "mlp_evaluations_per_frame) exclude frame 0: it compiles shaders and updates every "
        "texture in full; per_frame lists every frame"
        if len(stats) > 1
        else "one frame: its percentiles include shader compilation and the first full "
        "update (--frames 2 or more leaves frame 0 out)",
    }


UNTIMED_NOTE = (
    "this adapter's timestamps do not cover this pass (checked against the wall clock after the "
    "first frame: runtime/timecheck.py); its time is in frame_wall_ms, and `vrneural bench "
    "frame` times it by the wall clock"
)


def _texture_text(profile_res: int, sm: dict, given: bool = False) -> str:
    """The run line's texture side: the profile's (or ``--texture-res``, ``given``), or the
    objects' own where a scene's ``texture_res`` / ``min_texture_res`` changed it (listed per
    object on the next lines)."""
    sides = sorted({o["texture_res"] for o in sm["scene"]["objects"] if "texture_res" in o})
    if not sides or sides == [profile_res]:
        return f"{profile_res}^2"
    shown = f"{sides[0]}^2" if len(sides) == 1 else f"{sides[0]}^2-{sides[-1]}^2"
    return f"{shown} (per object; {'--texture-res' if given else 'profile'} {profile_res}^2)"


def human_summary(sm: dict) -> str:
    r = sm["resolved"]
    fw = sm["frame_wall_ms"]
    texture = r["mode"] == "texture"  # reuse, schedule and the texture only exist there
    unit = "blocks" if texture else "pixels"
    reuse = r["reuse"] if r.get("reuse_budget") is None else f"auto({r['reuse_budget']:g} deg)"
    shared = " radiance=shared" if r.get("radiance") == "shared" else ""
    shared += " mips" if r.get("mips") else ""
    shared += " screen-res" if r.get("screen_res") else ""
    shared += " no-neural-lod" if r.get("neural_lod") is False else ""
    shared += f" lod-taps={r['lod_taps']}" if r.get("lod_taps", 1) > 1 else ""
    shared += " neural-filter=exact" if r.get("neural_filter") == "exact" else ""
    shared += " target=display" if r.get("target") == "display" else ""
    space = (
        f"reuse={reuse} schedule={r['schedule']}{shared} "
        if texture
        else "(per pixel, every frame) "
    )
    given = r.get("texture_res_given", False)
    tex = f" texture={_texture_text(r['texture_res'], sm, given)}" if texture else ""
    updates = f" (updates in {sm['updates']})" if texture else ""
    lines = [
        f"adapter   {sm['adapter']['name']} ({sm['adapter']['backend']})",
        f"run       mode={r['mode']} eyes={r['eyes']} {space}precision={r['precision']}{tex} "
        f"eye={r['eye_res'][0]}x{r['eye_res'][1]} lights={r['n_lights']}",
        f"frames    {sm['frames']}{updates}, setup {sm['setup_s']:.1f} s",
        f"frame ms  median {fw.get('median', 0):.1f}  p95 {fw.get('p95', 0):.1f}  "
        f"p99 {fw.get('p99', 0):.1f} (wall, frame to frame, {sm.get('frames_in_flight', 1)} in "
        "flight; incl. writing outputs"
        + ("" if sm["frames"] > 1 else "; one frame: includes shader compilation")
        + ")",
        "gpu ms    "
        + "  ".join(
            [f"{k} {v['median']:.2f}" for k, v in sm["gpu_ms"].items()]
            + [f"{k} n/a (timestamps do not cover it here)" for k in sm.get("gpu_untimed", {})]
        ),
        f"per frame {unit} shaded {sm[f'{unit}_shaded_per_frame'].get('median', 0):.0f}, MLP evals "
        f"{sm['mlp_evaluations_per_frame'].get('median', 0):.0f} (median)",
    ]
    objs = [o for o in sm["scene"]["objects"] if "texture_res" in o]
    if objs and texture:  # each neural object's own texture and atlas (pixel modes: unused)
        lines.append(
            "objects   "
            + ", ".join(
                f"{o['name']} {o['texture_res']}^2 {o['coverage_pct']:.0f}% texels"
                + (
                    f" ({o['triangles_without_texels']} tris w/o texel)"
                    if o["triangles_without_texels"]
                    else ""
                )
                for o in objs
            )
        )
    return "\n".join(lines)
