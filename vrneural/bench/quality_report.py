"""Markdown table and PNG figures of `vrneural bench quality` (from its results dict)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vrneural.bench.quality_parallax import bins_png, markdown_bins
from vrneural.bench.report import pyplot, save_png, table
from vrneural.errors import count
from vrneural.outputs import atomic_path

ORDER = ("lafortune", "neumip", "single8", "student_nodistill", "student", "teacher")


# target -> (baseline, factor): met when the student's mean whole-BTF L1 times factor is at
# most the baseline's (strictly below for factor 1)
TARGETS = {
    "within 10% of NeuMIP": ("neumip", 1 / 1.10),
    "below single-level 8-wide": ("single8", 1.0),
    "below no-distillation": ("student_nodistill", 1.0),
    "1.5x below Lafortune": ("lafortune", 1.5),
}


def target_names(width: int = 8) -> list[str]:
    """The targets' column headers: :data:`TARGETS`' keys (which results.json keeps), the
    single-level net at the bench's ``--width``."""
    return [t.replace("8-wide", f"{width}-wide") for t in TARGETS]


def _seeds(r: dict) -> list[float]:
    return r.get("whole_l1_seeds") or [r["whole_l1"]]


def targets(m: dict) -> dict[str, bool]:
    """The issue's targets for one material's method records (on the seed means); a target
    whose baseline has no record is left out (scripts/research/pt_students.py scores four)."""
    s = m["student"]["whole_l1"]
    out = {}
    for name, (base, f) in TARGETS.items():
        if base not in m:
            continue
        b = m[base]["whole_l1"]
        out[name] = s * f < b if f == 1.0 else s * f <= b
    return out


def gaps(m: dict) -> dict[str, tuple[float, float]]:
    """Per target, the student's mean whole-BTF L1 against the baseline's: ``(relative,
    absolute)`` difference. The absolute one is what an error floor in the data cannot hide
    (docs/quality-research.md, "How an error floor dilutes the ratio targets")."""
    s = m["student"]["whole_l1"]
    out = {}
    for name, (base, _) in TARGETS.items():
        b = m[base]["whole_l1"]
        out[name] = (s / b - 1 if b > 0 else float("inf"), s - b)
    return out


def decided(m: dict) -> dict[str, bool]:
    """Whether each target's outcome holds for every seed pair: False where the student's
    seed range (scaled by the target's factor) overlaps the baseline's."""
    s = _seeds(m["student"])
    out = {}
    for name, (base, f) in TARGETS.items():
        b = _seeds(m[base])
        out[name] = max(s) * f < min(b) or min(s) * f > max(b)
    return out


def picked(m: dict) -> dict[str, dict]:
    """Each method's seed with the lowest held-out test L1 (what a user who trains K seeds and
    keeps one can do without the whole BTF), as ``{"whole_l1": ...}`` records."""
    out = {}
    for name, r in m.items():
        whole, test = _seeds(r), r.get("test_l1_seeds") or [r["test_l1"]]
        out[name] = {
            "whole_l1": whole[int(np.argmin(test))] if len(test) == len(whole) else r["whole_l1"]
        }
    return out


def seed_pairs(m: dict) -> dict[str, tuple[int, int]]:
    """``(wins, pairs)``: in how many seeds the student is below each 8-wide baseline trained
    with the same seed (a baseline without a record is left out)."""
    s = _seeds(m["student"])
    out = {}
    for base in ("single8", "student_nodistill"):
        if base not in m:
            continue
        b = _seeds(m[base])
        n = min(len(s), len(b))
        out[base] = (sum(x < y for x, y in zip(s[:n], b[:n], strict=True)), n)
    return out


