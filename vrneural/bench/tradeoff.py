"""`vrneural bench tradeoff`: what each knob buys and costs, where it bites.

The ground truth is the teacher per pixel in f32, supersampled (``--spp`` stratified sub-pixel
samples, :mod:`vrneural.bench.supersample`); a second reference with other sample positions gives
its noise floor, and every difference is read against it. The images are crops of the full quest3
eye (23 pixels per degree) that follow a neural sphere (:mod:`vrneural.bench.trade_scene`), under
conditions that make reuse and resolution matter: head turns from rest to 400 deg/s about the
neck, a moving light, distances from 0.3 to 20 m, material tiling, and the built-in slow orbit
(where every knob is varied, as before). Knobs: N (staggered; burst), texture resolution,
radiance textures shared by both eyes, adaptive reuse (``--reuse auto``, its budget matched to the
fixed N's mean shading work on the fastest turn), precision, the network, per-pixel shading.

Per condition and variant, over the scored frames (both eyes): HDR-FLIP against the reference at
the headset's pixels per degree (mean, p95, worst frame), PSNR and SSIM of the displayed image,
the temporal change (mean |frame - previous| of the display image, and FLIP between consecutive
frames, against the reference's own), the reuse error (FLIP against the N = 0 render of the same
frame), the work (2x2 blocks shaded, MLP evaluations per frame) and the frame time.
"""

from __future__ import annotations

import itertools
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from vrneural.bench import report as rp
from vrneural.bench import trade_scene as ts
from vrneural.bench.packs import PACKS, REQUIRED, load_packs, pack_paths, train_packs
from vrneural.bench.trade_scene import render, scheduled_candidates
from vrneural.bench.tradeoff_report import finish_report, label
from vrneural.bench.train_configs import TradeoffConfig
from vrneural.errors import VrnError, check_range
from vrneural.runtime.config import LIGHTS_MAX, REUSE_MAX
from vrneural.runtime.profiles import get_profile
from vrneural.scoring import metrics


def variant(knob="base", value="-", **kw) -> dict:
    base = dict(
        knob=knob,
        value=value,
        mode="texture",
        texture_res=None,
        reuse=None,
        schedule="staggered",
        precision="f32",
        material="student",
        radiance="per-eye",
        budget=None,
    )
    return {**base, **kw}


def variants_for(c, cond: ts.Condition, nets, has_f16: bool, budget: float | None) -> list:
    """The variants scored under ``cond`` (the first is N = 0: the reuse error's reference;
    the second the base)."""
    out = [variant("reuse", 0, reuse=0), variant()]
    reuse_rows = [variant("reuse", n, reuse=n) for n in c.reuse if n not in (0, c.base_reuse)]
    burst = variant("schedule", "burst", schedule="burst")
    shared = variant("radiance", "shared", radiance="shared")
    auto = [variant("reuse", "auto", budget=budget)] if budget else []
    res_rows = [variant("texture_res", t, texture_res=t) for t in c.texture_res if t != c.base_res]
    if cond.family in ("rest", "turn", "log"):
        return out + reuse_rows + [burst, shared, *auto]
    if cond.family == "light":
        return [*out, shared, *auto]
    if cond.family in ("distance", "tiling"):
        return out + res_rows
    rows = out + res_rows + reuse_rows + [burst, shared, *auto]  # smooth: every knob
    if has_f16:
        rows.append(variant("precision", "f16", precision="f16"))
    rows += [variant("network", m, material=m) for m in nets]
    rows.append(variant("mode", "screen (per pixel)", mode="screen", reuse=0))
    return rows


def conditions(c, fps: float, d: Path) -> list[ts.Condition]:

    d.mkdir(parents=True, exist_ok=True)
    out = []
    for v in c.speeds:
        out.append(ts.turn_condition(v, c.turn, fps, c.score.scored, d, c.near))
    for p in c.poses:
        out.append(ts.log_condition(Path(p), fps, c.score.scored, c.near))
    first = 8  # frames before scoring: every staggered phase of N <= 7 has run once
    window = list(range(first, first + c.score.scored))
    frames = window[-1] + 1
    out.append(ts.Condition("smooth orbit", "smooth", 0.0, frames, window))
    if c.light_speed:
        out.append(
            ts.Condition(
                f"light {c.light_speed:g} deg/s", "light", c.light_speed, frames, window,
                light_speed=c.light_speed,
            )
        )  # fmt: skip
    for dist in c.distances:
        out.append(ts.Condition(f"distance {dist:g} m", "distance", dist, frames, window, dist))
    for t in c.tilings:
        out.append(ts.Condition(f"tiling {t:g}", "tiling", t, frames, window, tiling=t))
    return out


