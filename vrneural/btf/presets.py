"""Material presets imitating UBO2014's families. Each builds a periodic :class:`Maps` tile.

A preset is a function ``(rng, n) -> Maps`` on an ``[n, n]`` grid; heights are in UV units
(fractions of the tile width), frequencies in cycles per tile, so the material is the same at any
grid size (a finer grid only adds detail up to its Nyquist limit). All randomness comes from
``rng``, so a seed fixes the material. Values are kept physically plausible: albedo <= 0.9,
dielectric F0 = 0.04, metal F0 from measured RGB reflectances, roughness in [0.05, 0.9].
"""

from __future__ import annotations

import numpy as np

from vrneural.btf.heightfield import (
    Maps,
    lerp,
    smoothstep,
    spectral_noise,
    toroidal_cells,
    uv_grid,
)

F0_DIELECTRIC = (0.04, 0.04, 0.04)


def _maps(
    n,
    height,
    albedo,
    f0=F0_DIELECTRIC,
    alpha_t=0.4,
    alpha_b=None,
    angle=0.0,
    sheen=(0.0, 0.0, 0.0),
    sheen_rough=0.5,
) -> Maps:
    def full(v, k=None):
        shape = (n, n) if k is None else (n, n, k)
        return np.broadcast_to(np.asarray(v, np.float32), shape).astype(np.float32)

    at = full(alpha_t)
    return Maps(
        height=(height - height.mean()).astype(np.float32),
        albedo=np.clip(full(albedo, 3), 0.0, 0.9),
        f0=np.clip(full(f0, 3), 0.0, 1.0),
        alpha_t=np.clip(at, 0.05, 0.9),
        alpha_b=np.clip(at if alpha_b is None else full(alpha_b), 0.05, 0.9),
        angle=full(angle),
        sheen=np.clip(full(sheen, 3), 0.0, 1.0),
        sheen_rough=np.clip(full(sheen_rough), 0.1, 1.0),
    )


def leather(rng, n: int) -> Maps:
    """Grained leather: raised cells separated by creases, pores, polished tops."""
    f1, f2, ids = toroidal_cells(rng, n, 90, jitter=0.9)
    crease = 1.0 - smoothstep(0.0, 0.03, f2 - f1)  # 1 in the creases
    dome = smoothstep(0.0, 0.06, f2 - f1)
    pores = np.maximum(spectral_noise(rng, n, 40, 120, beta=0.5), 1.8) - 1.8
    fine = spectral_noise(rng, n, 8, 64, beta=1.5)
    height = 0.010 * dome - 0.004 * crease - 0.0015 * pores + 0.0006 * fine
    cell_tint = rng.uniform(-1, 1, ids.max() + 1)[ids]
    tone = 0.5 + 0.5 * np.tanh(0.8 * spectral_noise(rng, n, 1, 8) + 0.4 * cell_tint)
    albedo = lerp((0.16, 0.065, 0.03), (0.34, 0.16, 0.07), tone)
    albedo = lerp(albedo, (0.05, 0.025, 0.012), 0.7 * crease)
    alpha = 0.42 - 0.18 * dome + 0.1 * crease
    return _maps(n, height, albedo, alpha_t=alpha)


def fabric(rng, n: int, threads: int = 12) -> Maps:
    """Plain-weave fabric: round warp (along v) and weft (along u) threads crossing over and
    under, twisted fibres, anisotropic highlights along each thread, sheen."""
    u, v = uv_grid(n)
    a, r, w = 0.006, 0.014, 0.46  # undulation, thread radius (UV), half width (fraction)
    cu, cv = u * threads, v * threads
    ju, iv = np.floor(cu), np.floor(cv)
    du, dv = cu - ju - 0.5, cv - iv - 0.5
    prof_warp = np.sqrt(np.clip(1 - (du / w) ** 2, 0, 1))
    prof_weft = np.sqrt(np.clip(1 - (dv / w) ** 2, 0, 1))
    z_warp = a * np.cos(np.pi * (cv - 0.5) + np.pi * ju)
    z_weft = -a * np.cos(np.pi * (cu - 0.5) + np.pi * iv)
    twist_w = spectral_noise(rng, n, 6, n / 2, beta=1.0, stretch=(1.0, 6.0))  # along v
    twist_f = spectral_noise(rng, n, 6, n / 2, beta=1.0, stretch=(6.0, 1.0))  # along u
    h_warp = np.where(prof_warp > 0, z_warp + r * prof_warp + 0.0012 * twist_w, -1.0)
    h_weft = np.where(prof_weft > 0, z_weft + r * prof_weft + 0.0012 * twist_f, -1.0)
    floor = -a - 0.3 * r
    height = np.maximum(np.maximum(h_warp, h_weft), floor)
    is_warp = h_warp >= h_weft
    in_gap = np.maximum(h_warp, h_weft) <= floor
    slub = 0.5 + 0.5 * np.tanh(spectral_noise(rng, n, 2, 24))
    warp_col = lerp((0.05, 0.09, 0.26), (0.09, 0.15, 0.38), slub)
    weft_col = lerp((0.55, 0.46, 0.30), (0.70, 0.60, 0.42), slub)
    albedo = np.where(is_warp[..., None], warp_col, weft_col)
    albedo = np.where(in_gap[..., None], albedo * 0.3, albedo)
    angle = np.where(is_warp, np.pi / 2, 0.0)
    sheen = np.where(is_warp[..., None], (0.35, 0.4, 0.6), (0.6, 0.55, 0.45)) * 0.8
    return _maps(
        n, height, albedo, alpha_t=0.18, alpha_b=0.6, angle=angle, sheen=sheen, sheen_rough=0.35
    )