def _several_seeds(res: dict, presets: list[str], lab: dict, width: int) -> list[str]:
    """The report's section for ``--repeats`` > 1: seed pairs and test-L1-picked seeds."""
    names = [n for n in ORDER if n != "teacher" and n in res[presets[0]]["methods"]]
    lines = [
        "## Several seeds: seed by seed, and one seed picked by held-out test L1",
        "",
        "Pairs: in how many seeds the student is below the baseline trained with the same seed. "
        "Picked: every method keeps the seed with the lowest held-out test L1 (whole-BTF L1 of "
        "that seed), and the targets are judged on those.",
        "",
    ]
    rows = []
    for p in presets:
        m = res[p]["methods"]
        pairs, pick = seed_pairs(m), picked(m)
        rows.append([p, *(f"{w} of {n}" for w, n in pairs.values()),
                     *(f"{pick[n]['whole_l1']:.5f}" for n in names),
                     *("yes" if v else "**no**" for v in targets(pick).values())])  # fmt: skip
    head = ["material", "student < single-level (pairs)", "student < no-distillation (pairs)",
            *(f"{lab[n]} (picked)" for n in names), *target_names(width)]  # fmt: skip
    return [*lines, *table(head, rows), ""]


def _cell(r: dict, best: bool) -> str:
    v = f"**{r['whole_l1']:.5f}**" if best else f"{r['whole_l1']:.5f}"
    seeds = _seeds(r)
    if len(seeds) > 1:
        v += f" ({min(seeds):.5f}-{max(seeds):.5f})"
    return v


def _psnr_ssim(res: dict, presets: list[str], lab: dict) -> list[str]:
    """The PSNR / SSIM table (absent from reports made before it existed)."""
    first = res[presets[0]]["methods"]
    if not any("ssim" in r for r in first.values()):
        return []
    lines = [
        "## PSNR and SSIM of the BTF slices as displayed",
        "",
        "Every slice at its own exposure (the BTF slice's 99th percentile at 1), then the "
        "runtime's tone map x / (1 + x) and sRGB; the mean over slices, and over seeds. The "
        "same definitions as `vrneural eval`. PSNR in dB / SSIM; Lafortune is not scored.",
        "",
    ]
    rows = [
        [lab[n], *(f"{r[n]['psnr_db']:.2f} / {r[n]['ssim']:.3f}"
                   for r in (res[p]["methods"] for p in presets))]
        for n in ORDER if n in first and "ssim" in first[n]
    ]  # fmt: skip
    return [*lines, *table(["method", *presets], rows), ""]


