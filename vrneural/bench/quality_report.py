"""Markdown table and PNG figures of `vrneural bench quality` (from its results dict)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vrneural.formats.atomic import atomic_path

ORDER = ("lafortune", "neumip", "single8", "student_nodistill", "student", "teacher")


def targets(m: dict) -> dict[str, bool]:
    """The issue's targets for one material's method records."""
    s = m["student"]["whole_l1"]
    return {
        "within 10% of NeuMIP": s <= 1.10 * m["neumip"]["whole_l1"],
        "below single-level 8-wide": s < m["single8"]["whole_l1"],
        "below no-distillation": s < m["student_nodistill"]["whole_l1"],
        "1.5x below Lafortune": 1.5 * s <= m["lafortune"]["whole_l1"],
    }


def markdown(doc: dict) -> str:
    res = doc["results"]
    cfg = doc["config"]
    presets = list(res)
    lab = doc["labels"]
    lines = [
        "# Quality: whole-BTF L1 per material and method (paper Table 1 analog)",
        "",
        f"Budget: {cfg['res']}^2 texels, {cfg['dirs']} x {cfg['dirs']} (light, view) "
        f"directions, teacher {cfg['teacher_epochs']} epochs, every other network "
        f"{cfg['epochs']} epochs, Lafortune {cfg['lafortune_iters']} LM iterations, seed "
        f"{cfg['seed']}; CPU, 1 torch thread. Total {doc['total_seconds'] / 60:.1f} min.",
        "",
        "| method | " + " | ".join(presets) + " | storage (bytes) | MLP MACs / texel |",
        "|---|" + "---|" * (len(presets) + 2),
    ]
    for name in ORDER:
        if name not in res[presets[0]]["methods"]:
            continue
        r0 = res[presets[0]]["methods"][name]
        vals = []
        for p in presets:
            v = res[p]["methods"][name]["whole_l1"]
            best = min(
                res[p]["methods"][k]["whole_l1"] for k in res[p]["methods"] if k != "teacher"
            )
            vals.append(f"**{v:.5f}**" if v == best else f"{v:.5f}")
        store = f"{r0['texture_bytes']} + {r0['weight_bytes']}"
        macs = "-" if r0["macs_per_texel"] is None else f"{r0['macs_per_texel']:g}"
        lines.append(f"| {lab[name]} | " + " | ".join(vals) + f" | {store} | {macs} |")
    lines += [
        "",
        "Storage = texture + network bytes of the runtime pack (textures float16, weights "
        "float32; Lafortune: 55 float32 per texel). Bold: best non-teacher method.",
        "",
        "## Targets (student vs baselines, whole-BTF L1)",
        "",
        "| material | " + " | ".join(targets(res[presets[0]]["methods"])) + " |",
        "|---|" + "---|" * 4,
    ]
    for p in presets:
        t = targets(res[p]["methods"])
        lines.append(f"| {p} | " + " | ".join("yes" if v else "**no**" for v in t.values()) + " |")
    lines += [
        "",
        "## Held-out test L1 and training time (s)",
        "",
        "train s: the run's training seconds (epochs + per-epoch test; wall clock, so it counts "
        "any time the job was paused or shared its core); s/epoch: the median epoch, which "
        "is robust to such interruptions.",
        "",
        "| material | method | test L1 | whole L1 | train s | s/epoch |",
        "|---|---|---|---|---|---|",
    ]
    for p in presets:
        for name in ORDER:
            r = res[p]["methods"].get(name)
            if r:
                ep = r.get("epoch_seconds_median")
                lines.append(
                    f"| {p} | {name} | {r['test_l1']:.5f} | {r['whole_l1']:.5f} | "
                    f"{r['train_seconds']:.1f} | {'-' if ep is None else f'{ep:.1f}'} |"
                )
    lines += [
        "",
        "Figures: `curves.png` (test L1 per epoch), `slices.png` (BTF slices vs ground truth).",
        "",
    ]
    return "\n".join(lines)


def _save(fig, path: Path) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110, bbox_inches="tight")


def curves_png(doc: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    res = doc["results"]
    fig, axes = plt.subplots(1, len(res), figsize=(4.2 * len(res), 3.4), squeeze=False)
    for ax, (p, r) in zip(axes[0], res.items(), strict=True):
        for name in ORDER:
            m = r["methods"].get(name)
            if not m:
                continue
            if m["curve"]:
                ax.plot(
                    range(1, len(m["curve"]) + 1),
                    m["curve"],
                    label=doc["labels"][name],
                    lw=2.2 if name == "student" else 1.2,
                )
            else:
                ax.axhline(m["test_l1"], ls="--", c="gray", label=doc["labels"][name])
        ax.set_yscale("log")
        ax.set_title(p)
        ax.set_xlabel("epoch")
        ax.set_ylabel("test L1")
        ax.grid(alpha=0.3)
    axes[0][-1].legend(fontsize=7)
    _save(fig, path)
    plt.close(fig)


def slices_png(doc: dict, slices: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cols = [
        "ground truth",
        "teacher",
        "student",
        "student_nodistill",
        "single8",
        "neumip",
        "lafortune",
    ]
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
    _save(fig, path)
    plt.close(fig)


def write_report(doc: dict, slices: dict, root: Path) -> None:
    with atomic_path(root / "results.md") as tmp:
        tmp.write_text(markdown(doc))
    curves_png(doc, root / "curves.png")
    slices_png(doc, slices, root / "slices.png")