def settings_for(c, v: dict, cond: ts.Condition, prof, ref=None):
    from vrneural.runtime.renderer import Settings

    return Settings(
        eyes=2,
        reuse=c.base_reuse if v["reuse"] is None else v["reuse"],
        texture_res=v["texture_res"] or c.base_res,
        eye_res=(c.score.crop, c.score.crop),
        frames=cond.frames,
        fps=prof.fps,
        fov_y=prof.fov_y,
        ipd=prof.ipd,
        n_lights=c.lights,
        mode=v["mode"],
        schedule=v["schedule"],
        precision=v["precision"],
        reference=ref,
        radiance=v["radiance"],
        reuse_budget=v["budget"],
        crop=(0, 0, *prof.eye_res),
    )


def match_budget(scene, c, cond, prof) -> tuple[float, float, float]:
    """The adaptive budget (degrees) whose candidate-block work over ``cond``'s frames matches
    the fixed base N's, by log-space bisection on the schedule alone (the smallest budget that
    does not exceed it: work falls in steps); returns (budget, its work, the fixed N's)."""
    from vrneural.runtime.renderer import Renderer

    r = Renderer(scene, settings_for(c, variant(), cond, prof))
    r.head = cond.head()
    target = scheduled_candidates(r, cond, None)
    lo, hi = 1e-3, 90.0
    for _ in range(30):  # more budget, less work
        mid = float(np.sqrt(lo * hi))
        if scheduled_candidates(r, cond, mid) > target:
            lo = mid
        else:
            hi = mid
        if hi / lo < 1.02:
            break
    return hi, scheduled_candidates(r, cond, hi), target


def scores(
    ref: dict, imgs: dict, n0: dict | None, ppd: float, frames: list, cache: dict, ref2=None
) -> dict:
    """The metrics of one variant over the scored ``frames`` (see the module docstring);
    ``cache`` keeps what depends on the reference alone (its display images, its own
    frame-to-frame change) across the variants of a condition; ``ref2``: the second
    reference (on its frames), against which FLIP is scored too, for the paired floor of
    differences (:func:`difference_floor`)."""
    flips, psnrs, ssims, reuse_err = [], [], [], []
    disp = {f: [metrics.display(e) for e in imgs[f]] for f in frames}
    if "disp" not in cache:
        cache["disp"] = {f: [metrics.display(e) for e in ref[f]] for f in frames}
    rdisp = cache["disp"]

    def per_eye(fn, a, b) -> float:  # the mean over both eyes
        return float(np.mean([fn(x, y) for x, y in zip(a, b, strict=True)]))

    def flip(a, b):  # both eyes in one FLIP evaluation
        return metrics.flip_hdr_eyes(a, b, ppd)

    def change(x, y):
        return float(np.abs(y - x).mean())

    for f in frames:
        flips.append(flip(ref[f], imgs[f]))
        psnrs.append(per_eye(metrics.psnr, rdisp[f], disp[f]))
        ssims.append(per_eye(metrics.ssim, rdisp[f], disp[f]))
        if n0 is not None:
            reuse_err.append(flip(n0[f], imgs[f]))
    pairs = list(itertools.pairwise(frames))
    if "change" not in cache:
        cache["change"] = [per_eye(change, rdisp[a], rdisp[b]) for a, b in pairs]
        cache["flip_consecutive"] = [flip(ref[a], ref[b]) for a, b in pairs]
    ch = [per_eye(change, disp[a], disp[b]) for a, b in pairs]
    tf = [flip(imgs[a], imgs[b]) for a, b in pairs]
    rch, rtf = cache["change"], cache["flip_consecutive"]
    out = {
        "flip": _dist(flips),
        "psnr": float(np.mean(psnrs)),
        "ssim": float(np.mean(ssims)),
        "change": float(np.mean(ch)) if ch else None,
        "change_ref": float(np.mean(rch)) if rch else None,
        "flip_consecutive": float(np.mean(tf)) if tf else None,
        "flip_consecutive_ref": float(np.mean(rtf)) if rtf else None,
    }
    out["reuse_error"] = _dist(reuse_err) if reuse_err else None
    if ref2:  # the same variant against both references, on the second one's frames
        out["paired"] = {
            "frames": sorted(ref2),
            "vs_ref": [flips[frames.index(f)] for f in sorted(ref2)],
            "vs_ref2": [flip(ref2[f], imgs[f]) for f in sorted(ref2)],
        }
    return out