def markdown(doc: dict) -> str:
    res = doc["results"]
    cfg = doc["config"]
    presets = list(res)
    lab = doc["labels"]
    width = int(cfg.get("width", 8))  # older results.json: the paper's 8
    k = int(cfg.get("repeats", 1))
    seeds = (
        f"seed {cfg['seed']}"
        if k == 1
        else f"seeds {cfg['seed']}-{cfg['seed'] + k - 1} for every network but the teacher "
        f"(mean, and in brackets the range over seeds)"
    )
    lines = [
        "# Quality: whole-BTF L1 per material and method (paper Table 1 analog)",
        "",
        *_partial(doc),
        f"Budget: {_data(doc)}, teacher {cfg['teacher_epochs']} epochs, every other network "
        f"{cfg['epochs']} epochs"
        + (f" with weight averaging (--ema {cfg['ema']:g})" if cfg.get("ema") else "")
        + (
            f" {'and' if cfg.get('ema') else 'with'} lr patience {cfg['lr_patience']} epochs "
            "(--lr-patience)"
            if cfg.get("lr_patience", 2) != 2
            else ""
        )
        + (
            f"; the single-level net and both students {width} wide (--width)"
            if width != 8 and not cfg.get("wide_start")
            else ""
        )
        + (
            f"; the {width}-wide networks (single-level, both students) {cfg['wide_start']} "
            f"wide for the first {count(cfg['epochs'] // 2, 'epoch')}, then pruned to {width} "
            "wide (--wide-start)"
            if cfg.get("wide_start")
            else ""
        )
        + f", Lafortune {cfg['lafortune_iters']} LM iterations, "
        f"{seeds}; {_trained_on(doc)}. This invocation took {_duration(doc['total_seconds'])}; "
        "networks it reused from earlier runs list their own train s below (per seed: "
        "the mean over the seeds).",
        "",
    ]
    best = {p: min(r["whole_l1"] for m, r in res[p]["methods"].items() if m != "teacher")
            for p in presets}  # fmt: skip
    rows = []
    for name in (n for n in ORDER if n in res[presets[0]]["methods"]):
        r0 = res[presets[0]]["methods"][name]
        vals = [_cell(r, r["whole_l1"] == best[p])
                for p, r in ((p, res[p]["methods"][name]) for p in presets)]  # fmt: skip
        macs = "-" if r0["macs_per_texel"] is None else f"{r0['macs_per_texel']:g}"
        rows.append([lab[name], *vals, f"{r0['texture_bytes']} + {r0['weight_bytes']}", macs])
    lines += table(["method", *presets, "storage (bytes)", "MLP MACs / texel"], rows)
    lines += [
        "",
        "Storage = texture + network bytes of the runtime pack (textures float16, weights "
        "float32; Lafortune: 55 float32 per texel). Bold: best non-teacher method.",
        "",
        "## Targets (student vs baselines, whole-BTF L1)",
        "",
        *(
            [
                "On the means over seeds. *(seeds overlap)*: the seed ranges overlap, so "
                "another seed could flip the outcome.",
                "",
            ]
            if k > 1
            else []
        ),
        "In brackets: the student's whole-BTF L1 against the baseline's, relative and "
        "absolute. A ratio of totals shrinks when the data carry error no model removes "
        "(measured BTFs); the absolute difference does not.",
        "",
    ]
    rows = []
    for p in presets:
        m = res[p]["methods"]
        sure, gap = decided(m), gaps(m)
        rows.append([p, *(("yes" if v else "**no**") + f" ({gap[n][0]:+.1%}, {gap[n][1]:+.5f})"
                          + ("" if sure[n] else " *(seeds overlap)*")
                          for n, v in targets(m).items())])  # fmt: skip
    lines += [*table(["material", *target_names(width)], rows), ""]
    if k > 1:
        lines += _several_seeds(res, presets, lab, width)
    lines += _psnr_ssim(res, presets, lab)
    lines += [
        "## Held-out test L1 and training time (s)",
        "",
        "train s: the run's training seconds (epochs + per-epoch test; wall clock, so it counts "
        "any time the job was paused or shared its core); s/epoch: the median epoch, which "
        "is robust to such interruptions.",
        "",
    ]
    rows = [
        [p, name, f"{r['test_l1']:.5f}", f"{r['whole_l1']:.5f}", f"{r['train_seconds']:.1f}",
         "-" if r.get("epoch_seconds_median") is None else f"{r['epoch_seconds_median']:.1f}"]
        for p in presets for name, r in ((n, res[p]["methods"].get(n)) for n in ORDER) if r
    ]  # fmt: skip
    lines += table(["material", "method", "test L1", "whole L1", "train s", "s/epoch"], rows)
    lines += [
        "",
        "Figures: `curves.png` (test L1 per epoch; thick: the first seed, thin: the others), "
        "`slices.png` (BTF slices vs ground truth, first seed), `view_bins.png` (L1 by view "
        "angle).",
        "",
    ]
    lines += markdown_bins(doc)
    return "\n".join(lines)


def curves_png(doc: dict, path: Path) -> None:
    from matplotlib.ticker import MaxNLocator

    plt = pyplot()

    res = doc["results"]
    n_rows = -(-len(ORDER) // (2 * len(res)))  # legend rows (at most one entry per method)
    fig, axes = plt.subplots(
        1, len(res), figsize=(4.2 * len(res), 3.4 + 0.15 * n_rows), squeeze=False
    )
    for ax, (p, r) in zip(axes[0], res.items(), strict=True):
        for name in ORDER:
            m = r["methods"].get(name)
            if not m:
                continue
            if m["curve"]:
                (line,) = ax.plot(
                    range(1, len(m["curve"]) + 1),
                    m["curve"],
                    label=doc["labels"][name],
                    lw=2.2 if name == "student" else 1.2,
                    ls="--" if name == "student_nodistill" else "-",  # seen under the student
                )
                for c in m.get("curves", [])[1:]:  # the other seeds, thin
                    ax.plot(range(1, len(c) + 1), c, c=line.get_color(), lw=0.7, alpha=0.45)
            else:
                ax.axhline(m["test_l1"], ls="--", c="gray", label=doc["labels"][name])
        wide = doc["config"].get("wide_start")
        if wide:  # the 8-wide networks were cut from their wide starts here
            cut = doc["config"]["epochs"] // 2 + 0.5
            ax.axvline(cut, c="k", ls=":", lw=0.8)
            ax.annotate(
                f"{wide} -> {doc['config'].get('width', 8)} wide",
                (cut, 1),
                xycoords=("data", "axes fraction"),
                xytext=(3, -10),
                textcoords="offset points",
                fontsize=7,
            )
        ax.set_yscale("log")
        ax.set_title(p)
        ax.set_xlabel("epoch")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))  # no epoch 1.5 on short runs
        ax.set_ylabel("test L1")
        ax.grid(alpha=0.3)
    handles, labels = axes[0][0].get_legend_handles_labels()
    ncol = min(len(labels), 2 * len(res))  # one panel: the legend in rows, not a wide strip
    rows = -(-len(labels) // max(ncol, 1))
    fig.legend(handles, labels, loc="lower center", ncol=ncol, fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0.04 + 0.04 * rows, 1, 1))  # below the panels, never over a curve
    save_png(fig, path, dpi=110)


