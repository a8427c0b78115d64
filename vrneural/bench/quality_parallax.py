"""`bench quality`: L1 by view angle and the parallax variants (issue #44).

Every method's whole-BTF L1 is also split by the view's polar angle into :data:`VIEW_BINS`
(degrees; a pair falls in ``[lo, hi)``): a texel-local network that cannot move its lookup
fails on a material with relief at grazing views, where the relief shifts the visible surface
furthest. With ``--parallax height`` (or ``both``) the bench also trains the height-field
variants:

- ``teacher_parallax``: the teacher with ``teach --parallax height``;
- ``student_parallax``: the student distilled from it, ``distill --parallax height``;
- ``neumip_parallax``: NeuMIP on ground truth with ``--parallax height`` (the height field in
  place of NeuMIP's neural offset module).

With ``--parallax neural`` (or ``both``) the neural-offset variants (NeuMIP's module,
:mod:`vrneural.neural_offset`, trained without a height field):

- ``teacher_neural``: the teacher with ``teach --parallax neural``;
- ``student_neural``: the student distilled from it, ``distill --parallax neural``;
- ``neumip_neural``: "NeuMIP with offset", the paper's full model, on ground truth.

The networks without a suffix train with ``--parallax off`` (the paper's "NeuMIP without
offset" baseline, and the student as before). Cost per texel beside the L1: the networks'
multiply-adds (the offset MLP's included) and the runtime kernel's texel loads (neural
textures, the offset texture's, and the height field's ``4 (steps + 1)`` at most).
"""

from __future__ import annotations

import math
import statistics

from vrneural.bench.report import pyplot, save_png
from vrneural.btf.format import read_btf
from vrneural.errors import VrnError
from vrneural.parallax import parallax_fetches

#: view polar-angle bins, degrees
VIEW_BINS = ((0.0, 30.0), (30.0, 50.0), (50.0, 65.0), (65.0, 76.0))

#: the suffix of each kind's variants
SUFFIX = {"height": "_parallax", "neural": "_neural"}

PARALLAX_LABELS = {
    "teacher_parallax": "Teacher + height parallax",
    "neumip_parallax": "NeuMIP (4x25) + height parallax",
    "student_parallax": "Ours (distilled) + height parallax",
    "teacher_neural": "Teacher + neural offset",
    "neumip_neural": "NeuMIP with offset (4x25)",
    "student_neural": "Ours (distilled) + neural offset",
}
PARALLAX_RUNS = {
    "height": {
        "neumip_parallax": dict(method="neumip", distill=False, parallax="height"),
        "student_parallax": dict(method="student", parallax="height", teacher="teacher_parallax"),
    },
    "neural": {
        "neumip_neural": dict(method="neumip", distill=False, parallax="neural"),
        "student_neural": dict(method="student", parallax="neural", teacher="teacher_neural"),
    },
}


def bench_kinds(cfg) -> list[str]:
    """The parallax kinds whose variants a bench trains (``--parallax``)."""
    p = getattr(cfg, "parallax", "off")
    return ["height", "neural"] if p == "both" else [] if p == "off" else [p]


def teachers(cfg) -> list[tuple[str, str]]:
    """``(stem, parallax)`` of the teachers a bench trains: the plain one first."""
    return [("teacher", "off")] + [(f"teacher{SUFFIX[k]}", k) for k in bench_kinds(cfg)]


def runs_table(cfg, runs: dict) -> dict:
    """The networks of a bench: ``runs`` and the variants of ``--parallax``."""
    out = dict(runs)
    for k in bench_kinds(cfg):
        out |= PARALLAX_RUNS[k]
    return out


def plain_twin(name: str) -> str | None:
    """The network without parallax a variant is compared with (None for a plain one)."""
    for suffix in SUFFIX.values():
        if name.endswith(suffix):
            return name.removesuffix(suffix)
    return None


