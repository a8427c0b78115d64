"""The report of `vrneural bench tradeoff`: tables per condition, the knobs ranked by what they
cost and buy, and the plots (``speed.png``, ``pareto.png``). Every FLIP difference is read
against the condition's noise floor: FLIP between two references with different sample
positions."""

from __future__ import annotations

from vrneural.bench import report as rp

LABELS = {
    "student": "student (distilled)",
    "student_nodistill": "student w/o distillation",
    "single8": "single-level 8-wide",
    "neumip": "NeuMIP-sized 4x25",
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


def ranking(doc: dict) -> list[dict]:
    """Per condition and preset, every variant against the base: FLIP change, frame ms and
    blocks saved, FLIP change per ms saved, and whether the change is within the noise floor."""
    out = []
    for rec in doc["records"]:
        b = next(v for v in rec["variants"] if v["knob"] == "base")
        floor = rec.get("difference_floor", rec["noise_floor"]["flip"])
        for v in rec["variants"]:
            if v is b:
                continue
            dflip = v["flip"]["mean"] - b["flip"]["mean"]
            saved = b["frame_ms"]["mean"] - v["frame_ms"]["mean"]
            out.append({
                "condition": rec["condition"], "preset": rec["preset"], "setting": label(v),
                "dflip": dflip, "ms_saved": saved,
                "blocks_saved": b["blocks_per_frame"] - v["blocks_per_frame"],
                "dflip_per_ms": dflip / saved if abs(saved) > 1e-9 else None,
                "below_floor": abs(dflip) < floor,
            })  # fmt: skip
    return out


def _f(v, nd=4):
    return "-" if v is None else f"{v:.{nd}g}"


def markdown(doc: dict) -> list[str]:
    c = doc["config"]
    adp = doc.get("adaptive")
    md = [
        "# Trade-off: each knob where it bites",
        "",
        rp.adapter_line(doc),
        f"Crops of {c['crop']} x {c['crop']} pixels of each quest3 eye image (2064 x 2208, "
        f"{doc['ppd']:.1f} pixels per degree) following a neural sphere; reference: the teacher "
        f"per pixel, f32, {c['spp']} stratified samples per pixel; {c['scored']} consecutive "
        f"frames scored per condition, both eyes. Base: texture {c['base_res']}^2, "
        f"N = {c['base_reuse']} staggered, per-eye radiance, f32, distilled student. FLIP: HDR at "
        f"{doc['ppd']:.1f} ppd (mean over frames; worst frame in brackets). **floor**: FLIP "
        "between two references with different sample positions (the noise of one score). "
        "**floor of a difference**: the most any setting's FLIP difference from N = 0 changes "
        "when it is measured against the second reference instead of the first (both settings "
        "see the same reference noise, so a difference is known far better than one score); a "
        "difference below it is noise. **reuse error**: FLIP against the N = 0 render of the "
        "same frame (deterministic: the staleness itself)."
        + (" **Quick run: reduced settings.**" if c["quick"] else ""),
        "",
    ]
    packs = doc["packs"]
    if packs.get("absent"):
        md += [f"Packs from {packs['source']}; no {', '.join(packs['absent'])} pack there, so "
               "no row for it.", ""]  # fmt: skip
    if adp:
        md += [
            f"Adaptive reuse (`--reuse auto`): budget {adp['budget_deg']:.3g} deg, matched on "
            f"'{adp['condition']}' to the base N's mean work "
            f"({adp['base_candidates_per_frame']:.0f} candidate blocks per frame; matched "
            f"{adp['matched_candidates_per_frame']:.0f}).",
            "",
        ]
    for rec in doc["records"]:
        floor = rec["noise_floor"]["flip"]
        dfloor = rec["difference_floor"]
        md += [f"## {rec['condition']} ({rec['preset']})", "",
               f"floor {floor:.4f} (FLIP, reference vs reference); floor of a difference "
               f"between settings {dfloor:.5f} (paired, see above)", ""]  # fmt: skip
        rows = []
        for v in rec["variants"]:
            ch = v["change"]
            rows.append([
                label(v), v["frame_ms"]["mean"], v["blocks_per_frame"],
                f"{v['flip']['mean']:.4f} ({v['flip']['worst']:.4f})", v["psnr"], v["ssim"],
                "-" if ch is None else f"{ch:.4f} / {v['change_ref']:.4f}",
                "-" if v["reuse_error"] is None else
                f"{v['reuse_error']['mean']:.4f} ({v['reuse_error']['worst']:.4f})",
            ])  # fmt: skip
        md += rp.table(
            ["setting", "frame ms", "blocks/frame", "FLIP (worst)", "PSNR", "SSIM",
             "change / ref's", "reuse error (worst)"],
            rows,
        )  # fmt: skip
        md.append("")
    md += ["## Ranking: what each knob buys (FLIP change) for the frame time it saves", "",
           "Against each condition's base; negative FLIP change is better; *: within the "
           "condition's floor of a difference (not measurable).", ""]  # fmt: skip
    rank = ranking(doc)
    rows = [[r["condition"], r["preset"], r["setting"] + (" *" if r["below_floor"] else ""),
             f"{r['dflip']:+.4f}", f"{r['ms_saved']:+.1f}", f"{r['blocks_saved']:+.0f}",
             "-" if r["dflip_per_ms"] is None else f"{r['dflip_per_ms']:+.2e}"]
            for r in sorted(rank, key=lambda r: (r["condition"], r["dflip"]))]  # fmt: skip
    md += rp.table(["condition", "preset", "setting", "dFLIP", "ms saved", "blocks saved",
                    "dFLIP per ms saved"], rows)  # fmt: skip
    return md


def speed_png(doc: dict, path) -> None:
    """Over head speed, per setting: its FLIP difference from N = 0 (both against the
    reference; the band is the condition's floor of a difference) and its reuse error."""
    recs = [r for r in doc["records"] if r["family"] in ("rest", "turn")]
    first = recs[0]["preset"] if recs else None
    recs = sorted((r for r in recs if r["preset"] == first), key=lambda r: r["value"])
    fig, axes = rp.figure(12, 4.2, 2)
    if recs:
        x = [r["value"] for r in recs]
        for i, v in enumerate(recs[0]["variants"]):
            col = f"C{i % 10}"
            d = [r["variants"][i]["flip"]["mean"] - r["variants"][0]["flip"]["mean"] for r in recs]
            axes[0].plot(x, d, "o-", color=col, label=label(v), lw=1)
            e = [r["variants"][i]["reuse_error"] for r in recs]
            if all(v is not None for v in e):
                axes[1].plot(x, [v["mean"] for v in e], "o-", color=col, label=label(v), lw=1)
        band = [r["difference_floor"] for r in recs]
        axes[0].fill_between(
            x, [-b for b in band], band, color="0.8", label="floor of a difference"
        )
    axes[0].set_ylabel("FLIP vs supersampled teacher, minus N = 0's")
    axes[1].set_ylabel("reuse error: FLIP vs the N = 0 render (mean)")
    for ax in axes:
        ax.set_xlabel("head turn speed, deg/s")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6)
    fig.suptitle(f"bench tradeoff on {doc['adapter']['name']}: head speed ({first})", fontsize=9)
    rp.save_png(fig, path)


