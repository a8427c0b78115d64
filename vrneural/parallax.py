"""Height-field parallax (numpy only): where a view ray meets the relief of a BTF's tile.

A BTF slice is rectified on its reference plane (``vrneural.btf.format``: the height field's
mean, height 0): texel ``(x, y)`` of view ``wo`` shows the surface point that the ray towards
``-wo`` through the plane at material UV ``u`` hits first. Above the plane at height ``z`` (UV
units: fractions of the tile width) that ray is at ``u + z * d`` with ``d = (wo.x / wo.z,
wo.y / wo.z * W / H)`` (local x = material u, y = v). A neural texture looked up at ``u`` sees
one texel for every view; looked up where the ray meets the relief it can stay put under the
view's shift, which a texel-local network cannot model (issue #44).

:func:`parallax_uv` is parallax-occlusion mapping: the ray is marched from the field's maximum
``hmax`` down to its minimum ``hmin`` in ``n`` equal steps; at the first sample at or below the
field it is intersected with the line between that sample and the one before (the classic
linear refinement). ``n`` follows the view (:func:`step_count`): the pack's ``steps`` at the
steepest view of the data, proportionally fewer where the ray crosses fewer texels (the same
texels per step at every angle). The march runs per texel (``march = "texel"``) or once per
2x2 block at its mean UV, the block's 4 lookups shifted alike (``"block"``: a quarter of the
height lookups; in the texture-space pass a block is 2x2 radiance texels, usually a fraction
of a material texel, and the renderer's default ``"auto"`` marches once per block exactly
there: :func:`auto_blocks`). Twins: ``parallax_uv`` in ``shaders/neural_material.wgsl`` and
:func:`vrneural.distill.models.parallax_uv`.

The height field of a pack is ``[H, W]`` float16 on the neural textures' full-resolution texel
grid, sampled bilinearly with wrap like them (:func:`vrneural.sampling.sample_bilinear_wrap`).
"""

from __future__ import annotations

import numpy as np

from vrneural.errors import VrnError, check_range
from vrneural.grazing import directions_range
from vrneural.sampling import MARCHES, block_rows, sample_bilinear_wrap

#: parallax kinds of ``distill --parallax`` (``auto`` resolves to one of the others)
PARALLAX_CHOICES = ("auto", "height", "neural", "off")
#: the kinds a pack can carry
PACK_KINDS = ("height", "neural", "off")
#: a material's march: a pack's (:data:`vrneural.sampling.MARCHES`: per texel or once per 2x2
#: block, as it trained) or, at render time, ``"auto"``: once per 2x2 block of radiance texels
#: where the block spans at most one texel of the march's grid, else per texel
#: (:func:`auto_blocks`)
MATERIAL_MARCHES = (*MARCHES, "auto")
#: the renderer's ``--parallax-march``: ``pack`` keeps the march a pack trained with
RENDER_MARCHES = ("auto", "pack", *MARCHES)
#: ``auto`` marches once per block where one atlas texel spans at most this many texels of the
#: height field (or offset texture): the block's 4 texels then lie within one texel, where the
#: per-texel march moves them alike to within a fraction of a texel (docs/parallax.md)
AUTO_BLOCK_FOOT_TEXELS = 0.5
MAX_STEPS = 64
#: ``auto`` gives a material parallax when its relief (:func:`relief_texels`) reaches this many
#: texels: below one texel the shift at the steepest measured view (``tan 75 deg`` ~ 3.7 texels
#: per texel of relief) stays within the few texels a texel-local network absorbs
AUTO_MIN_RELIEF_TEXELS = 1.0
#: the relief a material without a height field shows in its views
#: (:func:`vrneural.relief.apparent_relief`) from which ``auto`` gives it the neural offset:
#: higher than the height field's threshold, as the estimate is noisier and the module costs
#: MACs (1.32x the texture-space update per texel at quest3, docs/parallax.md)
AUTO_NEURAL_RELIEF_TEXELS = 2.0


