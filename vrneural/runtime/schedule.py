"""Reuse schedules: which radiance-texture blocks are updated at display frame ``f``.

With reuse ``N`` every ``N + 1`` frames share one full update of each radiance texture.

``burst`` (the paper): frame ``f`` updates everything when ``f % (N + 1) == 0``, nothing
otherwise, so one frame in ``N + 1`` carries the whole cost.
``staggered``: frame ``f`` updates the block rows ``by`` with ``by % (N + 1) == f % (N + 1)``
(interleaved rows of 2x2 blocks), so every frame carries about ``1 / (N + 1)`` of it and each
block is still updated exactly once per ``N + 1`` frames.

Either way the renderer gives an object one full update the first time it is seen (and again
when it comes back into view after being culled), so no frame shows an unfilled texture.
"""

from __future__ import annotations

from dataclasses import dataclass

SCHEDULES = ("burst", "staggered")


@dataclass(frozen=True)
class Slice:
    """The part of the texture updated at one frame: block rows ``phase::period``."""

    update: bool
    phase: int = 0
    period: int = 1


def frame_slice(frame: int, reuse: int, schedule: str) -> Slice:
    """What frame ``frame`` updates under ``schedule`` with reuse ``N = reuse``."""
    n1 = reuse + 1
    if schedule == "burst" or n1 == 1:
        return Slice(frame % n1 == 0, 0, 1)
    if schedule == "staggered":
        return Slice(True, frame % n1, n1)
    raise ValueError(f"schedule {schedule!r} not in {SCHEDULES}")
