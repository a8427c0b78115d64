"""``results.json`` and ``results.md`` of `vrneural bench atlas` (targets checked in the table)."""

from __future__ import annotations

from pathlib import Path

from vrneural.bench import report as rp
from vrneural.outputs import atomic_path, write_json

#: the issue's targets: coverage on every mesh but the needle fan, the 1M-triangle mesh's time
#: and peak memory, and the mesh with lightmap UVs using them
MIN_COVERAGE = 60.0
BIG_SECONDS = 60.0
BIG_MB = 1024.0


def targets(records: list) -> list[tuple[str, bool, str]]:
    """``(target, met, measured)`` for each of the issue's targets present in ``records``."""
    ok = [r for r in records if "error" not in r]
    out = [("no failure", len(ok) == len(records), f"{len(records) - len(ok)} failed")]
    for r in ok:
        mesh, cov, s, mb = r["mesh"], r["coverage_pct"], r["total_s"], r["peak_rss_mb"]
        if mesh != "fan":
            out.append(
                (f"{mesh}: coverage >= {MIN_COVERAGE:g}%", cov >= MIN_COVERAGE, f"{cov:.1f}%")
            )
        if r["triangles"] >= 1_000_000:
            out.append((f"{mesh}: < {BIG_SECONDS:g} s", s < BIG_SECONDS, f"{s:.1f} s"))
            out.append((f"{mesh}: < {BIG_MB:g} MB peak", mb < BIG_MB, f"{mb:.0f} MB"))
        if mesh == "lightmap":
            own = r["uv_source"].startswith("mesh lightmap")
            out.append(("lightmap: its own UVs", own, r["uv_source"]))
    return out


#: the table's columns: ``(header, field)``, a record's key or a function of the record
COLUMNS = [
    ("mesh", "mesh"),
    ("triangles", "triangles"),
    ("R", "resolution"),
    ("UVs", "uv_source"),
    ("path", lambda r: " -> ".join(r["unwrap_path"])),
    ("time s", "total_s"),
    ("peak MB", lambda r: round(r["peak_rss_mb"])),
    ("coverage %", "coverage_pct"),
    ("charts", "charts"),
    ("tris w/o texel", "triangles_without_texels"),
    ("spread", "density_spread"),
    ("seam err", lambda r: r.get("seams", {}).get("seam_error", "-")),
    ("interior err", lambda r: r.get("seams", {}).get("interior_error", "-")),
]


def _row(r: dict) -> list:
    if "error" in r:  # the table's width, the failure under UVs
        return [r["mesh"], "-", r["resolution"], "FAILED: " + r["error"]] + ["-"] * (
            len(COLUMNS) - 4
        )
    return [f(r) if callable(f) else r[f] for _, f in COLUMNS]


def write_reports(root: Path, doc: dict, cfg) -> None:
    write_json(root / "results.json", doc)
    md = [
        "# Atlas: time, memory, coverage and seams over the bench mesh set",
        "",
        rp.adapter_line(doc),
        f"{doc['cpu_count']} CPUs, load average {doc['load_avg_1m']:.1f} at the end; "
        f"{doc['total_seconds']:.0f} s in all."
        + (" **Quick run: small meshes.**" if cfg.quick else ""),
        "",
        "Time: `build_atlas` without cache (unwrap, rasterize, gutter, cache write), wall. "
        "Peak: the process's peak resident memory (interpreter, mesh and atlas). Coverage: "
        "texel centres inside triangles. Spread: texel density, 95th / 5th percentile. Seam / "
        "interior: largest |texture - screen| of a Lambertian render on atlas seams / elsewhere "
        "(relative to the image's 99th percentile).",
        "",
    ]
    md += rp.table([h for h, _ in COLUMNS], [_row(r) for r in doc["records"]])
    md += ["", "## Targets", ""]
    if cfg.quick:
        md += [
            "The issue's targets are for the full mesh set; a quick run's small atlases are "
            "listed against them for reference only.",
            "",
        ]
    md += rp.table(
        ["target", "met", "measured"],
        [[t, "yes" if ok else "**no**", m] for t, ok, m in targets(doc["records"])],
    )
    md += ["", "![atlases](atlases.png)", ""]
    with atomic_path(root / "results.md") as tmp:
        Path(tmp).write_text("\n".join(md) + "\n")
