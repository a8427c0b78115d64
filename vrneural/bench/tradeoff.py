"""`vrneural bench tradeoff`: what each knob buys and costs, against the per-pixel teacher.

Along the standard head-motion path (the built-in orbit) through the benchmark scene, with its
neural objects given a trained pack, each knob is varied alone from a base setting (texture
``base_res``^2, N = ``base_reuse``, staggered, f32, the distilled coarse-to-fine student, per-eye
radiance textures): texture resolution, N, schedule, precision, the network (student without
distillation, single-level 8-wide, NeuMIP-sized) and per-pixel screen space. Every displayed
frame (both eyes side by side) is compared with the teacher rendered per pixel every frame
(``--mode reference``): HDR-FLIP at the eye image's pixels per degree (eye height / profile
FOV), PSNR and SSIM on the tone-mapped display image (:mod:`vrneural.bench.metrics`). Frame time:
mean wall ms per displayed frame (1000 / FPS; amortised updates included), frame 0 excluded.
Shared (both-eye) radiance textures do not exist in this runtime (it shades per eye).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vrneural.bench import metrics, shimmer
from vrneural.bench import report as rp
from vrneural.config import is_explicit, mark_explicit, opt, quick_defaults, replace_config
from vrneural.errors import count

LABELS = {
    "student": "student (distilled)",
    "student_nodistill": "student w/o distillation",
    "single8": "single-level 8-wide",
    "neumip": "NeuMIP-sized 4x25",
}


@dataclass
class TradeoffConfig:
    """`vrneural bench tradeoff`."""

    out: str = opt("bench-tradeoff", "output directory", cli=False)
    eye_res: str = opt("344x368", "pixels per eye (quest3 / 6), WIDTHxHEIGHT")
    frames: int = opt(16, "displayed frames per setting (frame 0 is never scored)")
    scored: int = opt(4, "frames (evenly spaced in 1..frames-1) scored with FLIP, PSNR, SSIM")
    texture_res: str = opt("100,200,400", "texture sides compared (comma-separated)")
    base_res: int = opt(200, "texture side of the base setting (~ quest3's ratio 1200 / 2208)")
    reuse: str = opt("0,1,2,4,6", "update intervals N compared")
    base_reuse: int = opt(4, "N of the base setting")
    lights: int = opt(2, "point lights")
    preset: str = opt("leather", "synthetic BTF preset of the trained packs")
    btf_res: int = opt(32, "BTF texels per side (training budget)")
    btf_dirs: int = opt(10, "BTF light and view directions (dirs^2 slices)")
    teacher_width: int = opt(
        128, "teacher hidden width (the paper's; the streamed reference kernel makes it cheap)"
    )
    teacher_epochs: int = opt(4, "teacher epochs")
    epochs: int = opt(4, "epochs of each small network")
    seed: int = opt(0, "training seed")
    packs: str = opt(
        "",
        "directory with teacher/student/student_nodistill/single8/neumip.vrnm (skips training; "
        "each must be what its name says, all from one BTF and its teacher)",
    )
    shimmer_frames: int = opt(24, "frames of the temporal-shimmer test (0 = skip it)")
    shimmer_res: str = opt("258x276", "eye resolution of the shimmer test (one eye)")
    quick: bool = opt(
        False,
        "CI-sized: eyes 172x184, 6 frames (2 scored), textures 100,200, N 0,4, tiny training "
        "(16^2 texels, 6 dirs, 1 epoch, teacher 32 wide), shimmer 6 frames at 129x138",
    )
    progress: bool = opt(True, "show progress bars")
    force: bool = opt(False, "overwrite an existing output directory")

    def resolved(self) -> TradeoffConfig:
        if not self.quick:
            return self
        return quick_defaults(
            self,
            eye_res="172x184",
            frames=6,
            scored=2,
            texture_res="100,200",
            base_res=200,
            reuse="0,4",
            btf_res=16,
            btf_dirs=6,
            teacher_width=32,
            teacher_epochs=1,
            epochs=1,
            shimmer_frames=6,
            shimmer_res="129x138",
        )


#: Frames of the first setting rendered, untimed, before any setting is timed
WARMUP_FRAMES = 3


def settings(c: TradeoffConfig, has_f16: bool, networks=("student_nodistill", "single8", "neumip")):
    from vrneural.runtime.config import REUSE_MAX

    base = dict(
        knob="base",
        value="-",
        mode="texture",
        texture_res=c.base_res,
        reuse=c.base_reuse,
        schedule="staggered",
        precision="f32",
        material="student",
    )
    out = [base]
    for t in rp.int_list("--texture-res", c.texture_res, *rp.texture_res_range(), even=True):
        if t != c.base_res:
            out.append({**base, "knob": "texture_res", "value": t, "texture_res": t})
    for n in rp.int_list("--reuse", c.reuse, 0, REUSE_MAX):
        if n != c.base_reuse:
            out.append({**base, "knob": "reuse", "value": n, "reuse": n})
    out.append({**base, "knob": "schedule", "value": "burst", "schedule": "burst"})
    if has_f16:
        out.append({**base, "knob": "precision", "value": "f16", "precision": "f16"})
    for m in networks:  # the other networks at the base settings (those with a pack)
        out.append({**base, "knob": "network", "value": m, "material": m})
    out.append(
        {**base, "knob": "mode", "value": "screen (per pixel)", "mode": "screen", "reuse": 0}
    )
    return out


def scene_with(mat, n_lights: int):
    """The benchmark scene (:func:`~vrneural.bench.timing.bench_scene`), both neural objects
    using material ``mat``."""
    from vrneural.bench.timing import bench_scene

    return bench_scene(n_lights, (mat, mat))


def render(scene, s, frames: list[int], bar=None, keep=None):
    """Render ``frames`` in order. Returns (frame -> HDR image ``[H, 2W, 3]``, both eyes side by
    side, for the frames in ``keep`` (default all); every frame's FrameStats). A reference
    renderer has no temporal state, so it may skip frames."""
    from vrneural.runtime.renderer import Renderer

    r = Renderer(scene, s)
    keep = set(frames if keep is None else keep)
    imgs, st = {}, []
    for f in frames:
        st.append(r.frame(f))
        if f in keep:
            imgs[f] = np.concatenate([e[..., :3] for e in r.read_eyes()], 1)
        if bar:
            bar.update()
    return imgs, st


def check_budget(c: TradeoffConfig) -> None:
    """Validate the packs' training budget before any output exists (``train_packs`` would
    check it too, but only after the output directory was made, naming its own flags): the
    BTF as `btf synth` checks it, the epochs as `bench quality` does."""
    from vrneural.btf.synth import BtfConfig
    from vrneural.errors import check_range

    btf = BtfConfig(preset=c.preset, res=c.btf_res, dirs=c.btf_dirs, seed=c.seed)
    btf.validate(flags={"res": "--btf-res", "dirs": "--btf-dirs"})
    for k in ("teacher_epochs", "epochs"):
        check_range(f"--{k.replace('_', '-')}", getattr(c, k), 1, 10_000)


def run_tradeoff(cfg: TradeoffConfig) -> dict:
    from tqdm import tqdm

    from vrneural.bench.packs import PACKS, REQUIRED, load_packs, pack_paths, train_packs
    from vrneural.errors import VrnError, check_range
    from vrneural.gpu.device import adapter_summary
    from vrneural.runtime.config import LIGHTS_MAX, REUSE_MAX, parse_res
    from vrneural.runtime.profiles import get_profile
    from vrneural.runtime.renderer import Settings

    c = cfg.resolved()
    eye_res = parse_res(c.eye_res)
    check_range("--frames", c.frames, 2, 10000)
    if not is_explicit(c, "scored"):  # --quick's or the default's count, within your --frames
        c = mark_explicit(replace_config(c, scored=min(c.scored, c.frames - 1)), "scored")
    check_range("--scored", c.scored, 1, c.frames - 1)
    check_range("--teacher-width", c.teacher_width, 4, 512)
    shimmer_res = parse_res(c.shimmer_res, "--shimmer-res")
    check_range("--lights", c.lights, 1, LIGHTS_MAX)
    rp.check_texture_res(c.base_res, "--base-res")
    check_range("--base-reuse", c.base_reuse, 0, REUSE_MAX)
    check_range("--shimmer-frames", c.shimmer_frames, 0, 100000)
    if 0 < c.shimmer_frames < 3:  # frame 0 is the first update; its change needs two more
        raise VrnError(
            f"--shimmer-frames = {c.shimmer_frames} is too few; allowed 0 (skip the test) or "
            "[3, 100000]"
        )
    if is_explicit(c, "packs") and not c.packs.strip():  # "" trains; typed, it was a slip
        raise VrnError("--packs is empty; name the folder of packs, or leave it out to train them")
    given = pack_paths(c.packs) if c.packs else None
    nets = [k for k in PACKS if k not in REQUIRED and (given is None or k in given)]
    sets = settings(c, adapter_summary().features.get("shader-f16", False), nets)
    if given is not None:  # fail before any work or output, also on a pack not what its name says
        load_packs(given)
    else:  # the training budget, under this command's own flag names
        check_budget(c)
    root = rp.prepare_out(cfg.out, cfg.force, "tradeoff")
    t0 = time.perf_counter()
    doc = rp.header("tradeoff", c)
    if given is not None:
        paths = given
        doc["packs"] = {"source": c.packs, "absent": [k for k in PACKS if k not in paths]}
    else:
        budget = dict(
            preset=c.preset,
            res=c.btf_res,
            dirs=c.btf_dirs,
            teacher_width=c.teacher_width,
            teacher_epochs=c.teacher_epochs,
            epochs=c.epochs,
            seed=c.seed,
        )
        tt = time.perf_counter()
        paths = train_packs(root / "packs", budget, c.progress, log=lambda m: None)
        doc["packs"] = {"source": "trained", "budget": budget, "seconds": time.perf_counter() - tt}
    mats = load_packs(paths)
    prof = get_profile("quest3")
    ppd = metrics.pixels_per_degree(eye_res[1], prof.fov_y)
    doc["ppd"] = ppd
    doc["profile_ppd"] = metrics.pixels_per_degree(prof.eye_res[1], prof.fov_y)

    def settings_of(st: dict, mode: str, ref=None) -> Settings:
        return Settings(
            eyes=2,
            reuse=st["reuse"],
            texture_res=st["texture_res"],
            eye_res=eye_res,
            frames=c.frames,
            fps=prof.fps,
            fov_y=prof.fov_y,
            n_lights=c.lights,
            mode=mode,
            schedule=st["schedule"],
            precision=st["precision"],
            reference=ref,
        )

    scored = np.unique(np.linspace(1, c.frames - 1, c.scored).round().astype(int)).tolist()
    doc["scored_frames"] = scored
    bar = tqdm(
        total=c.frames * len(sets) + len(scored) + 1,
        desc="bench tradeoff",
        unit="frame",
        disable=not c.progress,
    )
    teacher = mats["teacher"]
    ref_imgs, ref_st = render(
        scene_with(teacher, c.lights), settings_of(sets[0], "reference", teacher), [0, *scored], bar
    )
    doc["reference"] = _timing(ref_st)
    ref_disp = {f: metrics.display(x) for f, x in ref_imgs.items()}
    # untimed warm-up of the first texture-space setting: without it the row measured first
    # (base) paid the driver's and caches' first use and read slower than it is
    warm = sets[0]
    render(scene_with(mats[warm["material"]], c.lights), settings_of(warm, warm["mode"]),
           list(range(WARMUP_FRAMES)), keep=[])  # fmt: skip
    doc["warmup_frames"] = WARMUP_FRAMES
    for st in sets:
        scene = scene_with(mats[st["material"]], c.lights)
        imgs, stats = render(scene, settings_of(st, st["mode"]), list(range(c.frames)), bar, scored)
        disp = {f: metrics.display(imgs[f]) for f in scored}
        rec = {**st, **_timing(stats)}
        rec["flip"] = float(np.mean([metrics.flip_hdr(ref_imgs[f], imgs[f], ppd) for f in scored]))
        rec["psnr"] = float(np.mean([metrics.psnr(ref_disp[f], disp[f]) for f in scored]))
        rec["ssim"] = float(np.mean([metrics.ssim(ref_disp[f], disp[f]) for f in scored]))
        doc["records"].append(rec)
    bar.close()
    if c.shimmer_frames:
        doc["shimmer"] = shimmer.run_shimmer(mats, c, shimmer_res, root / "shimmer.png")
    md = markdown(doc)
    pareto_png(doc, root / "pareto.png")
    md += ["", "![pareto](pareto.png)"]
    if c.shimmer_frames:
        md += [*shimmer.markdown(doc["shimmer"]), "", "![shimmer](shimmer.png)"]
    return rp.finish(root, doc, md, t0)


def _timing(stats) -> dict:
    w = [s.wall_ms for s in stats[1:]]
    shade = [s.gpu_ms.get("texture", 0.0) + s.gpu_ms.get("screen", 0.0) for s in stats[1:]]
    return {
        "frame_ms": rp.stats(w),
        "fps": 1e3 / float(np.mean(w)),
        "shading_ms_per_frame": float(np.mean(shade)),
        "forward_ms": float(np.median([s.gpu_ms.get("forward", 0.0) for s in stats[1:]])),
    }


def label(r: dict) -> str:
    if r["knob"] == "base":
        return "base"
    if r["knob"] == "network":
        return LABELS[r["value"]]
    return f"{r['knob']}={r['value']}"


def pareto(points: list[tuple[float, float]], lower_better: bool) -> list[int]:
    """Indices of the Pareto-optimal points ``(cost, error)``: no other point is at most as
    costly and strictly better."""
    out = []
    for i, (ci, ei) in enumerate(points):
        dominated = any(
            cj <= ci and (ej < ei if lower_better else ej > ei) and (cj, ej) != (ci, ei)
            for j, (cj, ej) in enumerate(points)
            if j != i
        )
        if not dominated:
            out.append(i)
    return out


def markdown(doc: dict) -> list[str]:
    c = doc["config"]
    recs = doc["records"]
    front = set(pareto([(r["frame_ms"]["mean"], r["flip"]) for r in recs], True))
    md = [
        "# Trade-off: each knob against the per-pixel teacher",
        "",
        rp.adapter_line(doc),
        f"Benchmark scene with trained packs ({_packs_line(doc)}), {count(c['lights'], 'light')}, "
        "both eyes "
        f"at {c['eye_res']}, {c['frames']} frames along the built-in head path. Base: texture "
        f"{c['base_res']}^2, N = {c['base_reuse']}, staggered, f32, distilled student. FLIP: "
        f"HDR, {doc['ppd']:.2f} ppd (eye height / FOV; {doc['profile_ppd']:.1f} at the full "
        f"quest3 resolution); PSNR (dB) and SSIM on the tone-mapped display; each the mean over "
        f"frames {doc['scored_frames']}. Frame ms: mean wall time per displayed frame "
        f"(frame 0 excluded; {doc.get('warmup_frames', 0)} untimed warm-up frames first). "
        f"Reference (teacher per pixel): {doc['reference']['frame_ms']['mean']:.1f} ms/frame."
        + (" **Quick run: reduced settings.**" if c["quick"] else ""),
        "Shared vs per-eye radiance textures: not available (this runtime shades per eye).",
        "",
    ]
    rows = [
        [
            label(r) + (" *" if i in front else ""),
            r["frame_ms"]["mean"],
            r["fps"],
            r["shading_ms_per_frame"],
            r["flip"],
            r["psnr"],
            r["ssim"],
        ]
        for i, r in enumerate(recs)
    ]
    md += rp.table(
        [
            "setting (* Pareto-optimal in FLIP)",
            "frame ms",
            "FPS",
            "shading ms/frame",
            "FLIP",
            "PSNR dB",
            "SSIM",
        ],
        rows,
    )
    return md


def _packs_line(doc: dict) -> str:
    p = doc["packs"]
    if p["source"] != "trained":
        absent = p.get("absent") or []
        return f"from {p['source']}" + (
            f"; no {', '.join(absent)} pack there, so no row for it" if absent else ""
        )
    b = p["budget"]
    return (
        f"{b['preset']} {b['res']}^2 x {b['dirs']}^2 directions, teacher {b['teacher_width']} wide "
        f"{b['teacher_epochs']}"
        f" epochs, others {b['epochs']}, trained in {p['seconds']:.0f} s"
    )


def pareto_png(doc: dict, path: Path) -> None:
    recs = doc["records"]
    fig, axes = rp.figure(14, 4.2, 3)
    for ax, key, lower in zip(axes, ("flip", "psnr", "ssim"), (True, False, False), strict=True):
        pts = [(r["frame_ms"]["mean"], r[key]) for r in recs]
        front = sorted(pareto(pts, lower), key=lambda i: pts[i][0])
        for i, (r, (x, y)) in enumerate(zip(recs, pts, strict=True)):
            ax.scatter(x, y, s=18, color="C3" if r["knob"] == "base" else "C0")
            if i in front or r["knob"] == "base":  # the rest are in the table: no label pile
                ax.annotate(label(r), (x, y), fontsize=6, xytext=(3, 2), textcoords="offset points")
        ax.plot(
            [pts[i][0] for i in front],
            [pts[i][1] for i in front],
            "k--",
            lw=0.8,
            label="Pareto front",
        )
        ax.set_xscale("log")
        rp.plain_log_ticks(ax.xaxis)
        ax.set_xlabel("frame ms (mean, wall)")
        ax.set_ylabel(key.upper() + (" (lower is better)" if lower else " (higher is better)"))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"bench tradeoff on {doc['adapter']['name']}", fontsize=9)
    rp.save_png(fig, path)
