"""What the renderer keeps of each neural object: its atlases, GPU buffers, render targets
per eye, bounding sphere and adaptive-reuse state."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from vrneural.runtime.adaptive import AdaptiveState
from vrneural.runtime.gpu_material import GpuAtlas


@dataclass
class NeuralObject:
    idx: int
    desc: object
    atlas: object
    gatlas: GpuAtlas
    centre: np.ndarray  # object-space bounding sphere
    radius: float
    targets: list = field(default_factory=list)  # per eye: TextureTarget | ScreenTarget
    fresh: bool = False  # its radiance textures hold a complete update since it was last culled
    adapt: AdaptiveState = field(default_factory=AdaptiveState)  # --reuse auto
    draw: object = None  # fw.DrawObject of the atlas in use
    #: resolution levels (screen_res): side -> (atlas, GpuAtlas, DrawObject, targets), built
    #: lazily; the one in use is also in atlas, gatlas, draw and targets
    levels: dict = field(default_factory=dict)
    level_sides: tuple = ()  # the sides it may use, largest first (its own side first)
    area: float = 0.0  # mesh surface, object space, m^2
    #: the neural-texture footprint's scale at its last update: the pixel over the atlas texel
    #: where the level's texel is the smaller (screen_res with lod_footprint "pixel"), else 1
    lod_scale: float = 1.0
    sphere: tuple = (None, None, 0.0, None)  # (model bytes, world centre, radius, [c, 1]): cache


def bounding_sphere(mesh) -> tuple[np.ndarray, float]:
    lo, hi = mesh.positions.min(0), mesh.positions.max(0)
    c = (lo + hi) / 2
    return c.astype(np.float64), float(np.linalg.norm(mesh.positions - c, axis=1).max())
