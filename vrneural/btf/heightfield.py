"""Tileable procedural microgeometry: a periodic heightfield plus spatially varying BRDF maps.

Everything lives on a periodic ``[N, N]`` grid over the unit tile (material UV in ``[0, 1)``;
grid cell ``(i, j)`` has its centre at UV ``((j + 0.5) / N, (i + 0.5) / N)``, row ``i`` = v).
Heights are in UV units (fractions of the tile width), so a preset looks the same at any grid
size. Every generator here is periodic by construction (FFT synthesis, toroidal distances,
integer frequencies), so tiles continue across their edges.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Channel layout of :attr:`Maps.stack` (what :func:`sample_maps` returns per hit).
CHANNELS = (
    "nx", "ny", "nz",            # shading normal (unit), local frame
    "ar", "ag", "ab",            # diffuse albedo
    "fr", "fg", "fb",            # specular F0
    "alpha_t", "alpha_b",        # GGX roughness along / across the tangent
    "tc", "ts",                  # tangent direction (cos, sin) in the surface plane
    "sr", "sg", "sb",            # sheen colour (weight of the sheen lobe)
    "sheen_rough",               # Charlie sheen roughness in (0, 1]
)  # fmt: skip


@dataclass
class Maps:
    """Microgeometry and reflectance of one tile. All arrays ``[N, N(, k)]`` float32.

    ``height`` is in UV units; ``albedo``/``f0``/``sheen`` are linear RGB in [0, 1];
    ``alpha_t``/``alpha_b`` are GGX roughness along / across the tangent whose in-plane angle is
    ``angle`` (radians from +u); ``sheen_rough`` in (0, 1].
    """

    height: np.ndarray
    albedo: np.ndarray
    f0: np.ndarray
    alpha_t: np.ndarray
    alpha_b: np.ndarray
    angle: np.ndarray
    sheen: np.ndarray
    sheen_rough: np.ndarray

    @property
    def n(self) -> int:
        return int(self.height.shape[0])

    def normals(self) -> np.ndarray:
        """Unit normals ``[N, N, 3]`` of the heightfield (periodic central differences)."""
        N = self.n
        h = self.height.astype(np.float64)
        dhdu = (np.roll(h, -1, 1) - np.roll(h, 1, 1)) * (N / 2.0)
        dhdv = (np.roll(h, -1, 0) - np.roll(h, 1, 0)) * (N / 2.0)
        nrm = np.stack([-dhdu, -dhdv, np.ones_like(h)], -1)
        return (nrm / np.linalg.norm(nrm, axis=-1, keepdims=True)).astype(np.float32)

    def stack(self) -> np.ndarray:
        """All shading inputs as one ``[N, N, len(CHANNELS)]`` float32 array."""
        a = self.angle
        parts = [
            self.normals(),
            self.albedo,
            self.f0,
            self.alpha_t[..., None],
            self.alpha_b[..., None],
            np.cos(a)[..., None],
            np.sin(a)[..., None],
            self.sheen,
            self.sheen_rough[..., None],
        ]
        return np.concatenate([np.asarray(p, np.float32) for p in parts], -1)


# ---------------------------------------------------------------------------------------------
# Periodic primitives. ``u, v`` are ``[N, N]`` grids of UV cell centres.


def uv_grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Cell-centre coordinates ``(u, v)``, each ``[N, N]`` float64, in [0, 1)."""
    c = (np.arange(n) + 0.5) / n
    return np.meshgrid(c, c, indexing="xy")


def spectral_noise(
    rng,
    n: int,
    f_lo: float,
    f_hi: float,
    beta: float = 2.0,
    stretch=(1.0, 1.0),
) -> np.ndarray:
    """Periodic Gaussian noise ``[N, N]`` (zero mean, unit std) with a band-limited power law.

    Frequencies in cycles per tile: power ``~ f^-beta`` between ``f_lo`` and ``f_hi``.
    ``stretch = (sx, sy)`` scales the frequency axes:
    ``(8, 1)`` suppresses variation along u, so features become streaks along u (wood grain,
    brushing); ``(1, 8)`` gives streaks along v.
    """
    white = rng.standard_normal((n, n))
    fx = np.fft.fftfreq(n, 1.0 / n)
    FX, FY = np.meshgrid(fx, fx, indexing="xy")
    f = np.hypot(FX * stretch[0], FY * stretch[1])
    amp = np.where((f >= f_lo) & (f <= f_hi), np.maximum(f, 1e-9) ** (-beta / 2), 0.0)
    out = np.fft.ifft2(np.fft.fft2(white) * amp).real
    sd = out.std()
    return out / sd if sd > 0 else out


