"""xatlas unwrap into exactly R x R texels, with vertices split at chart seams (the charts of
``build_atlas(atlas_uv="xatlas")``, which re-packs them; :mod:`vrneural.atlas.generate`).

xatlas's own ``texels_per_unit`` estimate for a given ``resolution`` overshoots (a 0.3 m sphere
asked for 1200^2 came back 1378 x 1384), and a fixed ``resolution`` with too high a
``texels_per_unit`` spills into several atlases. So:

1. **Charts** (the slow part): ``add_mesh`` + ``generate`` at an explicit ``texels_per_unit``
   estimated from the surface area for :data:`TARGET_FILL`, one atlas of free size
   (``resolution = 0``).
2. **Pack** (fast, ~0.5 s for 700 charts): if that atlas is larger than R, or smaller than
   :data:`GOOD_FIT` R, the charts (UVs divided by ``texels_per_unit``) are re-packed alone
   with ``add_uv_mesh`` at a corrected ``texels_per_unit``; charting is not repeated.
   xatlas gets ``bilinear = True`` (it reserves a 1-texel ring around each chart's
   conservative footprint, so bilinear taps of one chart never read another chart's texels:
   checked on random points of every built-in mesh by tests/test_atlas_build.py) plus
   ``padding - 1`` texels of extra spacing. On the knot this gives 39 % coverage instead of
   34 % with ``padding`` + bilinear, with no bleeding taps either way.
3. The packed pixel coordinates are scaled *up* uniformly by ``R / max(W, H) >= 1`` into the
   R x R texture: gaps between charts only grow.

Speed (measured, see docs/atlas.md): xatlas's chart growing and parameterization get much
slower with chart size. CPU time of ``generate`` on the 100k-triangle knot with
``max_iterations = 0``: unlimited charts 83 s, charts capped at ~2000 triangles 31 s, at ~300
triangles 3.8 s (8.1 s with xatlas's default single iteration).
So meshes above :data:`FAST_FACES` triangles use ``max_chart_area`` for about
:data:`FACES_PER_CHART` triangles per chart and no chart-relocation iterations: more, smaller
charts (more seams and gutter texels, a few % lower fill) for a 10-20x faster unwrap.
Random (not brute-force) placement is xatlas's default and kept.

**In the mesh's own units.** xatlas compares areas and lengths with fixed epsilons: a 2 cm
icosphere of 20k triangles (edges of about 0.4 mm) came back with no charts at all, and so
did one of 1.5 mm radius. So a mesh much smaller or larger than a unit is scaled by a power
of two to about unit size before the unwrap (:func:`normalized_positions`), which makes its
atlas as good whether it is modelled in metres or millimetres (not bit for bit: xatlas's charts
react to the last bits of a position, so meshes of ordinary size are left exactly as they are);
``texels_per_unit`` is converted back to the mesh's units.
Triangles that are still far smaller than the mesh (a 0.5 mm part of a 1 m model) can come
back with no area in the atlas: they are counted in ``zero_area_triangles`` and `run` and
`atlas` warn about them.

**In a child process.** xatlas destroys an atlas by stopping its worker threads, and that
shutdown can lose its wake-up (it sets the flag and notifies without holding the worker's
mutex): the join then waits forever, with the GIL held. We saw it once in CI, in a test that
builds many atlases. So :func:`unwrap` runs the work in a forked child process, which sends
the arrays back and ends with ``os._exit`` before any xatlas object is destroyed; every atlas
object stays referenced until then. A child that dies instead (xatlas segfaults on some meshes,
e.g. finely subdivided icospheres, jpcy/xatlas#146) is reported in one line naming the signal
(:func:`died_message`); :mod:`vrneural.atlas.generate` catches it and carries on.
"""

from __future__ import annotations

import faulthandler
import multiprocessing as mp
import os
import signal

import numpy as np

from vrneural.atlas.types import Mesh
from vrneural.errors import VrnError

#: meshes with more triangles than this get the fast chart options (module docstring)
FAST_FACES = 20000
#: target triangles per chart for large meshes (sets xatlas's max_chart_area)
FACES_PER_CHART = 300
#: first-try fraction of the R x R texels covered by charts (xatlas packs ~55-75 %)
TARGET_FILL = 0.5
#: a packed atlas with max(W, H) in [GOOD_FIT R, R] is accepted without re-packing
GOOD_FIT = 0.93
#: pack tries in all; a fixed ring and gap per chart make the size converge slowly where they
#: dominate (the 698 charts of the 100k-triangle knot fit 64^2 on the 6th try)
MAX_PACKS = 8


def _pack_options(tpu: float, padding: int):
    import xatlas

    po = xatlas.PackOptions()
    po.resolution = 0
    po.texels_per_unit = float(tpu)
    po.padding = max(int(padding) - 1, 0)  # + the bilinear ring = `padding` texels per chart
    po.bilinear = True
    return po


