"""The viewer's live knobs and the renderers behind them.

Every knob of `vrneural run` is here. ``reuse`` and ``schedule`` are read by the renderer every
frame, so they change in place; ``mode``, ``precision`` and ``texture_res`` change the shaders
or the atlases, so they select another :class:`~vrneural.runtime.renderer.Renderer`, built
through the same :func:`~vrneural.runtime.config.resolve` as `run` (same checks, same
messages) and kept in a small cache. Lights are switched off by giving them zero intensity
(the shaders' light count stays, so a switch is instant and costs the same GPU time).
"""

from __future__ import annotations

import dataclasses
import time
from collections import OrderedDict
from dataclasses import dataclass, field

from vrneural.atlas.config import MIN_RESOLUTION
from vrneural.runtime.config import REUSE_MAX, max_texture_res, resolve
from vrneural.runtime.settings import MODES

#: renderers kept (the active one, the split view's reference, the one before)
CACHE = 3


@dataclass
class Live:
    """What the keys change. ``lights_on[k]``: light k shaded; ``selected``: the light the
    right mouse button drags."""

    mode: str
    reuse: int
    schedule: str
    precision: str  # resolved: f32 | f16
    texture_res: int
    texture_res_given: bool = False
    radiance: str = "per-eye"  # per-eye | shared
    adaptive: bool = False  # reuse auto (budget: the command line's --reuse-budget)
    lights_on: list = field(default_factory=list)
    selected: int = 0
    split: str = "off"
    hud: bool = True
    help: bool = False
    paused: bool = False
    follow_head: bool = False

    def key(self, mode: str | None = None) -> tuple:
        """What selects a renderer: (mode, precision, texture side, its origin, radiance)."""
        mode = mode or self.mode
        precision = "f32" if mode == "reference" else self.precision
        radiance = self.radiance if mode == "texture" else "per-eye"
        return (mode, precision, self.texture_res, self.texture_res_given, radiance)

    def settings_dict(self) -> dict:
        return dataclasses.asdict(self)


class Renderers:
    """Builds and caches renderers for :class:`Live` settings on one scene."""

    def __init__(self, scene, cfg, adapter, progress=None):
        self.scene, self.cfg, self.adapter = scene, cfg, adapter
        self.cache: OrderedDict = OrderedDict()
        self.build_s: dict = {}  # key -> seconds its construction took
        self.progress = progress
        #: the adaptive-reuse budget (degrees) the `U` key switches on: --reuse-budget
        self.budget = float(getattr(cfg, "reuse_budget", 2.0))

    def settings(self, live: Live, mode: str | None = None):
        """Resolved :class:`~vrneural.runtime.renderer.Settings` for ``live`` (in ``mode``)."""
        mode = mode or live.mode
        cfg = dataclasses.replace(
            self.cfg,
            mode=mode,
            reuse=live.reuse,
            schedule=live.schedule,
            precision="auto" if mode == "reference" else live.precision,
            texture_res=live.texture_res if live.texture_res_given else None,
            reference=self.cfg.reference if mode == "reference" else None,
            radiance=live.radiance if mode == "texture" else "per-eye",
        )
        return resolve(cfg, self.scene, self.adapter)

    def get(self, live: Live, mode: str | None = None):
        """``(renderer, fresh)`` for ``live`` in ``mode`` (default ``live.mode``); ``fresh``:
        built or taken up again now (its radiance textures are then updated in full)."""
        from vrneural.runtime.renderer import Renderer

        key = live.key(mode)
        if key in self.cache:
            self.cache.move_to_end(key)
            return self.cache[key], False
        t0 = time.perf_counter()
        if self.progress:
            self.progress(f"building the {key[0]} renderer ({key[1]}, {key[2]}^2)")
        r = Renderer(self.scene, self.settings(live, mode))
        self.build_s[key] = time.perf_counter() - t0
        if self.progress:
            self.progress(
                f"built the {key[0]} renderer ({key[1]}, {key[2]}^2) in {self.build_s[key]:.1f} s"
            )
        self.cache[key] = r
        while len(self.cache) > CACHE:
            self.cache.popitem(last=False)
        return r, True


def cycle(value, options):
    """The option after ``value`` in ``options`` (wrapping)."""
    options = tuple(options)
    return options[(options.index(value) + 1) % len(options)] if value in options else options[0]


def step_reuse(live: Live, delta: int) -> None:
    live.reuse = int(min(max(live.reuse + delta, 0), REUSE_MAX))


def step_texture(live: Live, up: bool, adapter) -> None:
    """Double or halve the radiance texture side (even, within the atlas and adapter bounds)."""
    r = live.texture_res * 2 if up else live.texture_res // 2
    r = min(max(r, MIN_RESOLUTION), max_texture_res(adapter))
    live.texture_res = r - r % 2
    live.texture_res_given = True


def next_mode(live: Live) -> str:
    return cycle(live.mode, MODES)
