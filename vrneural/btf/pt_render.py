"""`render_btf(config)`: path-trace a preset into a ``.btf`` file with Mitsuba 3, streaming,
resumable, seeded (`vrneural btf render`).

As `btf synth` (:mod:`vrneural.btf.synth`): slices go straight into the memory-mapped
``<out>.partial`` through :class:`~vrneural.btf.format.BtfWriter`, each finished view (all its
lights) is recorded in the sidecar, Ctrl-C or SIGTERM stops at the current slice (the
unfinished view is rendered again by ``--resume``; a slice during which the signal came is
dropped, since Mitsuba stops its render on SIGINT and returns the image part-filled), and
``--resume`` with other settings is an error naming them. The file also carries the tile's
height field (format version 2).

``seed`` fixes the material (its geometry and colours); ``sample_seed`` fixes the Monte Carlo
samples. Two renders that differ only in ``sample_seed`` differ only by noise: their L1
distance is the noise floor under which no method can be judged.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from vrneural.btf import pathtrace as pt
from vrneural.btf.config import RENDER_BEFORE, RenderConfig
from vrneural.btf.dirs import MAX_THETA_DEG, direction_set
from vrneural.btf.format import BtfWriter, read_btf
from vrneural.btf.pt_presets import PT_PRESETS
from vrneural.config import config_dict
from vrneural.errors import VrnError
from vrneural.formats.f16 import F16_MAX
from vrneural.interrupt import Stop

GENERATOR = "vrneural.btf.pt_render v1 (Mitsuba 3)"


def build(cfg: RenderConfig):
    """The preset's scene (Mitsuba loaded, tile copies around it) and its height field
    ``[N, N]`` relative to the reference plane (whose height is set on the scene)."""
    pt.load_mitsuba()
    tile = PT_PRESETS[cfg.preset](np.random.default_rng([cfg.seed, 1]))
    zmin, zmax = tile.bounds()
    ring = pt.copy_ring(zmax - zmin, MAX_THETA_DEG)
    ps = pt.build_scene(tile, cfg.bounces, ring)
    h = pt.height_field(ps, cfg.grid_size)
    ps.z_ref = float(h.astype(np.float64).mean())
    return ps, (h - ps.z_ref).astype(np.float32), tile


def render_btf(
    cfg: RenderConfig, out, resume: bool = False, progress: bool = True, force: bool = False
) -> Path:
    """Render ``cfg`` into ``out`` (a ``.btf``); returns the finished file's path.

    ``resume`` continues an interrupted ``<out>.partial`` of the same settings (other
    settings are an error unless ``force``, which starts over). Views are written one at a
    time (all lights per view); values are checked finite and clamped into [0, 65504].
    """
    cfg.validate()
    pt.load_mitsuba()  # before any output: a one-line error when it is not installed
    dirs = direction_set(cfg.dirs)
    L = V = len(dirs)
    meta = {
        "name": cfg.preset,
        "generator": {**config_dict(cfg), "tool": GENERATOR, "mitsuba_variant": pt.VARIANT},
        "seed": cfg.seed,
        "reference_plane": "mean height of the top surface seen from above (z = 0 of height)",
    }
    with Stop() as stop:
        stop.second_raises = True
        ps, height, tile = build(cfg)
        meta["generator"]["scene"] = tile.fingerprint()  # resuming checks it: same material
        meta["about"] = tile.about
        meta["triangles"] = tile.triangles()
        meta["tile_copies"] = (2 * ps.ring + 1) ** 2
        if stop.flag:
            raise KeyboardInterrupt
        w = BtfWriter(
            out, dirs, dirs, (cfg.res, cfg.res), meta, resume=resume and not force, height=height
        )
        todo = [v for v in range(V) if v not in w.done]
        if resume and w.done:
            print(f"{out}: resuming, {len(w.done)}/{V} views already done", file=sys.stderr)
        with (
            w.keep_on_interrupt(out),
            tqdm(
                total=L * V,
                initial=len(w.done) * L,
                desc=f"{cfg.preset} slices",
                unit="slice",
                disable=not progress,
            ) as bar,
        ):
            for v in todo:
                cam = pt.sensor(ps, dirs[v], cfg.res, cfg.spp, cfg.sampler)
                view = np.empty((L, cfg.res, cfg.res, 3), np.float32)
                for li in range(L):
                    if stop.flag:
                        raise KeyboardInterrupt
                    seed = pt.slice_seed(cfg.sample_seed, li, v)
                    view[li] = pt.render_slice(ps, cam, dirs[li], cfg.spp, seed)
                    if stop.flag:  # Mitsuba cuts its render short on SIGINT and returns the
                        raise KeyboardInterrupt  # image part-filled: drop the slice and view
                    bar.update(1)
                w.put_view(v, view)
    return w.finalize()


def noise_floor(path, views: int = 6, progress: bool = True) -> dict:
    """The Monte Carlo noise of a rendered BTF: ``views`` evenly spaced views (all lights) of
    the file at ``path`` rendered again with the next ``sample_seed`` (same material, same
    settings), and the L1 between the two (mean |a - b| over those slices, texels and
    channels, linear BTF units). Two independent renders differ by about sqrt(2) times each
    one's distance to the converged image, so ``l1_vs_converged`` is ``l1 / sqrt(2)``.
    Returns ``{"file", "views", "l1", "l1_vs_converged", "mean", "relative", "seconds"}``."""
    btf = read_btf(path)
    gen = dict(btf.meta.get("generator") or {})
    if gen.get("config") != "RenderConfig":
        raise VrnError(f"{path}: not made by btf render (no RenderConfig in its header)")
    fields = {f.name for f in dataclasses.fields(RenderConfig)}
    cfg = RenderConfig(**{k: v for k, v in (RENDER_BEFORE | gen).items() if k in fields})
    cfg = dataclasses.replace(cfg, sample_seed=cfg.sample_seed + 1)
    t0 = time.perf_counter()
    ps, _, tile = build(cfg)
    scene = tile.fingerprint()
    if gen.get("scene") not in (None, scene):
        raise VrnError(
            f"{path}: the preset {cfg.preset!r} built here is not the material rendered there "
            f"(scene fingerprint {scene}, the file's {gen['scene']}): a variant "
            "or another version of the preset; measure it with the code that rendered it"
        )
    dirs = direction_set(cfg.dirs)
    pick = np.unique(np.linspace(0, len(dirs) - 1, min(views, len(dirs))).round().astype(int))
    diff = total = 0.0
    n = 0
    with tqdm(total=len(pick) * len(dirs), desc="noise", disable=not progress) as bar:
        for v in pick:
            cam = pt.sensor(ps, dirs[v], cfg.res, cfg.spp, cfg.sampler)
            for li in range(len(dirs)):
                seed = pt.slice_seed(cfg.sample_seed, li, int(v))
                b = pt.render_slice(ps, cam, dirs[li], cfg.spp, seed)
                b = np.clip(b, 0, F16_MAX).astype(np.float16).astype(np.float64)
                a = np.asarray(btf.values[li, v], np.float64)
                diff += float(np.abs(a - b).sum())
                total += float(a.sum())
                n += a.size
                bar.update(1)
    l1 = diff / n
    return {
        "file": str(path),
        "preset": cfg.preset,
        "spp": cfg.spp,
        "sampler": cfg.sampler,
        "views": [int(v) for v in pick],
        "l1": l1,
        "l1_vs_converged": l1 / np.sqrt(2.0),
        "mean": total / n,
        "relative": l1 / max(total / n, 1e-12),
        "seconds": time.perf_counter() - t0,
    }
