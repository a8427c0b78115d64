"""The microfacet BRDF used at every heightfield hit (numpy, vectorised, float32).

``f(wi, wo) = F D G2 / (4 cos_i cos_o)                            anisotropic GGX specular
            + (1 - F(cos_i)) (1 - F(cos_o)) [ (1 - max(sheen)) albedo / pi   Lambert diffuse
                                              + sheen D_charlie V_ashikhmin ]  sheen``

with Schlick Fresnel ``F(c) = f0 + s (1 - f0)(1 - c)^5`` per RGB channel (``s = min(1, max(f0) /
0.04)``: 1 for every real interface; below, the grazing rise fades out, so ``f0 = 0`` gives a
pure Lambertian BRDF), the anisotropic GGX
distribution ``D`` with roughness ``alpha_t`` along the tangent and ``alpha_b`` across it, and
the height-correlated Smith masking-shadowing ``G2 = 1 / (1 + Lambda(wi) + Lambda(wo))``.
Every term is symmetric in ``(wi, wo)``, so ``f`` is reciprocal. Directions are in the shading
frame (x = tangent, y = bitangent, z = normal), given as separate component arrays so that
callers broadcast ``[lights, 1]`` against ``[1, samples]`` without building ``[..., 3]`` stacks.

The BTF value (docs/conventions.md section 2) is ``f * cos_i``.
"""

from __future__ import annotations

import numpy as np

INV_PI = np.float32(1.0 / np.pi)
EPS = np.float32(1e-6)


def ggx_d(hx, hy, hz, at, ab) -> np.ndarray:
    """Anisotropic GGX normal distribution ``D(h)`` (1/sr) for a unit half vector ``h``."""
    t = (hx / at) ** 2 + (hy / ab) ** 2 + hz * hz
    return INV_PI / (at * ab * t * t)


def smith_lambda(x, y, z, at, ab) -> np.ndarray:
    """Smith ``Lambda(w)`` of the anisotropic GGX for a unit direction ``w`` with ``z > 0``."""
    z2 = np.maximum(z * z, EPS)
    return 0.5 * (np.sqrt(1.0 + ((at * x) ** 2 + (ab * y) ** 2) / z2) - 1.0)


def charlie_d(cos_h, rough) -> np.ndarray:
    """Estevez-Kulla "Charlie" sheen distribution ``(2 + 1/r) sin(theta_h)^(1/r) / (2 pi)``."""
    inv = 1.0 / rough
    sin2 = np.maximum(1.0 - cos_h * cos_h, 0.0)
    return (2.0 + inv) * sin2 ** (0.5 * inv) * (0.5 * INV_PI)


def ashikhmin_v(ci, co) -> np.ndarray:
    """Ashikhmin's sheen visibility ``1 / (4 (ci + co - ci co))`` (symmetric in ci, co)."""
    return 0.25 / np.maximum(ci + co - ci * co, EPS)


def brdf(wi, wo, p: dict) -> np.ndarray:
    """BRDF ``f`` (1/sr) ``[*S, 3]``.

    ``wi``, ``wo``: tuples ``(x, y, z)`` of arrays broadcasting to shape S, unit vectors in the
    shading frame. ``p``: parameters broadcasting to S: ``albedo``/``f0``/``sheen`` ``[..., 3]``
    given as channel-last arrays, ``alpha_t``, ``alpha_b``, ``sheen_rough`` scalars per sample.
    Returns 0 where either direction is below the shading horizon.
    """
    return np.stack(brdf_rgb(wi, wo, p), -1)