def height_at_texels(height: np.ndarray, res: tuple[int, int], where: str = "height") -> np.ndarray:
    """A BTF's height field ``[N, N]`` (UV units) box-averaged onto the texel grid ``res =
    (H, W)`` -> ``[H, W]`` float32; ``N`` must be a whole multiple of both sides (the height
    grid's cells nest in the texels). VrnError otherwise, or for non-finite heights."""
    h = np.asarray(height, np.float64)
    if not np.isfinite(h).all():
        raise VrnError(f"{where}: the height field contains NaN or Inf")
    H, W = res
    n0, n1 = h.shape
    if n0 % H or n1 % W:
        raise VrnError(
            f"{where}: height field {n0}x{n1} does not fit the {H}x{W} texels (its size must "
            "equal the texels' or be a whole multiple of them)"
        )
    a, b = n0 // H, n1 // W
    return h.reshape(H, a, W, b).mean((1, 3)).astype(np.float32)


def relief_texels(height: np.ndarray) -> float:
    """The relief of a height field ``[H, W]`` (UV units, on the texel grid) in texels: its
    1st-to-99th percentile range times the texel count across the tile (the outliers of a few
    cells do not count)."""
    h = np.asarray(height, np.float64)
    lo, hi = np.percentile(h, [1.0, 99.0])
    return float((hi - lo) * h.shape[1])


def choose_kind(
    requested: str, height: np.ndarray | None, where: str, seen=None
) -> tuple[str, str]:
    """``(kind, why)``: the parallax a pack gets for ``--parallax requested`` and the BTF's
    height field on the texel grid (None: it has none). ``auto``: ``height`` where the relief
    reaches :data:`AUTO_MIN_RELIEF_TEXELS`, else ``off``; without a height field ``neural``
    where the relief the data show (``seen``: :func:`vrneural.relief.apparent_relief`, texels,
    called only then) reaches :data:`AUTO_NEURAL_RELIEF_TEXELS`, else ``off``. ``neural``
    needs no height field. VrnError for ``height`` without one."""
    if requested not in PARALLAX_CHOICES:
        raise VrnError(f"--parallax = {requested!r}; choose one of {', '.join(PARALLAX_CHOICES)}")
    if requested in ("off", "neural"):
        return requested, f"--parallax {requested}"
    if height is None:
        if requested == "height":
            raise VrnError(
                f"--parallax height: {where} has no height field (BTF format version 1); use "
                "--parallax neural, auto or off, or a BTF with one (btf synth, btf render)"
            )
        r = seen() if seen is not None else None
        if r is None:
            return "off", f"{where} has no height field"
        if r >= AUTO_NEURAL_RELIEF_TEXELS:
            return "neural", (
                f"no height field; apparent relief {r:.2f} texels >= "
                f"{AUTO_NEURAL_RELIEF_TEXELS:g} (neural offset)"
            )
        return (
            "off",
            f"no height field; apparent relief {r:.2f} texels < {AUTO_NEURAL_RELIEF_TEXELS:g}",
        )
    r = relief_texels(height)
    if requested == "height":
        return "height", f"--parallax height (relief {r:.2f} texels)"
    if r >= AUTO_MIN_RELIEF_TEXELS:
        return "height", f"relief {r:.2f} texels >= {AUTO_MIN_RELIEF_TEXELS:g}"
    return "off", f"relief {r:.2f} texels < {AUTO_MIN_RELIEF_TEXELS:g} (flat)"


def check_pack_height(
    height: np.ndarray, res: tuple[int, int], steps: int, march: str = "texel"
) -> np.ndarray:
    """Validate a pack's height field against its texels ``res = (H, W)``: ``[H, W]``, finite,
    the step count in ``[1, MAX_STEPS]``, the march one of :data:`MATERIAL_MARCHES`. Returns it as
    float16; ValueError otherwise."""
    if march not in MATERIAL_MARCHES:
        raise ValueError(f"parallax march {march!r} not in {MARCHES}")
    h = np.asarray(height)
    if h.shape != tuple(res):
        raise ValueError(
            f"height field has shape {list(h.shape)}; the neural textures' texels are "
            f"{list(res)} (they must be equal)"
        )
    if not np.isfinite(h.astype(np.float64)).all():
        raise ValueError("height field contains NaN/Inf")
    if not np.isfinite(h.astype(np.float16).astype(np.float32)).all():
        raise ValueError("height field overflows float16")
    if not (isinstance(steps, int) and 1 <= steps <= MAX_STEPS):
        raise ValueError(f"parallax steps = {steps!r}; allowed [1, {MAX_STEPS}]")
    return h.astype(np.float16)


