"""Adaptive reuse (``--reuse auto``): update an object's radiance textures when what it was shaded
for has changed enough, not every ``N + 1`` frames.

A radiance texture goes stale only through the *directions* it was shaded with: texture space
follows the geometry exactly (a head turn moves nothing in it), but ``wo`` changes when the eye
moves and ``wi`` when a light (or the object) moves. Per object and frame the policy measures, in
the object's frame (so a moving object counts too), how far the view direction (object centre ->
centre eye) and each light direction (object centre -> light) have turned since the object's
last update started. A direction seen from the centre turns less than from the object's nearest
surface, which is what shows, so each angle is scaled by ``d / (d - r)`` (``d``: distance to the
centre, ``r``: bounding radius; at most 10x). Objects that cover little of the view tolerate more:
the budget grows as ``sqrt(COVERAGE_REF / coverage)``, at most ``COVERAGE_MAX_SLACK`` x.

When the largest scaled angle reaches the budget (degrees), a refresh starts. It is staggered like
the ``staggered`` schedule: over ``P`` frames, block rows ``phase::P`` one frame at a time, with
``P = floor(budget / rate)`` for the current per-frame rate (so the sweep ends before the
staleness doubles), between 1 and ``p_max``. With ``burst`` every refresh is one full update
(``P = 1``). An object at rest is never updated again: the work follows the motion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vrneural.runtime.schedule import Slice

#: coverage (fraction of the eye's image) below which an object's budget starts to grow
COVERAGE_REF = 0.05
#: the largest factor the budget grows by for small objects
COVERAGE_MAX_SLACK = 4.0
#: the largest near-surface scale of an angle, d / (d - r)
NEAR_SCALE_MAX = 10.0


def object_directions(model: np.ndarray, centre: np.ndarray, eye, lights) -> np.ndarray:
    """Unit directions ``[1 + L, 3]`` in the object's frame (model's rotation and scale removed)
    from its centre (object space) to the eye and to each light ``lights: [L, 3]`` (world)."""
    m = np.asarray(model, np.float64)
    c = m[:3, :3] @ centre + m[:3, 3]
    inv = np.linalg.inv(m[:3, :3])
    pts = np.vstack([np.reshape(eye, (1, 3)), np.reshape(lights, (-1, 3))]).astype(np.float64)
    v = (pts - c) @ inv.T
    return v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-12)


def near_scale(model, centre, radius: float, points) -> np.ndarray:
    """``d / (d - r)`` per point ``[K, 3]`` (world), at most :data:`NEAR_SCALE_MAX`."""
    m = np.asarray(model, np.float64)
    c = m[:3, :3] @ centre + m[:3, 3]
    r = radius * float(np.linalg.norm(m[:3, :3], axis=0).max())
    d = np.linalg.norm(np.reshape(points, (-1, 3)) - c, axis=1)
    return np.minimum(d / np.maximum(d - r, d / NEAR_SCALE_MAX), NEAR_SCALE_MAX)


def turned(a: np.ndarray, b: np.ndarray, scale: np.ndarray) -> float:
    """The largest angle (degrees) between matching rows of unit ``a, b: [K, 3]``, each
    multiplied by ``scale: [K]``."""
    cos = np.clip((a * b).sum(1), -1.0, 1.0)
    return float((np.degrees(np.arccos(cos)) * scale).max())


def coverage_slack(coverage: float) -> float:
    """The budget's factor for an object covering ``coverage`` of the view."""
    c = max(float(coverage), 1e-9)
    return float(np.clip(np.sqrt(COVERAGE_REF / c), 1.0, COVERAGE_MAX_SLACK))


@dataclass
class AdaptiveState:
    """One object's reuse state: the directions its running or last refresh started from, the
    previous frame's directions (for the rate) and the sweep in progress."""

    ref: np.ndarray | None = None  # [1 + L, 3] at the start of the last refresh
    last: np.ndarray | None = None  # [1 + L, 3] at the previous frame
    period: int = 1
    phase: int = 0  # the next phase of the sweep

    def restart(self, dirs: np.ndarray) -> None:
        """A full update was just made from ``dirs`` (first sight, back in view)."""
        self.ref, self.last, self.phase, self.period = dirs, dirs, 0, 1

    def step(
        self, dirs: np.ndarray, scale: np.ndarray, budget: float, p_max: int, staggered: bool
    ) -> Slice:
        """This frame's slice for an object seen with ``dirs`` (``scale``: :func:`near_scale`
        of the eye and lights), refreshing when it has turned by ``budget`` degrees."""
        if self.ref is None:  # switched to adaptive reuse while running: refresh from here
            self.restart(dirs)
            return Slice(True, 0, 1)
        prev = self.last if self.last is not None else dirs
        self.last = dirs
        if self.phase > 0:  # a sweep in progress: its next rows
            s = Slice(True, self.phase, self.period)
            self.phase = (self.phase + 1) % self.period
            return s
        if turned(dirs, self.ref, scale) < budget:
            return Slice(False)
        rate = turned(dirs, prev, scale)
        period = int(np.clip(np.floor(budget / max(rate, 1e-9)), 1, p_max)) if staggered else 1
        self.ref, self.period, self.phase = dirs, period, 1 % period
        return Slice(True, 0, period)