def view_theta(data, pair: int) -> float:
    """The view polar angle of a pair, degrees."""
    z = float(data.dirs(pair)[1][2])
    return math.degrees(math.acos(min(max(z, -1.0), 1.0)))


def bin_pairs(data, pairs) -> list[list[int]]:
    """``pairs`` grouped by :data:`VIEW_BINS` (a pair beyond the last bin: in none)."""
    out: list[list[int]] = [[] for _ in VIEW_BINS]
    for p in pairs:
        t = view_theta(data, p)
        for i, (lo, hi) in enumerate(VIEW_BINS):
            if lo <= t < hi:
                out[i].append(p)
    return out


def texel_fetches(mat) -> float:
    """Texel loads per shaded texel of the runtime kernel (4 per bilinear lookup of 8
    channels; the coarse texture once per 2x2 block) plus the parallax march's at most, or the
    offset texture's."""

    def loads(name):
        return 4 * math.ceil(mat.textures[name].shape[2] / 8)

    if mat.arch == "coarse_fine":
        n = loads("coarse") / 4 + loads("fine")
    else:
        n = float(loads("features"))
    if mat.parallax_steps:
        n += parallax_fetches(mat.parallax_steps)
    if mat.parallax_kind == "neural":
        from vrneural.neural_offset import offset_fetches

        n += offset_fetches(mat.offset_tex, mat.parallax_march)
    return n


def parallax_record(models: list, mat, data, pairs) -> dict:
    """What the bench adds to a network method's record: ``view_bins_l1`` (the seeds' mean L1
    per :data:`VIEW_BINS`, None for an empty bin), ``view_bin_pairs``, ``fetches_per_texel``
    and ``parallax`` (``{"kind", "steps"}``)."""
    from vrneural.distill.evaluate import mean_l1

    groups = bin_pairs(data, pairs)
    bins = [statistics.fmean(mean_l1(m, data, ps) for m in models) if ps else None for ps in groups]
    return {
        "view_bins_l1": bins,
        "view_bin_pairs": [len(ps) for ps in groups],
        "fetches_per_texel": texel_fetches(mat),
        "parallax": {"kind": mat.parallax_kind, "steps": mat.parallax_steps},
    }


def _fmt(x) -> str:
    return "-" if x is None else f"{x:.4g}"


def _ratio(a, b) -> str:
    return "-" if a is None or b in (None, 0) else f"{a / b:.3f}"


def markdown_bins(doc: dict) -> list[str]:
    """The report's section: L1 per view-angle bin and cost per texel of every method, and
    the parallax variants against their plain twins."""
    res = doc["results"]
    lab = doc["labels"]
    head = [f"{lo:g}-{hi:g} deg" for lo, hi in VIEW_BINS]
    lines = [
        "## L1 by view angle (whole BTF: every pair, by its view's polar angle)",
        "",
    ]
    for preset, r in res.items():
        methods = {k: m for k, m in r["methods"].items() if m.get("view_bins_l1")}
        if not methods:
            continue
        first = next(iter(methods.values()))
        n = first.get("view_bin_pairs") or []
        lines += [
            f"**{preset}** (pairs per bin: {', '.join(str(k) for k in n)})",
            "",
            "| Method | whole L1 | " + " | ".join(head) + " | MACs/texel | loads/texel |",
            "|---" * (len(head) + 4) + "|",
        ]
        for k, m in methods.items():
            macs = m.get("macs_per_texel")
            fetch = m.get("fetches_per_texel")
            lines.append(
                f"| {lab.get(k, k)} | {_fmt(m['whole_l1'])} | "
                + " | ".join(_fmt(x) for x in m["view_bins_l1"])
                + f" | {'-' if macs is None else f'{macs:.0f}'} | "
                + f"{'-' if fetch is None else f'{fetch:g}'} |"
            )
        pairs = [(a, plain_twin(a)) for a in methods]
        pairs = [(a, b) for a, b in pairs if b in methods]
        if pairs:
            lines += [
                "",
                "With / without parallax (ratio of L1; below 1: parallax helps):",
                "",
                "| Pair | whole | " + " | ".join(head) + " |",
                "|---" * (len(head) + 2) + "|",
            ]
            for a, b in pairs:
                ma, mb = methods[a], methods[b]
                lines.append(
                    f"| {lab.get(a, a)} / {lab.get(b, b)} | "
                    f"{_ratio(ma['whole_l1'], mb['whole_l1'])} | "
                    + " | ".join(
                        _ratio(x, y)
                        for x, y in zip(ma["view_bins_l1"], mb["view_bins_l1"], strict=True)
                    )
                    + " |"
                )
        ref = methods.get("neumip_neural")
        rivals = [k for k in ("student_parallax", "student_neural", "student") if k in methods]
        if ref is not None and rivals:  # the target: within 10% of NeuMIP with offset
            lines += [
                "",
                f"Against {lab.get('neumip_neural')} (ratio of L1; at most 1.1: within 10%):",
                "",
                "| Method | whole | " + " | ".join(head) + " |",
                "|---" * (len(head) + 2) + "|",
            ]
            for k in rivals:
                m = methods[k]
                lines.append(
                    f"| {lab.get(k, k)} | {_ratio(m['whole_l1'], ref['whole_l1'])} | "
                    + " | ".join(
                        _ratio(x, y)
                        for x, y in zip(m["view_bins_l1"], ref["view_bins_l1"], strict=True)
                    )
                    + " |"
                )
        lines.append("")
    return lines


