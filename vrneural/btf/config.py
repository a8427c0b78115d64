"""``BtfConfig`` and ``RenderConfig``: what `vrneural btf synth` and `btf render` take (each
field's help is its --help line); a light module (the CLI's parser imports it, not the stage)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from vrneural.config import opt
from vrneural.errors import VrnError, check_choice, check_range, check_seed

#: the keys of :data:`vrneural.btf.presets.PRESETS` (sorted) and of
#: :data:`vrneural.btf.pt_presets.PT_PRESETS` (in its order; a test checks both)
PRESET_NAMES = ("carpet", "fabric", "leather", "metal", "stone", "wood")
PT_PRESET_NAMES = ("weave", "pebbles", "fur", "bark", "mosaic", "berber")


@dataclass
class BtfConfig:
    """Synthetic BTF generation (`vrneural btf synth`)."""

    preset: str = opt("leather", "material preset: " + ", ".join(PRESET_NAMES))
    res: int = opt(64, "texels per side (the tile is res x res)")
    dirs: int = opt(151, "light and view directions (151 = UBO2014 layout, else quasi-uniform)")
    seed: int = opt(0, "random seed (same seed, same bytes on one machine)")
    spp: int = opt(4, "jittered sub-samples per texel (a square number is stratified)")
    grid: int = opt(
        0, "heightfield grid size N per side, 8 to 4096 (0 = 2 x res clamped to [64, 512])"
    )

    def validate(self, flags: dict[str, str] | None = None) -> None:
        """One-line :class:`VrnError` on a bad field, named ``--FIELD`` or as ``flags`` maps it
        (a command that synthesises under other flag names: ``{"res": "--btf-res"}``)."""
        f = {k: f"--{k}" for k in ("preset", "res", "dirs", "spp", "seed", "grid")} | (flags or {})
        check_choice(f["preset"], self.preset, list(PRESET_NAMES))
        check_range(f["res"], self.res, 2, 4096)
        if self.res % 2:  # the networks work on 2x2 texel blocks (teach/distill need it)
            raise VrnError(f"{f['res']} = {self.res} must be even (training uses 2x2 texel blocks)")
        # at least 2 x 2 (light, view) pairs: one can be held out for the test L1
        check_range(f["dirs"], self.dirs, 2, 100_000)
        check_range(f["spp"], self.spp, 1, 256)
        check_seed(f["seed"], self.seed)
        if self.grid != 0 and not 8 <= self.grid <= 4096:
            raise VrnError(
                f"{f['grid']} = {self.grid} is out of range; allowed 0 (auto) or [8, 4096]"
            )

    @property
    def grid_size(self) -> int:
        return self.grid or int(min(512, max(64, 2 * self.res)))

    def resolved(self) -> BtfConfig:
        """The config as rendered (``grid`` 0 replaced by the size used), as the sidecar has it."""
        return dataclasses.replace(self, grid=self.grid_size)


#: Monte Carlo samplers of `btf render` (Mitsuba plugins): multi-jittered (the default: on
#: the five presets its noise at 64 samples is 1.3-2.6x lower than the independent sampler's,
#: docs/quality-research.md) and independent (any sample count)
SAMPLERS = ("multijitter", "independent")
#: what a header or an interrupted render written before a field existed used
RENDER_BEFORE = {"sampler": "independent"}


def jitter_grid(n: int) -> int:
    """The sample count Mitsuba's multi-jittered sampler makes of ``n``: a grid of
    ``a x ceil(n / a)``, ``a = floor(sqrt(n))`` (64 -> 8 x 8; 128 -> 11 x 12 = 132)."""
    a = max(1, math.isqrt(n))
    return a * -(-n // a)


@dataclass
class RenderConfig:
    """Path-traced BTF (`vrneural btf render`)."""

    preset: str = opt("weave", "material preset: " + ", ".join(PT_PRESET_NAMES))
    res: int = opt(64, "texels per side (the tile is res x res)")
    dirs: int = opt(24, "light and view directions (151 = UBO2014 layout, else quasi-uniform)")
    seed: int = opt(0, "seed of the material: its geometry and colours")
    spp: int = opt(64, "Monte Carlo samples per texel and slice")
    sample_seed: int = opt(
        0,
        "seed of the Monte Carlo samples (another value: an independent render of the same "
        "material, for the noise floor)",
    )
    sampler: str = opt(
        "multijitter",
        "Monte Carlo sampler: multijitter (stratified; --spp must be a grid a x ceil(spp/a), "
        "a = floor(sqrt(spp)), e.g. a square) or independent (any --spp)",
        choices=SAMPLERS,
    )
    bounces: int = opt(5, "surface interactions per light path (1 = direct light only)")
    height_grid: int = opt(
        0,
        "height field size N stored in the file, for parallax: 0 = auto (2 x res up to res "
        "256, else res), or a whole multiple of --res up to 4096 (its cells nest in the texels)",
    )

    def validate(self) -> None:
        """One-line :class:`VrnError` on a bad field, named by its flag."""
        check_choice("preset", self.preset, list(PT_PRESET_NAMES))
        check_range("--res", self.res, 2, 4096)
        if self.res % 2:
            raise VrnError(f"--res = {self.res} must be even (training uses 2x2 texel blocks)")
        check_range("--dirs", self.dirs, 2, 100_000)
        check_range("--spp", self.spp, 1, 1 << 20)
        check_choice("--sampler", self.sampler, list(SAMPLERS))
        if self.sampler == "multijitter" and jitter_grid(self.spp) != self.spp:
            below = next(m for m in range(self.spp - 1, 0, -1) if jitter_grid(m) == m)
            raise VrnError(
                f"--spp = {self.spp}: the multi-jittered sampler takes a grid of a x ceil(spp / "
                f"a) samples, a = floor(sqrt(spp)); nearest {below} or {jitter_grid(self.spp)}, "
                "or pass --sampler independent"
            )
        check_seed("--seed", self.seed)
        check_seed("--sample-seed", self.sample_seed)
        check_range("--bounces", self.bounces, 1, 64)
        if self.height_grid != 0 and not 2 <= self.height_grid <= 4096:
            raise VrnError(
                f"--height-grid = {self.height_grid} is out of range; allowed 0 (auto) or [2, 4096]"
            )
        if self.height_grid % self.res:  # parallax box-averages it onto the texels
            raise VrnError(
                f"--height-grid = {self.height_grid} does not nest in the {self.res}x{self.res} "
                f"texels: parallax could not use it; give 0 (auto) or a whole multiple of --res "
                f"({', '.join(str(k * self.res) for k in range(1, 4) if k * self.res <= 4096)})"
            )

    @property
    def grid_size(self) -> int:
        """The height field's size: ``height_grid``, or 2 x res (up to res 256: at most 512,
        as before) and res itself above that, so the grid always nests in the texels."""
        return self.height_grid or (2 * self.res if self.res <= 256 else self.res)
