"""`synthesize(config)`: render a preset into a ``.btf`` file, streaming, resumable, seeded.

Memory stays bounded by one view (``[L, H, W, 3]`` float32) plus the tile's maps and the
shadow-height maps ``[L, N, N]``; slices go straight into the memory-mapped ``.partial`` file
through :class:`~vrneural.btf.format.BtfWriter`, and each finished view is recorded in its
sidecar, so an interrupted run continues with ``resume=True`` (the CLI's ``--resume``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

from vrneural.btf.config import BtfConfig
from vrneural.btf.dirs import direction_set
from vrneural.btf.format import BtfWriter
from vrneural.btf.heightfield import texel_height
from vrneural.btf.presets import PRESETS
from vrneural.config import config_dict
from vrneural.interrupt import Stop

GENERATOR = "vrneural.btf.synth v1"


def build_maps(cfg: BtfConfig):
    """The preset's tile at the configured grid size (seeded)."""
    rng = np.random.default_rng([cfg.seed, 1])
    return PRESETS[cfg.preset](rng, cfg.grid_size)


def subsamples(cfg: BtfConfig) -> np.ndarray:
    """Jittered sub-sample offsets ``[res, res, spp, 2]`` in texels, within ``[-0.5, 0.5)``.

    A square ``spp`` is stratified (one jittered sample per cell of a k x k grid)."""
    rng = np.random.default_rng([cfg.seed, 2])
    k = round(np.sqrt(cfg.spp))
    if k * k == cfg.spp:
        cells = (np.stack(np.meshgrid(np.arange(k), np.arange(k)), -1).reshape(-1, 2) + 0.0) / k
        jit = rng.random((cfg.res, cfg.res, cfg.spp, 2)) / k
        return (cells + jit - 0.5).astype(np.float64)
    return rng.random((cfg.res, cfg.res, cfg.spp, 2)) - 0.5


def synthesize(
    cfg: BtfConfig, out, resume: bool = False, progress: bool = True, force: bool = False
) -> Path:
    """Render ``cfg`` into ``out`` (a ``.btf``). Returns the path of the finished file.

    ``resume`` continues an interrupted ``<out>.partial`` of the same settings (other settings
    are an error unless ``force``, which starts over).

    Views are rendered one at a time (all lights per view); values are clamped into
    ``[0, 65504]`` (float16) and checked finite before they are written.
    """
    cfg.validate()
    from vrneural.btf.render import make_scene, render_view

    dirs = direction_set(cfg.dirs)
    meta = {
        "name": cfg.preset,
        # the config as given (grid 0 = auto), not resolved: the header's SHA-256 is part of
        # the BTF's identity in every teacher and student checkpoint, so it must not change
        # for the same data (tests/test_btf_cli.py pins it)
        "generator": {**config_dict(cfg), "tool": GENERATOR},
        "seed": cfg.seed,
    }
    # Ctrl-C or SIGTERM (also where a non-interactive shell started this in the background
    # with SIGINT ignored) stops after the current view; a second one at once. The handler is
    # in place before the .partial file appears, so a signal sent once it exists is never
    # missed
    with Stop() as stop:
        stop.second_raises = True
        maps = build_maps(cfg)
        height = texel_height(maps.height, cfg.res)  # the tile's relief travels with the data
        w = BtfWriter(
            out, dirs, dirs, (cfg.res, cfg.res), meta, resume=resume and not force, height=height
        )
        todo = [v for v in range(len(dirs)) if v not in w.done]
        if resume and w.done:
            print(f"{out}: resuming, {len(w.done)}/{len(dirs)} views already done", file=sys.stderr)
        with w.keep_on_interrupt(out):
            with tqdm(total=len(dirs), desc="shadow maps", unit="light", disable=not progress) as b:
                scene = make_scene(maps, dirs, b)
            del maps
            samples = subsamples(cfg)
            with tqdm(
                total=len(dirs),
                initial=len(w.done),
                desc=f"{cfg.preset} views",
                unit="view",
                disable=not progress,
            ) as bar:
                for v in todo:
                    if stop.flag:
                        raise KeyboardInterrupt
                    w.put_view(v, render_view(scene, dirs[v], samples, (cfg.res, cfg.res)))
                    bar.update(1)
    return w.finalize()
