"""Radiance-texture resolution from the screen (``Settings.screen_res``): an object far away is
shaded at a smaller side, so its shading follows its size in the image, not the profile's.

An object's side (a *level*) is chosen among its own side (the profile's, the scene's or
``--texture-res``: the cap) and the powers of two below it, down to :data:`MIN_SIDE`: the
smallest level that still gives about one atlas texel per pixel where the object is nearest the
eye. A texel covers ``area / (coverage * R^2)`` of the surface (``area``: the mesh's surface,
``coverage``: the atlas's share of texels that hold a triangle); a pixel at distance ``d`` covers
``(d * fov_y / eye_height)^2``, so ``R = sqrt(area / coverage) / (d * fov_y / eye_height)``.

Hysteresis: an object moves to a larger level as soon as it needs one (no detail is lost), but
to a smaller one only when that level would still give ``1 / DOWN_MARGIN`` (1.25) texels per
pixel, so one hovering at a boundary does not flip back and forth. A level the object moves to
is given one full update before it is shown (as on first sight): no frame shows an unfilled
texture. Both eyes use one level (their distances differ by a few centimetres at most).
"""

from __future__ import annotations

import numpy as np

#: the smallest side a level may have
MIN_SIDE = 16
#: a smaller level is taken only when it needs at most this share of its texels
DOWN_MARGIN = 0.8


def level_sides(cap: int) -> tuple[int, ...]:
    """``cap`` and the powers of two below it down to :data:`MIN_SIDE`, largest first."""
    out = [int(cap)]
    p = 1 << (int(cap) - 1).bit_length()  # the power of two at or above cap
    while p >= MIN_SIDE:
        if p < cap:
            out.append(p)
        p //= 2
    return tuple(out)


def mesh_area(mesh) -> float:
    """Surface area of a mesh, in its own units squared."""
    p = mesh.positions.astype(np.float64)
    f = mesh.faces.astype(np.int64)
    return float(np.linalg.norm(np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]]),
                                axis=1).sum() / 2)  # fmt: skip


def wanted_side(area_world: float, coverage: float, distance: float, fov_y: float,
                eye_height: int) -> float:  # fmt: skip
    """The side giving one texel per pixel at ``distance`` (metres; see the module
    docstring). ``coverage``: the atlas's share of covered texels, in (0, 1]."""
    pixel = max(distance, 1e-3) * np.radians(fov_y) / eye_height
    return float(np.sqrt(area_world / max(coverage, 1e-3)) / pixel)


def choose(sides: tuple[int, ...], current: int, want: float) -> int:
    """The level for an object that wants ``want`` texels per side, now at ``current``."""
    fits = [s for s in sides if s >= want]
    best = min(fits) if fits else max(sides)
    if best >= current:
        return best  # up at once (or stay)
    # down only where the smaller level keeps a margin
    margin = [s for s in sides if s >= want / DOWN_MARGIN and s < current]
    return min(margin) if margin else current
