"""``results.md`` and ``f16_error.png`` of ``vrneural bench extremes`` (``results.json`` via
:func:`vrneural.bench.report.finish`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vrneural.bench.report import adapter_line, figure, finish, save_png, table


def _fmt(metrics: dict) -> str:
    """Scalar measurements of a case as ``k=v`` (lists and long values left to the JSON)."""
    out = []
    for k, v in metrics.items():
        if isinstance(v, bool) or isinstance(v, (int, float)):
            out.append(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}")
    return ", ".join(out[:6])


def error_png(root: Path, doc: dict) -> Path | None:
    rec = next((r for r in doc["records"] if r["case"] == "f16_vs_f32" and r["metrics"]), None)
    if rec is None:
        return None
    fig, (ax,) = figure(6.4, 3.6)
    m = rec["metrics"]
    for arch in ("coarse_fine", "single"):
        if f"{arch}_hist" not in m:
            continue
        e = np.asarray(m[f"{arch}_hist_edges"])
        c = np.asarray(m[f"{arch}_hist"], float)
        ax.step(np.sqrt(e[:-1] * e[1:]), c / max(c.sum(), 1), where="mid", label=arch)
    ax.set_xscale("log")
    ax.set_xlabel("|f16 - f32| / f32 (6.1e-5 <= f32 < 65504; leftmost bin: identical)")
    ax.set_ylabel("fraction of values")
    ax.set_title("Texture-space kernel: f16 vs f32 arithmetic")
    ax.legend()
    return save_png(fig, root / "f16_error.png")


def write_report(root: Path, doc: dict, t0: float) -> dict:
    recs = doc["records"]
    n_fail = sum(r["outcome"] == "FAIL" for r in recs)
    md = [
        "# vrneural bench extremes",
        "",
        adapter_line(doc),
        f"Mode: {'--quick' if doc['config'].get('quick') else 'full'}. "
        f"{len(recs)} cases: {sum(r['outcome'] == 'works' for r in recs)} works, "
        f"{sum(r['outcome'] == 'rejected' for r in recs)} rejected (as documented), "
        f"{n_fail} FAIL.",
        "",
        "Outcomes: **works** = ran and its documented behaviour held; **rejected** = a one-line "
        "error, which is the documented behaviour; **FAIL** = anything else. Behaviours: "
        "docs/extremes.md (the documentation site's page Numerical behaviour at the extremes).",
        "",
    ]
    rows = [
        [
            r["group"],
            r["case"],
            r["outcome"],
            r["checks"],
            r["message"] or "",
            _fmt(r["metrics"]),
            f"{r['seconds']:.1f}",
        ]
        for r in recs
    ]
    md += table(["group", "case", "outcome", "checks", "message", "measured", "s"], rows)
    png = error_png(root, doc)
    if png:
        md += ["", f"![f16 vs f32 relative error]({png.name})"]
    doc["n_fail"] = n_fail
    return finish(root, doc, md, t0)
