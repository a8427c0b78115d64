"""`vrneural bench distance`: a neural material seen from afar or tiled densely, with and
without each level-of-detail feature.

One neural sphere (``--size`` m across) from 0.3 to 20 m away, and at 1 m with its material tiled
1 to 16 times, seen at the quest3 pixel density (crops of the full eye image that follow it, as
in `bench tradeoff`) under a slow head sway. Against the teacher per pixel supersampled (with its
noise floor: a second reference with other sample positions): FLIP per frame (mean and worst),
the temporal change (mean |frame - previous| of the displayed image against the reference's own:
above 1 is flicker the ground truth does not have), the shading work (texels shaded for the
object per frame, texture side, shading ms) and the frame time. Variants: all three features
off, each alone, and all three on (``--mips``: radiance mip chains; ``--screen-res``: texture
side from the screen; neural LOD: the same student with a pyramid of its neural textures' box
averages, and, as a variant of its own, a student trained with ``--lod-levels 4``); and 4x
MSAA (``run --msaa 4``) alone, with all three, and with all but the radiance mips: the
silhouette, where the sphere's pixels meet the background, is aliased by one sample per pixel
whatever the texture filters do; and footprint taps (``run --lod-taps``, ``--taps`` per axis):
the network's output averaged over each texel's footprint, the exact prefilter that the
pyramid's averaged latents approximate, alone and with resolution from the screen (whose
pixel footprint they then cover) and 4x MSAA. ``--variants`` renders some of them.

The material's texels are ``--texel-mm`` on the sphere at tiling 1 (1 mm: about a pixel at
1 m, so 10 m and tiling 8 minify it; each record has its texels per pixel), and each pack's
own error against the teacher (``network``: the pack per pixel with the reference's samples)
is measured beside the reference's noise floor: what no filter can remove.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
from tqdm import tqdm

from vrneural.bench import report as rp
from vrneural.bench import trade_scene as ts
from vrneural.bench import tradeoff as tr
from vrneural.bench.packs import load_packs, train_packs
from vrneural.bench.train_configs import DistanceConfig
from vrneural.errors import VrnError, check_int, check_range
from vrneural.runtime.config import REUSE_MAX
from vrneural.runtime.profiles import get_profile
from vrneural.runtime.settings import LOD_TAPS_MAX
from vrneural.scoring import metrics

#: name -> (mips, screen_res, the pack: ``student``, or one with prefiltered neural textures:
#: ``student_pyr`` the same student with a pyramid of its textures' box averages, the filter
#: alone; ``student_lod`` a student trained with its pyramid, ``distill --lod-levels 4``;
#: samples per pixel of the eyes: 4x MSAA, for the silhouette, which no texture filter reaches;
#: footprint taps, ``--taps`` per axis at most (``run --lod-taps``): the network's output
#: averaged over the footprint, the exact prefilter the pyramid approximates)
VARIANTS = {
    "all off": (False, False, "student", 1, False),
    "mips": (True, False, "student", 1, False),
    "screen res": (False, True, "student", 1, False),
    "neural LOD": (False, False, "student_pyr", 1, False),
    "neural LOD, trained": (False, False, "student_lod", 1, False),
    "all on": (True, True, "student_pyr", 1, False),
    # without the radiance mips: with screen res a radiance texel is already about a pixel,
    # and the mips' trilinear lookup blurs the material further; the neural textures are then
    # prefiltered to the pixel's footprint (Settings.lod_footprint "auto": docs/lod.md)
    "screen res + neural LOD": (False, True, "student_pyr", 1, False),
    "4x MSAA": (False, False, "student", 4, False),
    "all on, 4x MSAA": (True, True, "student_pyr", 4, False),
    "screen res + neural LOD, 4x MSAA": (False, True, "student_pyr", 4, False),
    "taps": (False, False, "student", 1, True),
    "screen res + taps, 4x MSAA": (False, True, "student", 4, True),
    "screen res + neural LOD + taps, 4x MSAA": (False, True, "student_pyr", 4, True),
}
PACKS = ("student", "student_pyr", "student_lod")


def variant_key(name: str) -> str:
    """A variant's key on the command line (``--variants``): ``"all on, 4x MSAA"`` ->
    ``"all-on+4x-msaa"``."""
    return "-".join(name.lower().replace(" + ", "+").replace(", ", "+").split())


def selected(c: DistanceConfig) -> list[str]:
    """The names of the variants ``--variants`` keeps (all without it), in the table's order;
    a one-line error for a key that names none."""
    keys = {variant_key(n): n for n in VARIANTS}
    for k in c.variants:
        if k not in keys:
            raise VrnError(f"--variants: {k!r} is not a variant; choose from {', '.join(keys)}")
    want = set(c.variants) or set(keys)
    return [n for k, n in keys.items() if k in want]


def base_tiling(c: DistanceConfig) -> float:
    """BTF tiles per material-UV unit at tiling 1 for material texels of ``--texel-mm``: the
    built-in sphere's UV unit is one radian, ``size / 2`` metres along a great circle."""
    return (c.size / 2) / (c.budget.btf_res * c.texel_mm * 1e-3)


