"""Point lights: position (m), colour (linear RGB), intensity ``I`` (W/sr), optional motion.

A point light contributes ``L = BTF(u, wi, wo) * colour * I / d^2`` (docs/conventions.md section 2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

MOTIONS = ("none", "circle")
#: Largest accepted ``colour * intensity`` (W/sr); shading sums in f32 and clamps to the f16
#: range before the rgba16float store (docs/extremes.md).
MAX_INTENSITY = 1e6


@dataclass
class PointLight:
    position: tuple  # metres, world (the circle's centre when moving)
    colour: tuple = (1.0, 1.0, 1.0)
    intensity: float = 1.0  # W/sr
    motion: str = "none"  # "none" | "circle" (horizontal circle about ``position``)
    radius: float = 0.0  # circle radius, metres
    period: float = 8.0  # seconds per revolution
    phase: float = 0.0  # radians at t = 0

    def at(self, t: float) -> np.ndarray:
        """World position ``[3]`` at time ``t`` (s)."""
        return np.array(self._at(t))

    def _at(self, t: float) -> tuple[float, float, float]:
        x, y, z = (float(v) for v in self.position)
        if self.motion == "circle":  # scalar math: called per light and frame
            a = self.phase + 2 * math.pi * t / self.period
            return x + self.radius * math.cos(a), y, z + self.radius * math.sin(a)
        return x, y, z

    @property
    def radiance(self) -> np.ndarray:
        """``colour * intensity`` ``[3]`` (W/sr)."""
        return np.asarray(self.colour, np.float64) * self.intensity


def light_arrays(lights: list[PointLight], t: float) -> tuple[np.ndarray, np.ndarray]:
    """``(positions [L, 3] float64, colour * intensity [L, 3] float32)`` at time ``t``.
    Positions stay float64 so that the renderer can make them camera-relative before they
    are rounded to f32 (a light 1e5 m from the origin would otherwise move in 7.8 mm steps)."""
    if not lights:
        return np.zeros((0, 3), np.float64), np.zeros((0, 3), np.float32)
    pos = np.array([lt._at(t) for lt in lights], np.float64)
    rgb = np.array([[float(c) * lt.intensity for c in lt.colour] for lt in lights], np.float32)
    return pos, rgb


def default_lights(n: int) -> list[PointLight]:
    """``n`` white-ish lights spread around the scene above head height, slowly circling."""
    cols = [(1.0, 0.95, 0.9), (0.8, 0.9, 1.0), (1.0, 0.85, 0.7), (0.9, 1.0, 0.9)]
    out = []
    for i in range(n):
        a = 2 * np.pi * i / max(n, 1)
        out.append(
            PointLight(
                (1.2 * np.cos(a), 2.2, 1.2 * np.sin(a)),
                cols[i % len(cols)],
                2.0,
                "circle",
                0.4,
                10.0 + 2 * i,
                a,
            )
        )
    return out