#: seconds a child unwrap may take before it is declared hung (far above any unwrap measured
#: here: the 100k-triangle knot's chart generation takes 3.8 s, module docstring)
CHILD_TIMEOUT_S = 1800.0


def unwrap(
    mesh: Mesh, resolution: int, padding: int, chart_options: dict | None = None
) -> tuple[np.ndarray, np.ndarray, dict]:
    """Unwrap ``mesh`` with xatlas. Returns ``(vmapping [V'] int64, uv [V', 2] float32 in
    [0, 1], info)``. Split vertex ``i`` copies input vertex ``vmapping[i]``; the faces keep
    their order, re-indexed onto the split vertices as ``info["faces"]`` [F, 3] int64.
    ``info`` also holds charts, texels_per_unit, packed size and pack count. Runs in a child
    process (module docstring); errors come back as the same one-line :class:`VrnError`.
    ``chart_options``: xatlas ``ChartOptions`` fields to set (None: the defaults above).
    """
    # fork, not spawn / forkserver: those re-import the caller's main module in the child,
    # which breaks scripts without a __main__ guard and `python -` (stdin). The child touches
    # only numpy and xatlas, never the parent's GPU or torch threads.
    ctx = mp.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(
        target=_child, args=(send, mesh, resolution, padding, chart_options), daemon=True
    )
    proc.start()
    send.close()
    try:
        if not recv.poll(CHILD_TIMEOUT_S):
            raise VrnError(f"{mesh.name}: xatlas did not finish in {CHILD_TIMEOUT_S:.0f} s")
        kind, payload = recv.recv()
    except EOFError:  # the child ended without a result: its exit code says how
        proc.join(10.0)  # before the join, ``exitcode`` may still read None
        raise VrnError(died_message(mesh.name, len(mesh.faces), proc.exitcode)) from None
    finally:
        recv.close()
        if proc.is_alive():
            proc.kill()
        proc.join()
    if kind == "error":
        raise VrnError(payload)
    if kind == "crash":
        raise RuntimeError(f"{mesh.name}: xatlas unwrap failed: {payload}")
    return payload


#: signals of a crash inside xatlas itself (as opposed to being killed from outside)
CRASH_SIGNALS = ("SIGSEGV", "SIGBUS", "SIGABRT", "SIGILL", "SIGFPE")


def died_message(name: str, n_faces: int, exitcode: int | None) -> str:
    """One line for a child unwrap that ended without a result (``exitcode`` as
    :attr:`multiprocessing.Process.exitcode`: ``-N`` = killed by signal ``N``)."""
    what = f"{name} ({n_faces} triangles)"
    if exitcode is None:
        return f"{what}: the xatlas process closed its pipe without a result and did not end"
    if exitcode >= 0:
        return f"{what}: the xatlas process exited with code {exitcode} without sending a result"
    sig = -exitcode
    try:
        sig_name = signal.Signals(sig).name
    except ValueError:
        sig_name = "unknown signal"
    if sig_name in CRASH_SIGNALS:
        # Measured on the 81920-triangle icosphere of jpcy/xatlas#146: every --res from 64 to
        # 4096 crashes, and so do other chart options and a rotated copy; a copy with
        # vertices moved 1e-6 gives folded charts. build_atlas(atlas_uv="xatlas") recovers
        # (vrneural.atlas.generate); the default never runs xatlas.
        return (
            f"{what}: xatlas crashed ({sig_name}, signal {sig}), a known xatlas bug for some "
            "meshes such as finely subdivided icospheres (jpcy/xatlas#146); vrneural's own "
            "charts (atlas_uv = auto or charts) do not use xatlas"
        )
    if sig_name == "SIGKILL":
        return (
            f"{what}: the xatlas process was killed (SIGKILL, signal 9), most likely by the "
            "out-of-memory killer"
        )
    return f"{what}: the xatlas process was stopped by {sig_name} (signal {sig})"


def _child(conn, mesh: Mesh, resolution: int, padding: int, chart_options=None) -> None:
    """Child process: unwrap, send ``(kind, payload)``, exit without destroying xatlas objects."""
    # a crash inside xatlas is reported by the parent in one line (died_message); a
    # faulthandler inherited from the parent (pytest, python -X faulthandler) would add a
    # multi-line "Fatal Python error" dump to stderr first
    faulthandler.disable()
    keep: list = []  # every xatlas.Atlas, alive until os._exit
    try:
        msg = ("ok", _unwrap(mesh, resolution, padding, keep, chart_options))
    except VrnError as e:
        msg = ("error", str(e))
    except BaseException as e:  # reported to the parent, which raises
        msg = ("crash", f"{type(e).__name__}: {e}")
    try:
        conn.send(msg)
        conn.close()
    finally:
        os._exit(0)


