"""The xatlas child process: a child that dies gives one actionable line, never a traceback."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import trimesh

from vrneural.atlas import builtin_mesh
from vrneural.atlas import unwrap as unwrap_mod
from vrneural.errors import VrnError


def test_xatlas_segfault_on_an_icosphere_is_recovered_and_said(tmp_path):
    """The real crash (jpcy/xatlas#146; about 1 s of xatlas): xatlas segfaults on the
    81920-face icosphere at every --res, and a copy moved by 1e-6 gives folded charts. With
    --atlas-uv xatlas the crash is survived: the path taken is in the stats (crash, retry,
    then vrneural's own charts) and the atlas is complete. Run as a user would, with Python's
    faulthandler on: stderr has no crash dump. If a new xatlas no longer crashes, this test
    fails: then drop the crash assertions (the fake-child tests below cover the message)."""
    trimesh.creation.icosphere(subdivisions=6).export(tmp_path / "ico6.ply")
    out = tmp_path / "ico.png"
    cli = [sys.executable, "-X", "faulthandler", "-m", "vrneural", "atlas"]
    r = subprocess.run(
        [
            *cli,
            str(tmp_path / "ico6.ply"),
            "--res",
            "512",
            "-o",
            str(out),
            "--no-cache",
            "--atlas-uv",
            "xatlas",
            "--json",
        ],
        capture_output=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr.decode()[-2000:]
    assert b"Fatal Python error" not in r.stderr
    stats = json.loads(r.stdout)
    path = stats["unwrap_path"]
    assert path[0] == "xatlas failed: xatlas crashed (SIGSEGV, signal 11)", path
    assert path[-1] == "charts" and stats["uv_source"] == "charts"
    assert stats["triangles"] == 81920 and stats["overlap_texels"] == 0
    assert stats["zero_area_triangles"] == 0 and stats["coverage_pct"] > 60
    assert out.exists()
    # the default never runs xatlas: vrneural's charts directly
    r = subprocess.run(
        [
            *cli,
            str(tmp_path / "ico6.ply"),
            "--res",
            "512",
            "-o",
            str(out),
            "--no-cache",
            "--json",
            "--force",
        ],
        capture_output=True,
        timeout=300,
    )
    assert r.returncode == 0 and json.loads(r.stdout)["unwrap_path"] == ["charts"]


def _dies(how, delay: float = 0.0):
    """A stand-in for ``unwrap._child`` that closes its pipe, waits ``delay`` s, then ends
    by ``how``: a signal number, or ``("exit", code)``."""

    def child(conn, *_args):
        conn.close()
        time.sleep(delay)
        if isinstance(how, tuple):
            os._exit(how[1])
        if how != signal.SIGKILL:  # the default action, not pytest's faulthandler dump
            signal.signal(how, signal.SIG_DFL)
        os.kill(os.getpid(), how)
        os._exit(0)  # not reached

    return child


@pytest.mark.parametrize(
    ("how", "delay", "message"),
    [
        # pipe closed 0.3 s before the crash: the exit code is read only after the join
        # (read before it, it was None: "the xatlas process died (exit code None)")
        (signal.SIGSEGV, 0.3, "xatlas crashed (SIGSEGV, signal 11), a known xatlas bug"),
        (signal.SIGABRT, 0.0, "xatlas crashed (SIGABRT, signal 6)"),
        (signal.SIGKILL, 0.0, "killed (SIGKILL, signal 9), most likely by the out-of-memory"),
        (signal.SIGTERM, 0.0, "the xatlas process was stopped by SIGTERM (signal 15)"),
        (("exit", 3), 0.0, "the xatlas process exited with code 3 without sending a result"),
    ],
)
def test_a_dead_child_is_named_with_its_signal(monkeypatch, how, delay, message):
    monkeypatch.setattr(unwrap_mod, "_child", _dies(how, delay))
    mesh = builtin_mesh("plane")
    with pytest.raises(VrnError) as e:
        unwrap_mod.unwrap(mesh, 64, 2)
    assert str(e.value).startswith(f"plane ({len(mesh.faces)} triangles): ")
    assert message in str(e.value) and "None" not in str(e.value)


@pytest.mark.parametrize("method", ["charts", "xatlas"])
def test_the_atlas_does_not_depend_on_the_mesh_units(method):
    """xatlas has absolute epsilons: a 2 cm icosphere of 20k triangles came back with no
    charts (then an IndexError from deep inside). The unwrap runs in the mesh's own units, so
    the same sphere in metres, centimetres and 1.5 mm gets an equally good atlas (not bit for
    bit: xatlas's charts react to the last bits of a position), and texels_per_unit comes
    back in the mesh's units. vrneural's own charts compare only ratios of lengths."""
    from vrneural.atlas import build_atlas, make_mesh

    ico = trimesh.creation.icosphere(subdivisions=5)
    atlases = {}
    for radius in (1.0, 0.01, 0.0015):
        mesh = make_mesh(f"ball {radius}", ico.vertices * radius, ico.faces)
        atlases[radius] = build_atlas(mesh, 128, cache=False, atlas_uv=method).stats
    metre = atlases.pop(1.0)
    for r, s in atlases.items():
        assert s["zero_area_triangles"] == 0 == metre["zero_area_triangles"]
        assert s["charts"] == pytest.approx(metre["charts"], rel=0.15)
        assert s["coverage_pct"] == pytest.approx(metre["coverage_pct"], rel=0.15)
        assert s["texels_per_unit"] == pytest.approx(metre["texels_per_unit"] / r, rel=0.15)
    # parts far smaller than the extent: xatlas makes no charts at all (one line inside the
    # xatlas path); that path then falls back to vrneural's charts, which pack each part at
    # the same texel density: every triangle gets its texels
    tiny = trimesh.creation.icosphere(subdivisions=2, radius=1e-5)
    pos = np.concatenate([tiny.vertices, tiny.vertices + np.array([1.0, 0.0, 0.0])])
    far = make_mesh("far", pos, np.concatenate([tiny.faces, tiny.faces + len(tiny.vertices)]))
    if method == "xatlas":
        with pytest.raises(VrnError, match="far: xatlas made no charts: all 640 triangles are"):
            unwrap_mod.unwrap(far, 64, 2)
    s = build_atlas(far, 128, cache=False, atlas_uv=method).stats
    assert s["zero_area_triangles"] == 0 and s["triangles_without_texels"] == 0
    assert s["unwrap_path"][-1] == "charts"