def texels_per_pixel(c: DistanceConfig, distance: float, uv_tiling: float, ppd: float) -> float:
    """Material texels under one pixel's width where the sphere faces the eye, at ``uv_tiling``
    BTF tiles per material-UV unit (above 1: the material is minified, what the filtering
    features are for)."""
    pixel = (distance - c.size / 2) * np.radians(1.0 / ppd)
    return float(pixel / ((c.size / 2) / (uv_tiling * c.budget.btf_res)))


def quest3_view():
    """The quest3 profile, its full eye resolution and its pixels per degree."""
    prof = get_profile("quest3")
    return prof, prof.eye_res, metrics.pixels_per_degree(prof.eye_res[1], prof.fov_y)


def supersampled(c: DistanceConfig, cond, prof, full, mat, frames) -> dict:
    """``mat``'s level 0 per pixel on ``cond``'s ``frames``, supersampled with the reference's
    samples (seed 0): frame -> ``[eyes, H, W, 3]``."""
    lvl0 = dataclasses.replace(mat, levels={})
    s = settings(c, cond, prof, False, False, "reference", lvl0)
    return ts.reference(ts.scene_for(cond, lvl0, lvl0), s, cond, c.score.crop, full, frames,
                        c.score.spp, 0)  # fmt: skip


def conditions(c: DistanceConfig) -> list[ts.Condition]:
    first = 8
    window = list(range(first, first + c.score.scored))
    base = base_tiling(c)
    out = []
    for d in c.distances:
        out.append(ts.Condition(f"{d:g} m", "distance", d, window[-1] + 1, window, d,
                                tiling=base, size=c.size))  # fmt: skip
    for t in c.tilings:
        out.append(ts.Condition(f"tiling {t:g}", "tiling", t, window[-1] + 1, window, 1.0,
                                tiling=base * t, size=c.size))  # fmt: skip
    return out


def check(c: DistanceConfig) -> None:
    check_range("--size", c.size, 0.001, 10.0)
    check_range("--texel-mm", c.texel_mm, 0.001, 1000.0)
    rp.check_texture_res(c.texture_res, "--texture-res")
    check_range("--reuse", c.reuse, 0, REUSE_MAX)
    check_int("--taps", c.taps, 2, LOD_TAPS_MAX)
    c.score.check()
    if not (c.distances or c.tilings):
        raise VrnError("--distances and --tilings are both empty; give at least one condition")
    selected(c)
    c.budget.check([c.preset])


def settings(c: DistanceConfig, cond, prof, mips: bool, screen: bool, mode="texture", ref=None,
             msaa: int = 1, taps: int = 1):  # fmt: skip
    from vrneural.runtime.renderer import Settings

    return Settings(
        eyes=2, reuse=c.reuse, texture_res=c.texture_res, eye_res=(c.score.crop, c.score.crop),
        frames=cond.frames, fps=prof.fps, fov_y=prof.fov_y, ipd=prof.ipd, n_lights=2,
        mode=mode, precision="f32", reference=ref, crop=(0, 0, *prof.eye_res), mips=mips,
        screen_res=screen, msaa=msaa, lod_taps=taps,
    )  # fmt: skip