def difference_floor(variants: list[dict]) -> float:
    """The noise floor of a FLIP *difference* between two variants: each variant's difference
    from the first (N = 0) is measured against both references on the same frames; the most
    the two measurements disagree, over the variants, is what sampling noise in the reference
    can do to a difference (a paired comparison: far below the floor of a single score, since
    both variants see the same reference noise)."""
    b = variants[0]["paired"]
    worst = 0.0
    for v in variants[1:]:
        p = v["paired"]
        d1 = np.mean(np.subtract(p["vs_ref"], b["vs_ref"]))
        d2 = np.mean(np.subtract(p["vs_ref2"], b["vs_ref2"]))
        worst = max(worst, abs(float(d1 - d2)))
    return worst


def _dist(x) -> dict:
    a = np.asarray(x, np.float64)
    return {"mean": float(a.mean()), "p95": float(np.percentile(a, 95)), "worst": float(a.max()),
            "per_frame": a.tolist()}  # fmt: skip


def work(stats) -> dict:
    """Frame time and shading work per displayed frame (frame 0, the first update, excluded)."""
    s = stats[1:] or stats
    w = [x.wall_ms for x in s]
    shade = [x.gpu_ms.get("texture", 0.0) + x.gpu_ms.get("screen", 0.0) for x in s]
    return {
        "frame_ms": rp.stats(w),
        # None where this adapter's timestamps do not cover the pass (FrameStats.untimed)
        "shading_ms_per_frame": None
        if set(s[0].untimed) & {"texture", "screen"}
        else float(np.mean(shade)),
        "blocks_per_frame": float(np.mean([x.blocks_shaded for x in s])),
        "mlp_per_frame": float(np.mean([x.mlp_coarse + x.mlp_fine for x in s])),
        "updated_frames": int(sum(x.blocks_shaded > 0 for x in s)),
    }


def check(c) -> None:
    """Every option, before any output exists."""
    c.score.check()
    check_range("--turn", c.turn, 1.0, 180.0)
    check_range("--near", c.near, 0.2, 100.0)
    check_range("--lights", c.lights, 1, LIGHTS_MAX)
    check_range("--light-speed", c.light_speed, 0.0, 3600.0)
    rp.check_texture_res(c.base_res, "--base-res")
    check_range("--base-reuse", c.base_reuse, 0, REUSE_MAX)
    rp.texture_list(c.texture_res)
    if not c.speeds:
        raise VrnError("--speeds is empty; give at least one turn speed (0 = at rest)")
    for p in c.poses:
        from vrneural.runtime.camera import PoseLogPath

        PoseLogPath(p)  # its one-line errors: missing, columns, time order, quaternion
    if c.packs is not None and not c.packs.strip():  # "" trains; typed, it was a slip
        raise VrnError("--packs is empty; name the folder of packs, or leave it out to train them")
    if c.packs:  # every pack what its name says, before any work or output
        load_packs(pack_paths(c.packs))
    else:
        c.budget.check(list(c.presets), "--presets")