def toroidal_cells(rng, n: int, count: int, jitter: float = 1.0):
    """Periodic Worley cells. Returns ``(f1, f2, cell_id)`` ``[N, N]``: distances (UV units) to
    the nearest and second-nearest seed point on the torus, and the nearest seed's index."""
    k = max(1, round(np.sqrt(count)))
    base = (np.stack(np.meshgrid(np.arange(k), np.arange(k)), -1).reshape(-1, 2) + 0.5) / k
    pts = (base + (rng.random(base.shape) - 0.5) * jitter / k) % 1.0
    u, v = uv_grid(n)
    f1 = np.full((n, n), np.inf)
    f2 = np.full((n, n), np.inf)
    ids = np.zeros((n, n), np.int64)
    for i, (px, py) in enumerate(pts):
        dx = np.abs(u - px)
        dy = np.abs(v - py)
        d = np.hypot(np.minimum(dx, 1 - dx), np.minimum(dy, 1 - dy))
        closer = d < f1
        f2 = np.where(closer, f1, np.minimum(f2, d))
        ids = np.where(closer, i, ids)
        f1 = np.where(closer, d, f1)
    return f1, f2, ids


def smoothstep(e0: float, e1: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3 - 2 * t)


def lerp(a, b, t):
    """``a + (b - a) * t`` broadcasting RGB tuples against ``[N, N]`` weights."""
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    t = np.asarray(t, np.float64)
    if (a.ndim == 1 or b.ndim == 1 or max(a.ndim, b.ndim) > t.ndim) and t.ndim > 0:
        t = t[..., None]
    return a + (b - a) * t


# ---------------------------------------------------------------------------------------------
# Sampling with wrap-around.


def bilinear_wrap(grid: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Bilinear lookup on a periodic grid ``[N, N(, C)]`` at UV ``u, v`` (any shape S, any real
    values; wraps). Returns ``[*S(, C)]`` float32. Cell centres sit at ``(j + 0.5) / N``."""
    n = grid.shape[0]
    x = u * n - 0.5
    y = v * n - 0.5
    x0 = np.floor(x)
    y0 = np.floor(y)
    fx = (x - x0).astype(np.float32)
    fy = (y - y0).astype(np.float32)
    i0 = y0.astype(np.int64) % n
    j0 = x0.astype(np.int64) % n
    i1 = (i0 + 1) % n
    j1 = (j0 + 1) % n
    if grid.ndim == 3:
        fx = fx[..., None]
        fy = fy[..., None]
    top = grid[i0, j0] * (1 - fx) + grid[i0, j1] * fx
    bot = grid[i1, j0] * (1 - fx) + grid[i1, j1] * fx
    return (top * (1 - fy) + bot * fy).astype(np.float32)


def shift_wrap(grid: np.ndarray, du: float, dv: float) -> np.ndarray:
    """``grid`` resampled at ``(u + du, v + dv)`` for every cell (bilinear, periodic) ``[N, N]``."""
    n = grid.shape[0]
    sx, sy = du * n, dv * n
    ix, iy = int(np.floor(sx)), int(np.floor(sy))
    fx, fy = sx - ix, sy - iy
    a = np.roll(grid, (-iy, -ix), (0, 1))
    b = np.roll(a, -1, 1)
    top = a * (1 - fx) + b * fx
    return top * (1 - fy) + np.roll(top, -1, 0) * fy


def texel_height(height: np.ndarray, res: int) -> np.ndarray:
    """A tile's height field ``[N, N]`` (UV units) on a grid that nests in ``res`` texels (as
    packs need it, :func:`vrneural.parallax.height_at_texels`): as it is where ``N`` is a whole
    multiple of ``res``, else its bilinear surface (:func:`bilinear_wrap`, the one the
    renderer marches) sampled at the cell centres of the nearest multiple ``k res`` (``k >=
    1``). ``[M, M]`` float32."""
    n = height.shape[0]
    if n % res == 0:
        return np.asarray(height, np.float32)
    m = res * max(1, round(n / res))
    c = (np.arange(m) + 0.5) / m
    u, v = np.meshgrid(c, c)  # row = v, as the grid's
    return bilinear_wrap(np.asarray(height, np.float32), u, v)