def bins_png(doc: dict, path) -> None:
    """L1 per view-angle bin, one panel per material, one line per method (PNG)."""
    plt = pyplot()

    res = doc["results"]
    lab = doc["labels"]
    shown = [p for p, r in res.items() if any(m.get("view_bins_l1") for m in r["methods"].values())]
    if not shown:
        return
    fig, axes = plt.subplots(1, len(shown), figsize=(6 * len(shown), 4.2), squeeze=False)
    x = [f"{lo:g}-{hi:g}" for lo, hi in VIEW_BINS]
    for ax, preset in zip(axes[0], shown, strict=True):
        colors = plt.get_cmap("tab20").colors  # 20 distinct: a method per colour
        for i, (k, m) in enumerate(res[preset]["methods"].items()):
            y = m.get("view_bins_l1")
            if not y:
                continue
            style = "--" if plain_twin(k) is None else "-"
            ax.plot(x, [float("nan") if v is None else v for v in y], style, marker="o",
                    label=lab.get(k, k), color=colors[i % len(colors)])  # fmt: skip
        ax.set_title(preset)
        ax.set_xlabel("view polar angle (degrees)")
        ax.set_ylabel("L1 (linear BTF units)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    save_png(fig, path, dpi=110, bbox=None)


def check_parallax_data(presets: list[str], given: dict, asked: str = "height") -> None:
    """``--parallax height`` (or ``both``) needs a height field in every BTF it benches:
    one-line error before any work for a synthetic preset (``btf synth`` writes none yet) or
    a given BTF without one (format version 1)."""
    if presets:
        raise VrnError(
            f"--parallax {asked}: the synthetic presets ({', '.join(presets)}) carry no height "
            "field (btf synth writes none yet); bench path-traced BTFs with --btf (btf render)"
        )
    for p in given.values():
        if read_btf(p).height is None:
            raise VrnError(
                f"--parallax {asked}: --btf {p} has no height field (BTF format version 1); "
                "drop it or --parallax"
            )


def resolved_parallax(ck: dict) -> str:
    """The ``--parallax`` a checkpoint was trained with, ``auto`` resolved to what it chose
    (the checkpoint's record), so a teacher trained with the default reuses as ``off`` or
    ``height``."""
    asked = ck["config"].get("parallax", "off")
    if asked != "auto":
        return asked
    return (ck.get("parallax") or {}).get("kind", "off")