def load_materials(c, root: Path) -> dict:
    """``{preset or pack folder: {pack name: NeuralMaterial}}`` (trained into ``root/packs``)."""
    if c.packs:
        return {Path(c.packs).name: load_packs(pack_paths(c.packs))}
    out = {}
    for i, preset in enumerate(c.presets):
        budget = c.budget.of(preset)
        d = root / "packs" / (preset if i else "")  # the first where earlier releases kept it
        only = None if i == 0 else ("student",)  # other presets: teacher and student
        out[preset] = load_packs(train_packs(d, budget, c.progress, only=only))
    return out


def run_tradeoff(cfg: TradeoffConfig) -> dict:
    from vrneural.gpu.device import adapter_summary

    c = cfg.resolved()
    check(c)
    with rp.prepare_out(cfg.out, cfg.force, "tradeoff") as root:
        t0 = time.perf_counter()
        doc = rp.header("tradeoff", c)
        tt = time.perf_counter()
        mats = load_materials(c, root)
        doc["packs"] = {"source": c.packs or "trained", "seconds": time.perf_counter() - tt,
                        "materials": {k: sorted(v) for k, v in mats.items()}}  # fmt: skip
        if c.packs:
            doc["packs"]["absent"] = [k for k in PACKS if k not in next(iter(mats.values()))]
        prof = get_profile("quest3")  # the eye image the crops are cut from
        full = prof.eye_res
        ppd = metrics.pixels_per_degree(full[1], prof.fov_y)
        doc["ppd"] = ppd
        conds = conditions(c, prof.fps, root / "poses")
        first = next(iter(mats))
        nets = [k for k in mats[first] if k not in REQUIRED]
        has_f16 = adapter_summary().features.get("shader-f16", False)
        # adaptive reuse at the fixed N's mean work, matched on the fastest turn
        fastest = max((x for x in conds if x.family in ("turn", "log")), key=lambda x: x.value,
                      default=None)  # fmt: skip
        budget = None
        if fastest is not None:
            scene = ts.scene_for(fastest, mats[first]["student"], n_lights=c.lights)
            budget, matched, target = match_budget(scene, c, fastest, prof)
            doc["adaptive"] = {"condition": fastest.name, "budget_deg": budget,
                               "base_candidates_per_frame": target,
                               "matched_candidates_per_frame": matched}  # fmt: skip
        jobs = []
        for cond in conds:
            presets = list(mats) if cond.family == "smooth" or cond is fastest else [first]
            for preset in presets:
                vs = variants_for(c, cond, nets if preset == first else [], has_f16, budget)
                jobs.append((cond, preset, vs))
        total = sum(len(vs) for _, _, vs in jobs)
        bar = tqdm(total=total, desc="bench tradeoff", unit="variant", disable=not c.progress)
        for cond, preset, vs in jobs:
            pm = mats[preset]
            teacher = pm["teacher"]
            rec = {"condition": cond.name, "family": cond.family, "value": cond.value,
                   "preset": preset, "scored_frames": cond.scored, "variants": []}  # fmt: skip
            rs = settings_for(c, variant(mode="reference"), cond, prof, teacher)
            rscene = ts.scene_for(cond, pm["student"], teacher, c.lights)
            bar.set_postfix_str(f"{cond.name} / {preset}: reference")
            n_floor = max(2, len(cond.scored) // 2)
            ref, ref2, nf, floor = ts.reference_pair(rscene, rs, cond, c.score, full, ppd, n_floor)
            rec["noise_floor"] = {"flip": floor, "frames": nf}
            cache: dict = {}
            n0 = None
            for v in vs:
                bar.set_postfix_str(f"{cond.name} / {preset}: {label(v)}")
                mat = pm.get(v["material"], pm["student"])
                scene = ts.scene_for(cond, mat, None, c.lights)
                imgs, st = render(scene, settings_for(c, v, cond, prof), cond, c.score.crop, full,
                                  set(cond.scored))  # fmt: skip
                if v["knob"] == "reuse" and v["value"] == 0:
                    n0 = imgs
                n0_ = n0 if v is not vs[0] else None
                r = {**v, **work(st), **scores(ref, imgs, n0_, ppd, cond.scored, cache, ref2)}
                rec["variants"].append(r)
                bar.update()
            rec["difference_floor"] = difference_floor(rec["variants"])
            doc["records"].append(rec)
        bar.close()
        return finish_report(root, doc, t0)