def brdf_rgb(wi, wo, p: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`brdf` as three channel planes ``(R, G, B)``, each ``[*S]`` float32.

    The fast path: every operation runs on contiguous scalar planes (a channel-last ``[..., 3]``
    layout makes numpy loop over an inner axis of length 3, several times slower). ``p`` may
    be :func:`prepare`'d once per view to skip recomputing per-sample colour constants.
    """
    ix, iy, iz = wi
    ox, oy, oz = wo
    ci = np.maximum(iz, 0.0)
    co = np.maximum(oz, 0.0)
    hx, hy, hz = ix + ox, iy + oy, iz + oz
    hl = np.sqrt(hx * hx + hy * hy + hz * hz)
    ok = hl > 1e-6
    inv = 1.0 / np.where(ok, hl, 1.0)
    hx, hy, hz = (
        np.where(ok, hx * inv, 0.0),
        np.where(ok, hy * inv, 0.0),
        np.where(ok, hz * inv, 1.0),
    )
    c_hi = np.clip(ix * hx + iy * hy + iz * hz, 0.0, 1.0)
    at, ab = p["alpha_t"], p["alpha_b"]
    d = ggx_d(hx, hy, hz, at, ab)
    g2 = 1.0 / (1.0 + smith_lambda(ix, iy, iz, at, ab) + smith_lambda(ox, oy, oz, at, ab))
    above = ((iz > 0) & (oz > 0)).astype(np.float32)
    spec = d * g2 * above / (4.0 * np.maximum(ci * co, EPS))  # [*S]
    q = p if "_k" in p else prepare(p)
    sh = None
    if q["_has_sheen"]:  # else skip the (costly) pow
        sh = charlie_d(hz, p["sheen_rough"]) * ashikhmin_v(ci, co) * above  # [*S]

    def m5(c):  # (1 - c)^5 (the Schlick weight), scalar per sample
        m = 1.0 - np.clip(c, 0.0, 1.0)
        m2 = m * m
        return m2 * m2 * m

    m_h, m_i, m_o = m5(c_hi), m5(ci), m5(co)
    out = []
    for c in range(3):
        k, a = q["_k"][c], q["_one_f0"][c]  # F = f0 + k m5 = 1 - a + k m5
        f = (1.0 - a + k * m_h) * spec
        lobe = q["_diffuse"][c] if sh is None else q["_diffuse"][c] + q["_sheen"][c] * sh
        f += (a - k * m_i) * (a - k * m_o) * lobe
        out.append(f.astype(np.float32, copy=False))
    return out[0], out[1], out[2]


def prepare(p: dict) -> dict:
    """``p`` plus per-sample colour constants as channel planes (``_k[c]``: Schlick slope
    ``min(1, max(f0) / 0.04) (1 - f0)``, ``_one_f0[c]``, ``_diffuse[c]``: ``(1 - max(sheen))
    albedo / pi``, ``_sheen[c]``, ``_has_sheen``). Call once per view for many lights."""
    f0 = np.asarray(p["f0"], np.float32)
    sheen = np.asarray(p["sheen"], np.float32)
    albedo = np.asarray(p["albedo"], np.float32)
    f0max = np.maximum(np.maximum(f0[..., 0], f0[..., 1]), f0[..., 2])
    smax = np.maximum(np.maximum(sheen[..., 0], sheen[..., 1]), sheen[..., 2])
    s = np.minimum(1.0, f0max / 0.04)

    def planes(fn):
        return [np.ascontiguousarray(fn(c), dtype=np.float32) for c in range(3)]

    return {
        **p,
        "_k": planes(lambda c: s * (1.0 - f0[..., c])),
        "_one_f0": planes(lambda c: 1.0 - f0[..., c]),
        "_diffuse": planes(lambda c: (1.0 - smax) * albedo[..., c] * INV_PI),
        "_sheen": planes(lambda c: sheen[..., c]),
        "_has_sheen": bool(np.any(sheen > 0)),
    }


def params(
    albedo=(0.5, 0.5, 0.5), f0=(0.0, 0.0, 0.0), alpha=(0.3, 0.3), sheen=(0, 0, 0), sheen_rough=0.5
) -> dict:
    """A homogeneous parameter dict for :func:`brdf` (scalars / RGB triples)."""
    return {
        "albedo": np.asarray(albedo, np.float32),
        "f0": np.asarray(f0, np.float32),
        "alpha_t": np.float32(alpha[0]),
        "alpha_b": np.float32(alpha[1]),
        "sheen": np.asarray(sheen, np.float32),
        "sheen_rough": np.float32(sheen_rough),
    }
