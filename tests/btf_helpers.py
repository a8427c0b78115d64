"""BTF test fixtures: a UBO2014 file writer, a flat homogeneous tile and the analytic
Lambertian BTF (what the physics and import tests compare against)."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from vrneural.btf.heightfield import Maps
from vrneural.btf.ubo2014 import _COMMON


def lambert_btf(albedo, wi_z) -> np.ndarray:
    """Analytic flat Lambertian BTF ``albedo / pi * wi.z`` (the convention's reference)."""
    return np.asarray(albedo, np.float64) / np.pi * max(float(wi_z), 0.0)


def flat_maps(
    n: int,
    albedo=(0.5, 0.5, 0.5),
    f0=(0.0, 0.0, 0.0),
    alpha=(0.3, 0.3),
    angle=0.0,
    sheen=(0.0, 0.0, 0.0),
    sheen_rough=0.5,
) -> Maps:
    """A flat, homogeneous patch (for tests: it must reproduce the analytic BRDF)."""

    def full(v, k=None):
        shape = (n, n) if k is None else (n, n, k)
        return np.broadcast_to(np.asarray(v, np.float32), shape).copy()

    return Maps(
        height=full(0.0),
        albedo=full(albedo, 3),
        f0=full(f0, 3),
        alpha_t=full(alpha[0]),
        alpha_b=full(alpha[1]),
        angle=full(angle),
        sheen=full(sheen, 3),
        sheen_rough=full(sheen_rough),
    )


def write_dfmf(path, values: np.ndarray, light_angles: np.ndarray, view_angles: np.ndarray):
    """Write a UBO2014-style "!DFMF08FC" file (for tests). ``values``: ``[L, V, H, W, 3]`` RGB
    (``L == V``, as btf.hh's DFMF reader requires); angles ``[N, 2]`` (theta, phi) radians."""
    L, V, H, W, _ = values.shape
    if L != V:
        raise ValueError("DFMF needs as many views as lights")
    out = bytearray(b"!DFMF08FC")
    out += _COMMON.pack(_COMMON.size, 1, b"vrneural test", b"none", b"none", 1.0, 1, 1, 1)
    out += struct.pack("<I", V)
    for v in range(V):
        out += struct.pack("<2fI", *view_angles[v], L)
        for li in range(L):
            out += struct.pack("<2f", *light_angles[li])
    out += struct.pack("<II", W, H)
    k = min(L * V, H * W)
    out += struct.pack("<II3f9f", k, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1)
    flipped = values[:, :, ::-1]  # stored bottom-up; btf.hh flips rows on load
    for c in range(3):
        # rows: lv = view * L + light; columns: xy = y * W + x
        a = np.transpose(flipped[..., c], (1, 0, 2, 3)).reshape(V * L, H * W).astype(np.float64)
        u, s, vt = np.linalg.svd(a, full_matrices=False)
        out += struct.pack("<BIII", 4, k, V * L, H * W)
        out += s[:k].astype("<f4").tobytes()
        out += np.ascontiguousarray(u[:, :k]).astype("<f4").tobytes()
        out += np.ascontiguousarray((s[:k, None] * vt[:k]).T).astype("<f4").tobytes()
    Path(path).write_bytes(bytes(out))