def height_bounds(height: np.ndarray) -> tuple[np.float32, np.float32]:
    """``(hmin, hmax)`` float32 of a pack's float16 height field (the march's ends)."""
    h = np.asarray(height, np.float32)
    return np.float32(h.min()), np.float32(h.max())


def ray_slope(wo: np.ndarray, res: tuple[int, int]) -> np.ndarray:
    """``d: [N, 2]`` float32, the UV shift per unit height of view rays ``wo: [N, 3]``
    (``wo.z > 0``, local frame) on a tile of ``res = (H, W)`` texels."""
    wo = np.asarray(wo, np.float32)
    aspect = np.float32(res[1] / res[0])
    return np.stack([wo[:, 0] / wo[:, 2], wo[:, 1] / wo[:, 2] * aspect], -1).astype(np.float32)


def slope_max(cos_max: np.float32, sin_max: np.float32, res: tuple[int, int]) -> np.float32:
    """The largest ``|d|`` (:func:`ray_slope`) of the data's views: ``tan(theta_o_max)``
    (times ``W / H`` where that is above 1), float32 (a WGSL constant)."""
    aspect = np.float32(max(1.0, res[1] / res[0]))
    return np.float32(np.float32(sin_max) / np.float32(cos_max) * aspect)


def step_count(d: np.ndarray, steps: int, t_max: np.float32) -> np.ndarray:
    """March steps ``[M]`` int for ray slopes ``d: [M, 2]``: ``ceil(steps |d| / t_max)`` in
    ``[1, steps]`` (float32 arithmetic, as the shader's)."""
    f = np.float32
    t = np.sqrt((d * d).sum(-1, dtype=f)).astype(f)
    n = np.ceil((f(steps) * t / f(t_max)).astype(f))
    return np.clip(n, 1, steps).astype(np.int64)


def parallax_uv(
    height: np.ndarray,
    wo: np.ndarray,
    uv: np.ndarray,
    steps: int,
    t_max: float,
    march: str | np.ndarray = "texel",
) -> np.ndarray:
    """Parallax-corrected material UVs ``[N, 4, 2]`` float32 of the 2x2 blocks ``uv: [N, 4,
    2]`` seen along ``wo: [N, 3]`` (one view per block, ``wo.z > 0``: the extended view of
    :mod:`vrneural.grazing`), on the height field ``height: [H, W]`` float16 (UV units), in at
    most ``steps`` march steps (``t_max``: :func:`slope_max`), per texel or per block
    (``march``: ``"texel"``, ``"block"`` or ``[N]`` bool, True where a block marches once:
    :func:`auto_blocks`). See the module docstring."""
    f = np.float32
    uv = np.asarray(uv, f)
    d = ray_slope(wo, np.shape(height))  # [N, 2]
    blk = block_rows(march, len(uv))
    out = np.empty_like(uv)
    if blk.any():  # once per block, at the texels' mean
        hit = march_hits(height, uv[blk].mean(axis=1).astype(f), d[blk], steps, t_max)
        out[blk] = uv[blk] + (hit[:, None] * d[blk])[:, None, :]
    if not blk.all():
        d4 = np.repeat(d[~blk], 4, axis=0)  # [M*4, 2]
        u = uv[~blk].reshape(-1, 2)
        hit = march_hits(height, u, d4, steps, t_max)
        out[~blk] = (u + hit[:, None] * d4).reshape(-1, 4, 2)
    return out


def auto_blocks(foot: np.ndarray, grid: tuple[int, ...]) -> np.ndarray:
    """March ``"auto"`` for blocks whose atlas texel spans ``foot: [N]`` of (tiled) material
    UV, on a march grid (height field or offset texture) of shape ``grid = (H, W, ...)``:
    ``[N]`` bool, True (once per block) where ``foot * max(H, W) <=``
    :data:`AUTO_BLOCK_FOOT_TEXELS`. float32 arithmetic in the texture-space kernel's order."""
    f = np.float32
    side = f(max(grid[0], grid[1]))
    return (np.asarray(foot, f) * side).astype(f) <= f(AUTO_BLOCK_FOOT_TEXELS)