def pareto_png(doc: dict, path) -> None:
    rec = next((r for r in doc["records"] if r["family"] == "smooth"), doc["records"][0])
    vs = rec["variants"]
    fig, axes = rp.figure(6.4, 4.2, 1)
    ax = axes[0]
    pts = [(v["frame_ms"]["mean"], v["flip"]["mean"]) for v in vs]
    front = sorted(pareto(pts, True), key=lambda i: pts[i][0])
    for v, (x, y) in zip(vs, pts, strict=True):
        ax.scatter(x, y, s=18, color="C3" if v["knob"] == "base" else "C0")
        ax.annotate(label(v), (x, y), fontsize=6, xytext=(3, 2), textcoords="offset points")
    ax.plot([pts[i][0] for i in front], [pts[i][1] for i in front], "k--", lw=0.8,
            label="Pareto front")  # fmt: skip
    ax.axhspan(min(p[1] for p in pts), min(p[1] for p in pts) + rec["noise_floor"]["flip"],
               color="0.85", label="noise floor above the best")  # fmt: skip
    ax.set_xscale("log")
    rp.plain_log_ticks(ax.xaxis)
    ax.set_xlabel("frame ms (mean, wall)")
    ax.set_ylabel("FLIP (lower is better)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.suptitle(f"{rec['condition']} ({rec['preset']}) on {doc['adapter']['name']}", fontsize=9)
    rp.save_png(fig, path)


def finish_report(root, doc: dict, t0: float) -> dict:
    doc["ranking"] = ranking(doc)
    plots = [("speed.png", "speed", speed_png), ("pareto.png", "pareto", pareto_png)]
    return rp.finish(root, doc, markdown(doc), t0, plots)
