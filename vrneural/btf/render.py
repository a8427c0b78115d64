"""Render BTF slices of a heightfield material (numpy, vectorised, float32).

Per view direction ``wo`` (:func:`render_view`):

1. every sub-sample ray starts where it crosses the reference plane ``z = 0`` (the mean height)
   at its texel position ``(u0, v0)`` and is traced orthographically along ``-wo``:
   ``p(s) = (u0 + s wo.x, v0 + s wo.y, s wo.z)``, from the top of the heightfield down
   (:func:`march_view`: fixed steps of half a grid cell, then bisection and a secant step).
   The first crossing is the visible point: parallax and masking. It depends only on ``wo``, so
   it is computed once per view and shared by all light directions.
2. per light direction, self-shadowing comes from a precomputed *shadow-height map*
   (:func:`shadow_maps`): ``S(x) = max_{s >= s0} h(x + s wi_xy) - s wi.z``; a point at height z is
   lit when ``z >= S(x)`` (with a linear ramp of half a grid cell for anti-aliasing). So shadows
   cost one march per light for the whole render, not one per (light, view).
3. the BRDF (:mod:`vrneural.btf.brdf`) is evaluated in the shading frame of the hit (normal from
   the heightfield, tangent from the anisotropy map) and multiplied by ``max(n . wi, 0)``
   (the convention: cos(theta_i) inside the BTF) and the light visibility; sub-samples are
   box-filtered into the texel.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vrneural.btf.brdf import brdf_rgb, prepare
from vrneural.btf.heightfield import CHANNELS, Maps, bilinear_wrap, shift_wrap

_C = {name: i for i, name in enumerate(CHANNELS)}
NO_SHADOW = np.float32(-1e9)


@dataclass
class Scene:
    """What every view needs: the tile's height ``[N, N]`` (UV units), shading stack
    ``[N, N, C]``, height range, and the shadow-height maps ``[L, N, N]`` of the light set."""

    height: np.ndarray
    stack: np.ndarray
    hmin: float
    hmax: float
    light_dirs: np.ndarray  # [L, 3]
    shadow: np.ndarray  # [L, N, N]

    @property
    def n(self) -> int:
        return int(self.height.shape[0])


def shadow_maps(height: np.ndarray, light_dirs: np.ndarray, progress=None) -> np.ndarray:
    """Shadow-height maps ``[L, N, N]`` float32: ``S(x) = max_{s >= s0} h(x + s wi_xy) - s wi.z``.

    Marching starts one grid cell away (``s0``) so a surface does not shadow itself; steps are
    half a grid cell; marching stops once the ray has risen above the whole heightfield.
    Near-vertical lights (and flat tiles) get ``NO_SHADOW``.
    """
    h = height.astype(np.float32)
    n = h.shape[0]
    span = float(h.max() - h.min())
    out = np.empty((len(light_dirs), n, n), np.float32)
    for li, (dx, dy, dz) in enumerate(np.asarray(light_dirs, np.float64)):
        r = np.hypot(dx, dy)
        out[li] = NO_SHADOW
        if r < 1e-6 or span <= 0 or dz <= 0:
            continue
        ds = 0.5 / (n * r)  # half a grid cell horizontally
        s = 1.0 / (n * r)
        best = np.full((n, n), NO_SHADOW, np.float32)
        while s * dz <= span + 1e-12:
            np.maximum(best, shift_wrap(h, s * dx, s * dy) - np.float32(s * dz), out=best)
            s += ds
        out[li] = best
        if progress is not None:
            progress.update(1)
    return out


def make_scene(maps: Maps, light_dirs: np.ndarray, progress=None) -> Scene:
    """Precompute everything that does not depend on the view direction."""
    h = maps.height.astype(np.float32)
    return Scene(
        height=h,
        stack=maps.stack(),
        hmin=float(h.min()),
        hmax=float(h.max()),
        light_dirs=np.asarray(light_dirs, np.float32),
        shadow=shadow_maps(h, light_dirs, progress),
    )


def march_view(scene: Scene, u0: np.ndarray, v0: np.ndarray, wo: np.ndarray):
    """First intersection of the rays ``p(s) = (u0, v0, 0) + s wo`` (traced toward -wo) with the
    heightfield. ``u0, v0``: ``[M]`` UV. Returns hit ``(u, v, z)``, each ``[M]`` float32/64."""
    h = scene.height
    wx, wy, wz = (float(c) for c in wo)
    s_top = (scene.hmax + 1e-6) / wz
    s_bot = (scene.hmin - 1e-6) / wz
    travel = (s_top - s_bot) * np.hypot(wx, wy) * scene.n
    k_steps = max(1, int(np.ceil(travel / 0.5)))
    ds = (s_top - s_bot) / k_steps
    lo = np.full(u0.shape, s_bot)  # below the surface (hit side)
    hi = np.full(u0.shape, s_top)  # above the surface
    act = np.arange(u0.size)
    for k in range(1, k_steps + 1):
        s = s_top - k * ds
        a_u, a_v = u0[act], v0[act]
        hit = bilinear_wrap(h, a_u + s * wx, a_v + s * wy) >= s * wz
        if k == k_steps:
            hit[:] = True
        sel = act[hit]
        lo[sel] = s
        hi[sel] = s + ds
        act = act[~hit]
        if act.size == 0:
            break

    def gap(s):  # height above the ray; >= 0 means below the surface
        return bilinear_wrap(h, u0 + s * wx, v0 + s * wy) - s * wz

    for _ in range(8):
        mid = 0.5 * (lo + hi)
        below = gap(mid) >= 0
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    g_lo, g_hi = gap(lo), gap(hi)
    den = g_lo - g_hi
    t = np.where(den > 1e-12, g_lo / np.where(den > 1e-12, den, 1.0), 0.0)
    s = lo + (hi - lo) * np.clip(t, 0.0, 1.0)
    return u0 + s * wx, v0 + s * wy, (s * wz).astype(np.float32)


def render_view(
    scene: Scene, wo: np.ndarray, samples: np.ndarray, res: tuple[int, int], chunk: int = 1 << 18
) -> np.ndarray:
    """All light directions for one view: ``[L, H, W, 3]`` float32 BTF values.

    ``samples``: ``[H, W, S, 2]`` sub-sample offsets in texels, in ``[-0.5, 0.5)``.
    ``chunk`` bounds the number of (light, sample) pairs processed at once (memory).
    """
    H, W = res
    S = samples.shape[2]
    ys, xs = np.meshgrid(np.arange(H), np.arange(W), indexing="ij")
    u0 = ((xs[..., None] + 0.5 + samples[..., 0]) / W).reshape(-1)
    v0 = ((ys[..., None] + 0.5 + samples[..., 1]) / H).reshape(-1)
    hu, hv, hz = march_view(scene, u0, v0, np.asarray(wo, np.float64))
    g = bilinear_wrap(scene.stack, hu, hv)  # [M, C]
    nx, ny, nz = g[:, 0], g[:, 1], g[:, 2]
    inv = 1.0 / np.sqrt(nx * nx + ny * ny + nz * nz)
    nx, ny, nz = nx * inv, ny * inv, nz * inv
    tc, ts = g[:, _C["tc"]], g[:, _C["ts"]]
    d = tc * nx + ts * ny  # Gram-Schmidt: t = normalize(t0 - (t0 . n) n)
    tx, ty, tz = tc - d * nx, ts - d * ny, -d * nz
    inv = 1.0 / np.sqrt(np.maximum(tx * tx + ty * ty + tz * tz, 1e-12))
    tx, ty, tz = tx * inv, ty * inv, tz * inv
    bx, by, bz = ny * tz - nz * ty, nz * tx - nx * tz, nx * ty - ny * tx
    p = {
        "albedo": g[:, 3:6],
        "f0": g[:, 6:9],
        "alpha_t": np.maximum(g[:, _C["alpha_t"]], 1e-3),
        "alpha_b": np.maximum(g[:, _C["alpha_b"]], 1e-3),
        "sheen": g[:, 13:16],
        "sheen_rough": np.clip(g[:, _C["sheen_rough"]], 0.05, 1.0),
    }
    wo = np.asarray(wo, np.float32)
    wo_l = tuple(
        wo[0] * a + wo[1] * b + wo[2] * c for a, b, c in ((tx, ty, tz), (bx, by, bz), (nx, ny, nz))
    )
    # Shadow lookup: bilinear weights at the hit, shared by every light.
    n = scene.n
    x = hu * n - 0.5
    y = hv * n - 0.5
    j0 = np.floor(x).astype(np.int64)
    i0 = np.floor(y).astype(np.int64)
    fx = (x - j0).astype(np.float32)
    fy = (y - i0).astype(np.float32)
    j0 %= n
    i0 %= n
    j1 = (j0 + 1) % n
    i1 = (i0 + 1) % n
    ramp = np.float32(0.5 / n)
    L = len(scene.light_dirs)
    M = hu.size
    out = np.empty((L, H * W, 3), np.float32)
    # Work in blocks of <= chunk (light, sample) pairs: lights x whole texels (S samples each).
    # Small blocks keep temporaries in cache and out of mmap/munmap churn.
    m_step = min(M, max(S, chunk // S * S))
    l_step = max(1, chunk // m_step)
    for m0 in range(0, M, m_step):
        ms = slice(m0, min(M, m0 + m_step))
        frame = [q[ms] for q in (tx, ty, tz, bx, by, bz, nx, ny, nz)]
        wo_b = tuple(q[ms] for q in wo_l)
        p_b = prepare({k: v[ms] for k, v in p.items()})
        ii0, ii1, jj0, jj1, ffx, ffy = i0[ms], i1[ms], j0[ms], j1[ms], fx[ms], fy[ms]
        for a in range(0, L, l_step):
            wi = scene.light_dirs[a : a + l_step]  # [Lc, 3]
            sh = scene.shadow[a : a + l_step]
            s_hit = (sh[:, ii0, jj0] * (1 - ffx) + sh[:, ii0, jj1] * ffx) * (1 - ffy) + (
                sh[:, ii1, jj0] * (1 - ffx) + sh[:, ii1, jj1] * ffx
            ) * ffy  # [Lc, Mb]
            vis = np.clip((hz[None, ms] - s_hit) / ramp + 1.0, 0.0, 1.0)
            c = [wi[:, k : k + 1] for k in range(3)]
            wi_l = tuple(
                c[0] * frame[3 * r] + c[1] * frame[3 * r + 1] + c[2] * frame[3 * r + 2]
                for r in range(3)
            )
            scale = np.maximum(wi_l[2], 0.0) * vis  # cos(theta_i) at the hit x visibility
            t0, t1 = ms.start // S, ms.stop // S
            for c, f in enumerate(brdf_rgb(wi_l, wo_b, p_b)):  # [Lc, Mb] per channel
                f *= scale
                f = f.reshape(len(wi), t1 - t0, S)
                acc = f[:, :, 0].copy()
                for k in range(1, S):  # box filter; explicit adds beat a short-axis reduce
                    acc += f[:, :, k]
                out[a : a + l_step, t0:t1, c] = acc * np.float32(1.0 / S)
    return out.reshape(L, H, W, 3)
