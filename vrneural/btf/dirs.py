"""Direction sets in the local frame (z along the normal), as unit vectors ``[N, 3]`` float32.

``direction_set(151)`` is UBO2014's layout: rings at theta = 0, 11, 23.5, 30, 37.5, 45, 52.5, 60,
67.5, 75 degrees holding 1, 6, 12, 12, 12, 18, 18, 24, 24, 24 directions, evenly spaced in phi
(starting at phi = 0). Any other N gives N quasi-uniform directions (a Fibonacci spiral, uniform
in solid angle) over the same theta range [0, 75] degrees.
"""

from __future__ import annotations

import numpy as np

from vrneural.errors import check_range

UBO_THETA_DEG = (0.0, 11.0, 23.5, 30.0, 37.5, 45.0, 52.5, 60.0, 67.5, 75.0)
UBO_RING_COUNTS = (1, 6, 12, 12, 12, 18, 18, 24, 24, 24)
MAX_THETA_DEG = 75.0


def spherical(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Unit vectors ``[N, 3]`` from polar angle ``theta`` and azimuth ``phi`` (radians)."""
    st = np.sin(theta)
    return np.stack([st * np.cos(phi), st * np.sin(phi), np.cos(theta)], -1).astype(np.float32)


def ubo2014_directions() -> np.ndarray:
    """UBO2014's 151 directions ``[151, 3]``."""
    th, ph = [], []
    for t, n in zip(UBO_THETA_DEG, UBO_RING_COUNTS, strict=True):
        th += [np.radians(t)] * n
        ph += list(2 * np.pi * np.arange(n) / n)
    return spherical(np.array(th), np.array(ph))


def direction_set(n: int = 151) -> np.ndarray:
    """``[n, 3]`` directions: UBO2014's layout for 151, else a quasi-uniform spiral."""
    check_range("--dirs", n, 1, 100_000)
    if n == 151:
        return ubo2014_directions()
    cos_max = np.cos(np.radians(MAX_THETA_DEG))
    i = np.arange(n) + 0.5
    cos_t = 1.0 - (1.0 - cos_max) * i / n  # uniform in solid angle over the cap
    golden = np.pi * (3.0 - np.sqrt(5.0))
    return spherical(np.arccos(cos_t), golden * np.arange(n))