def slices_png(doc: dict, slices: dict, path: Path) -> None:
    plt = pyplot()

    cols = ["ground truth", *reversed(ORDER)]  # teacher, student, ..., lafortune
    rows = [(p, i) for p in slices for i in range(len(slices[p][1]))]
    fig, axes = plt.subplots(
        len(rows), len(cols), figsize=(1.7 * len(cols), 1.8 * len(rows)), squeeze=False
    )
    for r, (p, i) in enumerate(rows):
        imgs, pairs = slices[p]
        gt = imgs["ground truth"][i]
        scale = float(np.percentile(gt, 99)) or 1.0
        for c, name in enumerate(cols):
            ax = axes[r][c]
            im = imgs[name][i]
            ax.imshow(np.clip(im / scale, 0, 1) ** (1 / 2.2), interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if name != "ground truth":
                err = float(np.abs(im - gt).mean())
                ax.set_xlabel(f"L1 {err:.4f}", fontsize=7)
            if r == 0:
                ax.set_title(name.replace("_", "\n"), fontsize=8)
        axes[r][0].set_ylabel(f"{p}\npair {pairs[i]}", fontsize=8)
    save_png(fig, path, dpi=110)


def _partial(doc: dict) -> list[str]:
    """A line that says so above the tables of a run that stopped before its last material
    (results.json's ``complete`` false; the tables show the materials it finished)."""
    if doc.get("complete", True):
        return []
    todo = [m for m in doc.get("materials", []) if m not in doc["results"]]
    return [
        f"**Partial run**: {len(doc['results'])} of {len(doc['results']) + len(todo)} materials "
        f"finished{' (not yet: ' + ', '.join(todo) + ')' if todo else ''}. The run was "
        "interrupted; the same command with `--resume` finishes it.",
        "",
    ]


def write_report(doc: dict, slices: dict, root: Path) -> None:
    with atomic_path(root / "results.md") as tmp:
        tmp.write_text(markdown(doc))
    curves_png(doc, root / "curves.png")
    bins_png(doc, root / "view_bins.png")
    slices_png(doc, slices, root / "slices.png")


def _data(doc: dict) -> str:
    """The data of the table: the presets' size (``--res``, ``--dirs``) and each BTF file's
    own (``--btf``: the materials named ``*.btf``)."""
    cfg, res = doc["config"], doc["results"]
    parts = []
    if any(not p.endswith(".btf") for p in res):
        parts.append(
            f"{cfg['res']}^2 texels, {cfg['dirs']} x {cfg['dirs']} (light, view) directions"
            + (" (the presets)" if cfg.get("btf") else "")
        )
    for p, r in res.items():
        if p.endswith(".btf") and "shape" in r.get("btf", {}):
            L, V, H, W = r["btf"]["shape"]
            parts.append(f"{p} {H}x{W} texels, {L} x {V} (light, view) directions")
    return "; ".join(parts)


def _trained_on(doc: dict) -> str:
    """Where the networks were (last) trained: the devices their checkpoints record."""
    devs = sorted(
        {
            d
            for r in doc["results"].values()
            for m in r["methods"].values()
            for d in m.get("devices", [])
        }
    )
    if devs in ([], ["cpu"]):  # records from before devices were stored: CPU only
        return "CPU, 1 torch thread"
    return "networks trained on " + ", ".join(devs) + " (Lafortune on the CPU)"


def _duration(seconds: float) -> str:
    """``"42 s"`` below two minutes, else ``"15.4 min"``."""
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.1f} min"