def march_hits(height, u: np.ndarray, d: np.ndarray, steps: int, t_max) -> np.ndarray:
    """The ray heights ``[M]`` float32 where rays through ``u: [M, 2]`` with slopes ``d: [M,
    2]`` meet ``height`` (the march and refinement of the module docstring)."""
    f = np.float32
    tex = np.asarray(height, np.float32)[..., None]
    hmin, hmax = height_bounds(height)
    n = step_count(d, steps, f(t_max))
    dz = ((hmax - hmin) / n.astype(f)).astype(f)

    def field(z):
        return sample_bilinear_wrap(tex, (u + z[:, None] * d).astype(f))[:, 0]

    z_prev = np.full(len(u), hmax, f)
    h_prev = field(z_prev)
    hit = np.where(h_prev >= z_prev, hmax, hmin).astype(f)
    done = h_prev >= z_prev
    for k in range(1, steps + 1):
        z = (hmax - f(k) * dz).astype(f)
        h = field(z)
        now = ~done & (z <= h) & (k <= n)
        a = z_prev - h_prev
        t = a / np.where(now, a - (z - h), f(1))  # a > 0 >= z - h where `now`
        hit = np.where(now, z_prev + t * (z - z_prev), hit).astype(f)
        done |= now
        z_prev, h_prev = z, h
    return hit


def parallax_fetches(steps: int) -> int:
    """Height-field texel loads per shaded texel at most (4 per bilinear lookup, steps + 1
    lookups): the fetch cost ``bench quality`` reports beside the networks'."""
    return 4 * (steps + 1)


def setup_parallax(
    cfg, spec: dict, btf, where: str, recorded: dict | None = None
) -> tuple[np.ndarray | None, dict]:
    """Resolve ``cfg.parallax`` for a training run on ``btf`` (a :class:`~vrneural.btf.format.Btf`
    named ``where`` in messages): sets ``spec["parallax"]`` when the choice is ``height`` and
    returns ``(height on the texel grid [H, W] float32 or None, record)``, the record
    ``{"kind", "why", "relief_texels"}`` kept in the checkpoint and the pack's meta.
    ``recorded``: that record of the checkpoint a ``--resume`` continues (``auto`` keeps its
    choice, which an older version may have made otherwise)."""
    check_range("--parallax-steps", cfg.parallax_steps, 1, MAX_STEPS)
    height = None
    if btf.height is not None:
        height = height_at_texels(btf.height, btf.resolution, f"{where}: height")
    seen: list[float] = []

    def apparent() -> float:
        from vrneural.relief import apparent_relief

        seen.append(apparent_relief(btf))
        return seen[-1]

    if recorded and cfg.parallax == "auto":  # a resumed run keeps what auto chose then
        kind, why = recorded["kind"], recorded["why"]
    else:
        kind, why = choose_kind(cfg.parallax, height, where, apparent)
    record = {"kind": kind, "why": why, "relief_texels": None}
    if height is not None:
        record["relief_texels"] = round(relief_texels(height), 4)
    if seen:
        record["apparent_relief_texels"] = round(seen[-1], 4)
    if kind == "neural":
        from vrneural.neural_offset import OFFSET_SIZES

        channels, hidden = OFFSET_SIZES[getattr(cfg, "method", "teacher")]
        spec["parallax"] = {
            "kind": "neural",
            "march": cfg.parallax_march,
            "res": list(btf.resolution),
            "channels": channels,
            "hidden": list(hidden),
        }
        record["march"] = cfg.parallax_march
        return None, record
    if kind != "height":
        return None, record

    spec["parallax"] = {
        "kind": "height",
        "steps": int(cfg.parallax_steps),
        "march": cfg.parallax_march,
        "res": list(height.shape),
        # the steepest view of the data: the march's full step count (the pack's dir_range)
        "theta_o_max": directions_range(btf.light_dirs, btf.view_dirs)[1],
    }
    record["steps"] = int(cfg.parallax_steps)
    record["march"] = cfg.parallax_march
    return height, record
