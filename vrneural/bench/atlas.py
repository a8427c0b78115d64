"""`vrneural bench atlas`: the atlas stage over a fixed, generated mesh set
(:mod:`vrneural.bench.atlas_meshes`): time, peak memory, coverage, charts, triangles without a
texel, texel density spread, which UVs were used, and the seam error of a rendered Lambertian
image against ``--mode screen`` (:mod:`vrneural.bench.atlas_seams`).

Each mesh is generated, written to a file (PLY, or GLB for the one with lightmap UVs) and
loaded in one forked process, then atlased (no cache) in another that holds only the
interpreter, the mesh's arrays and the build, so its peak resident memory (``ru_maxrss``) is
the build's (the loading's peak is reported apart). Writes ``results.json``,
``results.md`` and ``atlases.png`` (every atlas, a colour per chart, gutter at half brightness).
"""

from __future__ import annotations

import dataclasses
import multiprocessing as mp
import os
import resource
import tempfile
import time
from pathlib import Path

import numpy as np

from vrneural.bench import report as rp
from vrneural.bench.atlas_meshes import RESOLUTION, write_mesh
from vrneural.bench.configs import AtlasBenchConfig
from vrneural.errors import check_range


def _resolution(name: str, quick: bool) -> int:
    if quick:
        return 256 if name in ("field", "knot") else 128
    return RESOLUTION.get(name, 1200)


def _rss_mb() -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def _load_child(name: str, folder: str, quick: bool):
    """Generate and load one mesh (``load_mesh``: trimesh, normals, tangents); keep the
    :class:`Mesh` arrays in ``folder/<name>.npz`` for the build process."""
    from vrneural.atlas import load_mesh

    t = time.perf_counter()
    path = write_mesh(name, Path(folder), quick)
    (mesh,) = load_mesh(path)
    load_s = time.perf_counter() - t
    arrays = {k: v for k, v in dataclasses.asdict(mesh).items() if isinstance(v, np.ndarray)}
    np.savez(Path(folder) / f"{name}.npz", **arrays)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    info = {"name": mesh.name, "uv_source": mesh.uv_source}
    return {"load_s": load_s, "load_peak_rss_mb": peak, **info}, None, str(path)


def _build_child(name: str, folder: str, res: int, loaded: dict):
    """Atlas the mesh of ``folder/<name>.npz`` (no cache); its stats and a preview. The
    process holds only the interpreter, the mesh arrays and the build: its peak resident
    memory is the build's."""
    from vrneural.atlas import Mesh, build_atlas
    from vrneural.atlas.visualize import atlas_image, gutter_mask

    with np.load(Path(folder) / f"{name}.npz") as z:
        arrays = {k: z[k] for k in z.files}
    mesh = Mesh(name=loaded["name"], uv_source=loaded["uv_source"], **arrays)
    rss0 = _rss_mb()
    atlas = build_atlas(mesh, res, 2, cache=False, progress=False)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    img = atlas_image(atlas, by="chart", gutter=gutter_mask(atlas))
    step = max(1, res // 320)
    rec = {
        **{k: v for k, v in atlas.stats.items() if k not in ("cache", "cache_file")},
        "mesh": name,
        "rss_before_mb": rss0,
        "peak_rss_mb": peak,
    }
    return rec, img[::step, ::step].copy(), None


def _child_main(conn, target, *args) -> None:
    """The forked process: send ``("ok", *target(*args))`` or the error, never hang."""
    try:
        conn.send(("ok", *target(*args)))
    except BaseException as e:  # reported, never a hang
        conn.send(("error", f"{type(e).__name__}: {e}", None, None))
    finally:
        conn.close()
        os._exit(0)


def _in_child(target, *args):
    ctx = mp.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child_main, args=(send, target, *args))
    proc.start()
    send.close()
    try:
        kind, rec, img, path = recv.recv()
    except EOFError:
        kind, rec, img, path = "error", f"the process died (exit code {proc.exitcode})", None, None
    proc.join()
    return kind, rec, img, path


def _measure(name: str, folder: Path, quick: bool, res: int):
    """``(kind, record, preview, mesh file)``: load in one process, build in another."""
    kind, loaded, _, path = _in_child(_load_child, name, str(folder), quick)
    if kind != "ok":
        return kind, loaded, None, None
    kind, rec, img, _ = _in_child(_build_child, name, str(folder), res, loaded)
    if kind == "ok":
        rec = {**rec, "file": Path(path).name, "load_s": loaded["load_s"]}
        rec["load_peak_rss_mb"] = loaded["load_peak_rss_mb"]
    return kind, rec, img, path


def run_atlas(cfg: AtlasBenchConfig) -> dict:
    c = cfg.resolved()
    check_range("--eye", c.eye, 16, 4096)
    with rp.prepare_out(cfg.out, cfg.force, "atlas") as root:
        t0 = time.perf_counter()
        records, previews, failures = [], {}, []
        from tqdm import tqdm

        with tempfile.TemporaryDirectory(prefix="vrneural-bench-atlas-") as tmp:
            old = os.environ.get("VRNEURAL_CACHE")
            os.environ["VRNEURAL_CACHE"] = str(Path(tmp) / "cache")  # the seam renders' atlases
            try:
                # every atlas first, each in a process forked from this small one (before any
                # render grows it: a child's peak includes what it inherits), then the renders
                bar = tqdm(c.meshes, desc="bench atlas", unit="mesh", disable=not c.progress)
                paths = {}
                for name in bar:
                    bar.set_postfix_str(name)
                    res = _resolution(name, c.quick)
                    kind, rec, img, path = _measure(name, Path(tmp), c.quick, res)
                    if kind != "ok":
                        failures.append(f"{name}: {rec}")
                        records.append({"mesh": name, "resolution": res, "error": rec})
                        continue
                    records.append(rec)
                    previews[name], paths[name] = img, path
                if c.seams:
                    from vrneural.bench.atlas_seams import seam_error

                    for rec in tqdm(records, desc="bench atlas seams", disable=not c.progress):
                        if rec["mesh"] in paths:
                            rec["seams"] = seam_error(paths[rec["mesh"]], rec["resolution"], c.eye)
            finally:
                if old is None:
                    os.environ.pop("VRNEURAL_CACHE", None)
                else:
                    os.environ["VRNEURAL_CACHE"] = old
        doc = rp.header("atlas", c)
        doc["records"] = records
        doc["failures"] = failures
        doc["total_seconds"] = time.perf_counter() - t0
        doc["load_avg_1m"] = os.getloadavg()[0]
        doc["cpu_count"] = os.cpu_count()
        _plot(previews, records, root / "atlases.png")
        from vrneural.bench.atlas_report import write_reports

        write_reports(root, doc, c)
        return doc


def _plot(previews: dict, records: list, path: Path) -> None:
    plt = rp.pyplot()

    n = max(len(previews), 1)
    cols = min(4, n)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.5 * rows), squeeze=False)
    by_name = {r["mesh"]: r for r in records}
    for ax in axes.ravel():
        ax.axis("off")
    for ax, (name, img) in zip(axes.ravel(), previews.items(), strict=False):
        r = by_name[name]
        ax.imshow(img, interpolation="nearest")
        ax.set_title(
            f"{name}: {r['triangles']} tris, {r['resolution']}^2\n"
            f"{r['coverage_pct']:.0f}% covered, {r['charts']} charts, {r['uv_source'][:18]}",
            fontsize=8,
        )
    fig.tight_layout()
    rp.save_png(fig, path, bbox=None)
