"""results.md and widths.png of `vrneural bench widths` (from its results.json document)."""

from __future__ import annotations

from pathlib import Path

from vrneural.bench.report import pyplot, save_png, table
from vrneural.bench.train_configs import METHODS, STARTS
from vrneural.errors import count
from vrneural.outputs import atomic_path


def describe(cfg: dict) -> str:
    """The budget line of the report."""
    reps = cfg["repeats"]
    seeds = f"seed {cfg['seed']}" if reps == 1 else f"seeds {cfg['seed']}-{cfg['seed'] + reps - 1}"
    return (
        f"{cfg['preset']}, {cfg['res']}^2 texels, {cfg['dirs']} x {cfg['dirs']} directions; "
        f"teacher {count(cfg['teacher_epochs'], 'epoch')}, every other network "
        f"{count(cfg['epochs'], 'epoch')}, {seeds}"
    )


def _label(r: dict) -> str:
    if r["method"] == "neumip":
        return "NeuMIP (4 x 25)"
    return f"{METHODS[r['method']][1]}, {STARTS[r['start']]}"


def within(r: dict, neumip: dict) -> bool:
    """The report's target: a seed mean within 10% of NeuMIP's (the table's bold and
    :func:`~vrneural.bench.widths.narrowest` alike)."""
    return r["whole_l1"] <= 1.1 * neumip["whole_l1"]


def _family(rows: dict, method: str, start: str) -> list[dict]:
    fam = [r for r in rows.values() if r["method"] == method and r["start"] == start]
    return sorted(fam, key=lambda r: r["width"])


def families(doc: dict) -> list[tuple[str, str]]:
    """``(method, start)`` of every family of networks swept over the widths, in the order
    the config names them."""
    cfg = doc["config"]
    return [(m, s) for m in cfg["methods"] for s in cfg["starts"]]


def markdown(doc: dict) -> str:
    rows, cfg = doc["rows"], doc["config"]
    nm = rows["neumip"]
    wide = ""
    if any(s == "wide" for _, s in families(doc)):
        wide = (
            f" A wide start trains 2W wide for the first {count(cfg['epochs'] // 2, 'epoch')} "
            "(epochs // 2), then the network pruned to W for the rest (`distill --wide-start "
            "2W`)."
        )
    lines = [
        f"# What the student's width costs and buys: {cfg['preset']}",
        "",
        f"Budget: {describe(cfg)}.{wide} Whole-BTF L1: mean absolute error over all "
        f"{doc['pairs']} (light, view) pairs, texels and channels, linear units; mean ± sd "
        f"over the seeds. Teacher (128 wide): {doc['teacher']['whole_l1']:.5f}; an all-black "
        f"output: {doc['zero_output_l1']:.5f}. MACs per texel count the student's coarse "
        "net at a quarter (it runs once per 2x2 texel block).",
        "",
    ]

    def row(r: dict, label: str, width: str) -> list:
        black = doc["zero_output_l1"]  # a seed at or above it learned nothing: say so
        seeds = " / ".join(
            f"{v:.5f}" + (" (no better than black)" if v >= black else "")
            for v in r["whole_l1_seeds"]
        )
        sd = f" ± {r['whole_l1_sd']:.5f}" if len(r["whole_l1_seeds"]) > 1 else ""
        gap = r["whole_l1"] / nm["whole_l1"] - 1
        secs = sum(r["train_seconds_seeds"]) / len(r["train_seconds_seeds"])
        vs = "" if r is nm else f"{gap:+.1%}"
        if r is not nm and within(r, nm):
            vs = f"**{vs}**"
        return [label, width, f"{r['macs_per_texel']:g}", r["weight_bytes"], seeds,
                f"{r['whole_l1']:.5f}{sd}", vs, f"{secs:.1f}"]  # fmt: skip

    table_rows = [row(r, _label(r), str(r["width"]))
                  for m, s in families(doc) for r in _family(rows, m, s)]  # fmt: skip
    head = ["network", "width", "MACs / texel", "weights (B)", "whole-BTF L1 per seed",
            "mean ± sd", "vs NeuMIP", "training s (mean of seeds)"]  # fmt: skip
    lines += table(head, [*table_rows, row(nm, _label(nm), "25")])
    lines += ["", "Narrowest width within 10% of NeuMIP (seed means; **bold** above):", ""]
    for method, start in families(doc):
        w = doc["within_10pct"][f"{method}:{start}"]
        fam = _family(rows, method, start)
        if w is None:
            widths = ", ".join(str(r["width"]) for r in fam)
            lines.append(f"- {_label(fam[0])}: none of {widths}")
            continue
        r = next(r for r in fam if r["width"] == w)
        share = r["macs_per_texel"] / nm["macs_per_texel"]
        lines.append(
            f"- {_label(r)}: {w} wide ({r['macs_per_texel']:g} MACs per texel, {share:.0%} of "
            f"NeuMIP's {nm['macs_per_texel']:g}; {r['whole_l1'] / nm['whole_l1'] - 1:+.1%})"
        )
    lines += [
        "",
        "![whole-BTF L1 against multiply-adds per texel](widths.png)",
        "",
        f"Total {doc['total_seconds'] / 60:.1f} min. Kernel time of the same networks on the GPU "
        "(wgpu): `vrneural bench kernels --networks student:W,single8:W,...`.",
        "",
    ]
    return "\n".join(lines)


def widths_png(doc: dict, path: Path) -> None:
    plt = pyplot()

    rows = doc["rows"]
    nm = rows["neumip"]
    fig, ax = plt.subplots(figsize=(7.2, 4.8))
    marks = {"plain": "o-", "wide": "s--"}  # a method keeps its colour; the start its line
    colours = {"student": "C0", "student_nodistill": "C1", "single8": "C2"}
    series = [(_family(rows, m, s), dict(fmt=marks[s], color=colours[m])) for m, s in families(doc)]
    for fam, style in [*series, ([nm], dict(fmt="r*", ms=11))]:  # NeuMIP last, no width label
        x = [r["macs_per_texel"] for r in fam]
        y = [r["whole_l1"] for r in fam]
        ax.errorbar(
            x, y, yerr=[r["whole_l1_sd"] for r in fam], capsize=3, label=_label(fam[0]), **style
        )
        for r, xi, yi in zip(fam, x, y, strict=True):
            if r is not nm:
                ax.annotate(
                    str(r["width"]),
                    (xi, yi),
                    textcoords="offset points",
                    xytext=(4, 4),
                    fontsize=7,
                    color=style["color"],
                )
    ax.axhline(1.1 * nm["whole_l1"], color="r", lw=0.8, ls=":", label="NeuMIP + 10%")
    top = max(r["whole_l1"] + r["whole_l1_sd"] for r in rows.values())
    if doc["zero_output_l1"] <= 1.5 * top:  # in view: a network near it learned nothing
        ax.axhline(doc["zero_output_l1"], color="k", lw=0.8, ls="-.", label="all-black output")
    ax.set_xscale("log")
    ax.set_xlabel("MLP multiply-adds per texel (labels: width)")
    several = doc["config"]["repeats"] > 1
    ax.set_ylabel("whole-BTF L1" + (" (mean ± sd over seeds)" if several else ""))
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    ax.set_title(describe(doc["config"]), fontsize=8)
    fig.tight_layout()
    save_png(fig, path, dpi=110, bbox=None)


def write_report(doc: dict, root: Path) -> None:
    with atomic_path(root / "results.md") as tmp:
        tmp.write_text(markdown(doc))
    widths_png(doc, root / "widths.png")