def wood(rng, n: int, rings: int = 7) -> Maps:
    """Varnished plank: distorted growth rings (dark latewood), pores along the grain, a glossy
    finish slightly anisotropic along the grain (u)."""
    u, v = uv_grid(n)
    warp = spectral_noise(rng, n, 1, 6, beta=3.0, stretch=(3.0, 1.0))
    g = v * rings + 0.35 * warp + 0.1 * np.sin(2 * np.pi * u)
    ring = g - np.floor(g)
    late = smoothstep(0.55, 0.8, ring) * (1 - smoothstep(0.85, 1.0, ring))
    fibre = spectral_noise(rng, n, 4, n / 2, beta=1.0, stretch=(10.0, 1.0))
    pores = np.clip(spectral_noise(rng, n, 20, n / 2, beta=0.5, stretch=(6.0, 1.0)) - 1.8, 0, 9)
    height = 0.0008 * late - 0.0025 * pores + 0.0003 * fibre
    tone = 0.5 + 0.5 * np.tanh(0.5 * fibre)
    early = lerp((0.50, 0.30, 0.15), (0.58, 0.37, 0.19), tone)
    albedo = lerp(early, (0.22, 0.10, 0.04), late)
    albedo = lerp(albedo, (0.12, 0.06, 0.03), np.clip(pores, 0, 1))
    alpha_t = 0.08 + 0.1 * np.clip(pores, 0, 1)
    return _maps(n, height, albedo, alpha_t=alpha_t, alpha_b=alpha_t * 1.8, angle=0.0)


def carpet(rng, n: int, tufts: int = 196) -> Maps:
    """Cut-pile carpet: deep, densely packed yarn tufts with fibre tips; strong self-shadowing
    and masking, sheen, rough saturated yarn."""
    f1, _, ids = toroidal_cells(rng, n, tufts, jitter=0.8)
    rad = 0.75 / np.sqrt(tufts)
    body = np.sqrt(np.clip(1 - (f1 / rad) ** 2, 0, 1))
    fibres = spectral_noise(rng, n, 20, 48, beta=1.0)
    tuft_h = rng.uniform(0.8, 1.0, ids.max() + 1)[ids]
    height = 0.05 * tuft_h * body**0.6 + 0.002 * fibres * body
    height = np.maximum(height, -0.002)
    shade = rng.uniform(0, 1, ids.max() + 1)[ids]
    albedo = lerp((0.45, 0.06, 0.05), (0.62, 0.12, 0.08), shade)
    albedo = lerp(albedo, albedo * 0.25, 1 - body)
    return _maps(
        n, height, albedo, alpha_t=0.6, angle=0.0, sheen=(0.5, 0.25, 0.22), sheen_rough=0.5
    )


def metal(rng, n: int) -> Maps:
    """Brushed aluminium: fine grooves along u, anisotropic GGX (smooth along the brushing,
    rough across), a few deeper cross scratches and smudged regions."""
    u, v = uv_grid(n)
    grooves = spectral_noise(rng, n, 8, n / 2, beta=0.8, stretch=(40.0, 1.0))
    wobble = 0.08 * spectral_noise(rng, n, 1, 4)
    height = 0.001 * grooves
    scratch = np.zeros((n, n))
    sc_angle = np.zeros((n, n))
    for _ in range(2):  # straight periodic scratches: integer direction (k, m) across the tile
        k, m = int(rng.integers(1, 3)), int(rng.integers(-3, 4))
        d = np.abs((k * u + m * v + rng.uniform(0, 1)) % 1.0 - 0.5) / np.hypot(k, m)
        this = 1 - smoothstep(0.0, 0.003, d)
        sc_angle = np.where(this > scratch, np.arctan2(-k, m), sc_angle)
        scratch = np.maximum(scratch, this)
    height = height - 0.001 * scratch
    smudge = 0.5 + 0.5 * np.tanh(1.5 * spectral_noise(rng, n, 1, 6) - 1.0)
    f0 = lerp((0.91, 0.92, 0.92), (0.84, 0.84, 0.86), smudge)
    alpha_t = 0.07 + 0.025 * smudge
    alpha_b = 0.32 + 0.04 * smudge
    return _maps(
        n,
        height,
        (0.0, 0.0, 0.0),
        f0=f0,
        alpha_t=alpha_t,
        alpha_b=alpha_b,
        angle=np.where(scratch > 0.5, sc_angle, wobble),
    )


def stone(rng, n: int) -> Maps:
    """Rough granite-like stone: mineral grains (pale feldspar, grey quartz, dark shiny mica),
    bumpy fBm relief with pits, rough diffuse base."""
    f1, f2, ids = toroidal_cells(rng, n, 220, jitter=1.0)
    kind = rng.choice(3, ids.max() + 1, p=[0.5, 0.3, 0.2])[ids]
    relief = spectral_noise(rng, n, 2, 40, beta=3.0)
    pits = np.clip(spectral_noise(rng, n, 12, 40, beta=0.5) - 2.0, 0, 9)
    edge = 1 - smoothstep(0.0, 0.01, f2 - f1)
    height = 0.008 * relief - 0.003 * pits - 0.0015 * edge + 0.002 * (kind == 1)
    cols = np.array([(0.72, 0.62, 0.56), (0.45, 0.45, 0.46), (0.06, 0.06, 0.07)])
    var = 0.85 + 0.15 * np.tanh(spectral_noise(rng, n, 4, 40))
    albedo = cols[kind] * var[..., None]
    alpha = np.array([0.7, 0.35, 0.15])[kind]
    return _maps(n, height, albedo, alpha_t=alpha)


PRESETS = {
    "leather": leather,
    "fabric": fabric,
    "wood": wood,
    "carpet": carpet,
    "metal": metal,
    "stone": stone,
}
