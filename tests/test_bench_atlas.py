"""`vrneural bench atlas`: the quick mesh set end to end (JSON + Markdown + PNG, every mesh
atlased in its own process), its user errors, and the seam error on lavapipe."""

from __future__ import annotations

import json
import math

import pytest

from vrneural.bench.configs import NAMES
from vrneural.cli import main


def test_quick_run_writes_every_mesh_json_markdown_and_png(tmp_path, capsys):
    out = tmp_path / "b"
    argv = ["bench", "atlas", "--quick", "--no-seams", "--no-progress", "--out", str(out)]
    assert main(argv) == 0
    doc = json.loads((out / "results.json").read_text())
    assert doc["bench"] == "atlas" and doc["config"]["quick"] is True and not doc["failures"]
    recs = {r["mesh"]: r for r in doc["records"]}
    assert list(recs) == list(NAMES)
    for r in recs.values():
        for k in ("total_s", "peak_rss_mb", "coverage_pct", "charts", "density_spread"):
            assert isinstance(r[k], (int, float)) and math.isfinite(r[k]), (r["mesh"], k)
        assert r["triangles_without_texels"] == 0 and r["overlap_texels"] == 0
        assert 20 < r["peak_rss_mb"] < 2000 and r["unwrap_path"]
    assert recs["lightmap"]["uv_source"] == "mesh lightmap UVs (TEXCOORD_1)"
    assert recs["field"]["charts"] == 1 and recs["field"]["coverage_pct"] > 90
    md = (out / "results.md").read_text()
    assert "Quick run" in md and "| lightmap: its own UVs | yes |" in md
    png = (out / "atlases.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) < 300_000
    assert main(argv) == 2 and "pass --force" in capsys.readouterr().err
    # a mesh that failed keeps its row the table's width (it had one cell too many)
    from types import SimpleNamespace

    from vrneural.bench.atlas_report import write_reports

    doc["records"][0] = {"mesh": "ico6", "resolution": 64, "error": "xatlas crashed"}
    write_reports(tmp_path, doc, SimpleNamespace(quick=True))
    table = [ln for ln in (tmp_path / "results.md").read_text().splitlines() if ln[:6] == "| ico6"]
    head = next(ln for ln in md.splitlines() if ln.startswith("| mesh |"))
    assert "FAILED: xatlas crashed" in table[0] and table[0].count("|") == head.count("|")


def test_unknown_mesh_is_one_line_before_any_work(tmp_path, capsys):
    out = tmp_path / "x"
    assert main(["bench", "atlas", "--meshes", "ico6,teapot", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--meshes: teapot not in ico6, ico7" in err
    assert not out.exists()


@pytest.mark.gpu
def test_seam_error_of_a_small_torus_is_near_its_interior_error(tmp_path):
    """Lambertian, texture space vs screen space on lavapipe: the chart seams are no worse
    than the rest of the surface (measured 0.068 vs 0.068 at 128^2, 128 px)."""
    from vrneural.bench.atlas_meshes import write_mesh
    from vrneural.bench.atlas_seams import seam_error

    path = write_mesh("torus", tmp_path, quick=True)
    s = seam_error(str(path), 128, 128)
    assert s["border_pixels"] > 100 and s["object_pixels"] > s["border_pixels"]
    assert 0 <= s["seam_error"] < 0.2 and 0 < s["interior_error"] < 0.2
    assert s["seam_error"] < 2 * s["interior_error"] + 0.02