def normalized_positions(positions) -> tuple[np.ndarray, float]:
    """``(positions / unit, unit)`` in float64 for xatlas (module docstring): a mesh whose
    bounding box is between a quarter and 16 units wide is left as it is (``unit`` = 1, so
    its atlas is bit for bit what it was); a smaller or larger one is scaled by a power of two
    (exact in floating point) to about 2 units wide, and one far from its own origin (more
    than 4 half-widths) is centred first."""
    pos = np.asarray(positions, dtype=np.float64)
    lo, hi = pos.min(0), pos.max(0)
    half = float(np.max(hi - lo)) / 2.0
    if not (half > 0 and np.isfinite(half) and np.isfinite(1.0 / half)):
        return pos, 1.0
    centre = (lo + hi) / 2.0
    if float(np.abs(centre).max()) > 4.0 * half:
        pos = pos - centre
    unit = 1.0 if 0.125 <= half <= 8.0 else 2.0 ** round(np.log2(half))
    return pos / unit, unit


def _unwrap(mesh: Mesh, resolution: int, padding: int, keep: list, chart_options=None):
    import xatlas

    # xatlas in units of the mesh's own size (module docstring: its absolute epsilons)
    pos64, unit = normalized_positions(mesh.positions)
    pos = np.ascontiguousarray(pos64, dtype=np.float32)
    faces = np.ascontiguousarray(mesh.faces, dtype=np.uint32)
    p = pos64[faces]
    area3d = float(np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum())
    area3d = max(area3d / 2.0, 1e-12)
    R = resolution
    tpu = R * np.sqrt(TARGET_FILL / area3d)
    atlas = xatlas.Atlas()
    keep.append(atlas)
    atlas.add_mesh(pos, faces)
    co = xatlas.ChartOptions()
    if len(faces) > FAST_FACES:
        co.max_chart_area = float(area3d * FACES_PER_CHART / len(faces))
        co.max_iterations = 0
    for k, v in (chart_options or {}).items():
        setattr(co, k, v)
    atlas.generate(co, _pack_options(tpu, padding))
    if int(atlas.atlas_count) == 0:  # atlas[0] would be an IndexError
        raise VrnError(
            f"{mesh.name}: xatlas made no charts: all {len(faces)} triangles are far smaller "
            "than the mesh's extent (several tiny parts far apart?); make them separate meshes"
        )
    vmap, idx, uv = atlas[0]
    if idx.shape != faces.shape or not np.array_equal(vmap[idx], faces):
        raise VrnError(f"{mesh.name}: xatlas changed the face list (degenerate input?)")
    charts = int(atlas.chart_count)
    W, H, count, util = (
        int(atlas.width),
        int(atlas.height),
        int(atlas.atlas_count),
        atlas.utilization,
    )
    chart_uv = None
    best = (uv, W, H, tpu, util) if count == 1 and max(W, H) <= R else None
    packs = 1
    while not (count == 1 and GOOD_FIT * R <= max(W, H) <= R) and packs < MAX_PACKS:
        if chart_uv is None:  # chart shapes in surface units, positions irrelevant
            chart_uv = (uv.astype(np.float64) * [W, H] / tpu).astype(np.float32)
        tpu *= 0.99 * R / max(W, H, 1)
        again = xatlas.Atlas()
        keep.append(again)
        again.add_uv_mesh(chart_uv, idx)
        again.generate(xatlas.ChartOptions(), _pack_options(tpu, padding))
        vm2, idx2, uv = again[0]
        if not (np.array_equal(vm2, np.arange(len(chart_uv))) and np.array_equal(idx2, idx)):
            raise VrnError(f"{mesh.name}: xatlas re-pack changed the vertices")
        packs += 1
        W, H, count = int(again.width), int(again.height), int(again.atlas_count)
        if count == 1 and max(W, H) <= R and (best is None or tpu > best[3]):
            best = (uv, W, H, tpu, again.utilization)
    if best is None:
        raise VrnError(
            f"{mesh.name}: xatlas could not pack {len(faces)} triangles into {R}x{R} texels "
            f"in {MAX_PACKS} tries; use a larger resolution"
        )
    uv, W, H, tpu, util = best
    scale = R / max(W, H)
    px = uv.astype(np.float64) * np.array([W, H]) * scale
    info = {
        "faces": idx.astype(np.int64),
        "charts": charts,
        "texels_per_unit": float(tpu * scale / unit),  # per metre (mesh unit), not per `unit`
        "packed_size": [W, H],
        "packs": packs,
        "xatlas_utilization": float(util),
    }
    return vmap.astype(np.int64), (px / R).astype(np.float32), info
