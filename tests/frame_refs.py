"""Small frames rendered by the frame loop as it was before issue #41 (frames in flight,
single submit, fused texture-space kernel and compile-time light loop), and the configurations
that render them: ``tests/data/frames_before_41.npz`` holds, per configuration, every frame's
eyes (the ``rgba16float`` colour targets, raw) and counters. Rendered at 59801ef, main just
before #41 merged (first recorded at e90c611; again after #36 changed every atlas). The packs
have carried prefiltered pyramids since (#39), which the loop before did not know: the
configurations render with ``neural_lod=False``, level 0 alone, as it did, and with
``neural_filter="exact"``, the filter in the shader that the loop before had (the sampler's
filtering, the default since, is held to these frames in tests/test_neural_filter.py).

Regenerate only on purpose (the point is that they stay the old frames):
``python tests/frame_refs.py`` with the old code checked out.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

DATA = Path(__file__).parent / "data" / "frames_before_41.npz"
COUNTERS = ("updated_objects", "culled_objects", "blocks_shaded", "blocks_backfacing",
            "mlp_coarse", "mlp_fine", "pixels_shaded")  # fmt: skip


def configs() -> dict:
    """name -> (scene factory, Settings kwargs, frames, jitter, per-frame light scale)."""
    base = dict(eyes=2, reuse=2, schedule="staggered", texture_res=128, eye_res=(48, 40),
                n_lights=3, fov_y=96.0, neural_lod=False, neural_filter="exact")  # fmt: skip
    return {
        "texture": ("builtin", base, 4, None),
        "burst_f16": ("builtin", {**base, "schedule": "burst", "precision": "f16"}, 3, None),
        "shared_auto": ("builtin", {**base, "radiance": "shared", "reuse_budget": 0.2}, 4, None),
        "crop_jitter": ("builtin", {**base, "crop": (8, 6, 96, 80), "reuse": 0}, 2, (0.25, -0.3)),
        "screen": ("builtin", {**base, "mode": "screen"}, 2, None),
        "reference": ("builtin", {**base, "mode": "reference", "eyes": 1}, 1, None),
        "bench_1light": ("bench", {**base, "n_lights": 1, "reuse": 1}, 3, None),
        "no_lights": ("builtin", {**base, "n_lights": 0, "eyes": 1}, 1, None),
    }


def scene(kind: str, n_lights: int):
    from vrneural.bench.timing import bench_scene
    from vrneural.runtime.scene import builtin_scene

    return builtin_scene(max(n_lights, 0)) if kind == "builtin" else bench_scene(n_lights)


def render(name: str, wait=None, frames: int | None = None, **overrides) -> tuple:
    """Frames of configuration ``name``: eyes ``[F, E, H, W, 4]`` float16 (raw colour targets)
    and counters ``[F, 7]`` int64 (:data:`COUNTERS`). ``wait(renderer)``: called before the
    stats are read (the new frame loop's stats arrive later); ``frames``: that many instead of
    the configuration's; ``overrides``: Settings fields set on top of the configuration's."""
    from vrneural.runtime.renderer import Renderer, Settings

    kind, kw, n_frames, jitter = configs()[name]
    frames = frames or n_frames
    kw = {**kw, **overrides}
    s = Settings(
        **{k: v for k, v in kw.items() if k in {f.name for f in dataclasses.fields(Settings)}}
    )
    r = Renderer(scene(kind, s.n_lights), s)
    if jitter is not None:
        r.jitter = jitter
    imgs, stats = [], []
    for f in range(frames):
        stats.append(r.frame(f))
        imgs.append(np.stack(r._read_colour()))  # each eye's raw colour target
    if wait is not None:
        wait(r)
    cnt = np.array([[getattr(st, k) for k in COUNTERS] for st in stats], np.int64)
    return np.stack(imgs), cnt


def main() -> None:
    out = {}
    for name in configs():
        imgs, cnt = render(name)
        out[f"{name}/eyes"], out[f"{name}/counters"] = imgs, cnt
        print(name, imgs.shape, cnt.tolist())
    DATA.parent.mkdir(exist_ok=True)
    np.savez_compressed(DATA, **out)
    print(DATA, DATA.stat().st_size)


if __name__ == "__main__":
    main()