def run_distance(cfg: DistanceConfig) -> dict:
    c = cfg.resolved()
    check(c)
    with rp.prepare_out(cfg.out, cfg.force, "distance") as root:
        t0 = time.perf_counter()
        doc = rp.header("distance", c)
        budget = c.budget.of(c.preset)
        tt = time.perf_counter()
        paths = train_packs(root / "packs", budget, c.progress, only=PACKS)
        mats = load_packs(paths)
        doc["packs"] = {"budget": budget, "seconds": time.perf_counter() - tt}
        prof, full, ppd = quest3_view()
        doc["ppd"] = ppd
        conds = conditions(c)
        names = selected(c)
        bar = tqdm(total=len(conds) * (len(names) + 3), desc="bench distance", unit="render",
                   disable=not c.progress)  # fmt: skip
        for cond in conds:
            teacher = mats["teacher"]
            rs = settings(c, cond, prof, False, False, "reference", teacher)
            rscene = ts.scene_for(cond, mats["student"], teacher)
            bar.set_postfix_str(f"{cond.name}: reference")
            ref, _, _, floor = ts.reference_pair(rscene, rs, cond, c.score, full, ppd, 2)
            bar.update()
            rec = {"condition": cond.name, "family": cond.family, "value": cond.value,
                   "noise_floor": floor, "uv_tiling": cond.tiling,
                   "texels_per_pixel": texels_per_pixel(c, cond.distance, cond.tiling, ppd),
                   "network_flip": {}, "variants": []}  # fmt: skip
            cache: dict = {}
            own = {}  # pack -> its level 0 per pixel, supersampled: the filtering error alone
            for key in ("student", "student_lod"):  # (student_pyr's level 0 is student's)
                bar.set_postfix_str(f"{cond.name}: {key} supersampled")
                own[key] = supersampled(c, cond, prof, full, mats[key], cond.scored)
                # the network's own error: no filter removes it (same samples as the reference)
                rec["network_flip"][key] = float(np.mean(
                    [metrics.flip_hdr_eyes(ref[f], own[key][f], ppd) for f in cond.scored]
                ))  # fmt: skip
            own["student_pyr"] = own["student"]
            rec["network_flip"]["student_pyr"] = rec["network_flip"]["student"]
            for name in names:
                mips, screen, key, msaa, tapped = VARIANTS[name]
                taps = c.taps if tapped else 1
                bar.set_postfix_str(f"{cond.name}: {name}")
                mat = mats[key]
                s = settings(c, cond, prof, mips, screen, msaa=msaa, taps=taps)
                imgs, st = ts.render(
                    ts.scene_for(cond, mat), s, cond, c.score.crop, full, set(cond.scored)
                )
                sc = tr.scores(ref, imgs, None, ppd, cond.scored, cache)
                own_f = [metrics.flip_hdr_eyes(own[key][f], imgs[f], ppd) for f in cond.scored]
                w = st[1:]
                rec["variants"].append({
                    "variant": name, "mips": mips, "screen_res": screen, "pack": key, "msaa": msaa,
                    "neural_lod": key != "student", "lod_taps": taps,
                    "flip_own": float(np.mean(own_f)), "flip_network": rec["network_flip"][key],
                    **{k: sc[k] for k in ("flip", "psnr", "ssim", "change", "change_ref")},
                    "flicker": sc["change"] / max(sc["change_ref"], 1e-12),
                    "texels_shaded": float(np.mean([4 * x.object_blocks[0] for x in w])),
                    "texture_side": int(np.median([x.object_res[0] for x in w])),
                    "lod_scale": float(np.median([x.object_lod_scale[0] for x in w])),
                    **tr.work(st),
                })  # fmt: skip
                bar.update()
            bar.update(2)  # the two own references
            doc["records"].append(rec)
        bar.close()
        return finish(root, doc, t0)


def finish(root, doc: dict, t0: float) -> dict:
    md = [
        "# Distance: level of detail at distance and under tiling",
        "",
        rp.adapter_line(doc),
        f"A {doc['config']['size']:g} m neural sphere, its material's texels "
        f"{doc['config']['texel_mm']:g} mm at tiling 1, crops of the quest3 eye image at "
        f"{doc['ppd']:.1f} ppd following it, slow head sway; reference: the teacher per pixel "
        f"with {doc['config']['spp']} stratified samples. flicker: the mean frame-to-frame "
        "change of the displayed image over the reference's own (1 = as steady as the truth). "
        "FLIP own: against the variant's own pack (level 0) per pixel with the same samples, "
        "the filtering error without the network's error against the teacher. network: the "
        "variant's pack per pixel with the reference's samples against the reference, the "
        "network's own error, which no filter removes (FLIP's floor for that variant). "
        "texels/px: material texels under a pixel's width where the sphere faces the eye "
        "(above 1: minified). texels: texels shaded for the sphere per frame; side: its "
        "radiance texture's median side; lod x: the neural textures' footprint in its atlas "
        "texels (above 1: a pixel's, with screen res and no mips). taps: the network's output "
        f"averaged over each texel's footprint at up to {doc['config']['taps']} x "
        f"{doc['config']['taps']} points (run --lod-taps {doc['config']['taps']})."
        + (" **Quick run: reduced settings.**" if doc["config"]["quick"] else ""),
        "",
    ]
    rows = []
    for rec in doc["records"]:
        for v in rec["variants"]:
            rows.append([rec["condition"], f"{rec['texels_per_pixel']:.2g}", v["variant"],
                         f"{v['flip']['mean']:.4f} ({v['flip']['worst']:.4f})",
                         f"{v['flip_own']:.4f}", f"{rec['noise_floor']:.4f}",
                         f"{v['flip_network']:.4f}", v["flicker"], v["texels_shaded"],
                         v["texture_side"], f"{v['lod_scale']:.2f}",
                         v["frame_ms"]["mean"]])  # fmt: skip
    md += rp.table(["condition", "texels/px", "variant", "FLIP (worst)", "FLIP own", "floor",
                    "network", "flicker", "texels", "side", "lod x", "frame ms"], rows)  # fmt: skip
    return rp.finish(root, doc, md, t0, [("distance.png", "distance", png)])


def png(doc: dict, path) -> None:
    """FLIP against the teacher (and each pack's own error, which no filter removes) and
    flicker, over distance and over tiling."""
    fig, axes = rp.figure(17, 4.0, 4)
    for k, fam in enumerate(("distance", "tiling")):
        recs = sorted((r for r in doc["records"] if r["family"] == fam), key=lambda r: r["value"])
        ax, axf = axes[k], axes[2 + k]
        xlabel = "distance, m" if fam == "distance" else "tiling (at 1 m)"
        if not recs:
            ax.set_visible(False)
            axf.set_visible(False)
            continue
        x = [r["value"] for r in recs]
        for i, v in enumerate(recs[0]["variants"]):
            (line,) = ax.plot(x, [r["variants"][i]["flip"]["mean"] for r in recs], "o-", lw=1,
                              label=v["variant"])  # fmt: skip
            ax.plot(x, [r["variants"][i]["flip_own"] for r in recs], "s:", lw=1, ms=3,
                    color=line.get_color())  # fmt: skip
            axf.plot(x, [r["variants"][i]["flicker"] for r in recs], "o-", lw=1,
                     label=v["variant"])  # fmt: skip
        for key, mk in (("student", "x"), ("student_lod", "+")):
            ax.plot(x, [r["network_flip"][key] for r in recs], mk + "-.", color="0.45", lw=0.8,
                    label=f"network alone ({key})")  # fmt: skip
        ax.plot(x, [r["noise_floor"] for r in recs], "k--", lw=0.8, label="noise floor")
        axf.axhline(1.2, color="k", ls="--", lw=0.8, label="1.2x the reference")
        for a, ylabel in ((ax, "FLIP vs supersampled teacher (dotted: vs own pack)"),
                          (axf, "flicker (change / reference's)")):  # fmt: skip
            a.set_xscale("log")
            a.set_xlabel(xlabel)
            a.set_ylabel(ylabel)
            a.grid(alpha=0.3)
            a.legend(fontsize=6)
    fig.suptitle(f"bench distance on {doc['adapter']['name']}", fontsize=9)
    rp.save_png(fig, path)
