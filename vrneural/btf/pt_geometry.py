"""Triangle meshes of microgeometry for the path tracer (numpy only, no Mitsuba).

Coordinates are in tile units: the tile is the unit square ``[0, 1)^2`` in x (= material u) and
y (= v), z up (the local frame of docs/conventions.md section 1). A :class:`Part` is one mesh
with one BSDF (a Mitsuba plugin dict, see :mod:`vrneural.btf.pathtrace`); a preset builds a
list of parts whose union tiles periodically (geometry may stick out of the unit square: the
renderer surrounds the tile with copies of itself, so whatever sticks out of one copy is what
comes in from its neighbour).

Builders here: a periodic height field (:func:`heightfield`), tubes along polylines
(:func:`tube`: fibres, strands, threads), deformed ellipsoids (:func:`blob`: pebbles), prisms
with a tilted top (:func:`slab`: mosaic tiles), and :func:`merge` to combine meshes. Every
builder returns a :class:`Mesh` (vertices ``[N, 3]``, faces ``[F, 3]``, uv ``[N, 2]`` and
optionally exact vertex normals ``[N, 3]``, which keep shading continuous where copies of the
tile meet); faces are counter-clockwise seen from outside.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Mesh:
    """A triangle mesh: ``v [N, 3]``, ``f [F, 3]`` uint32, ``uv [N, 2]``, and ``n [N, 3]``
    exact unit vertex normals or None (then the renderer computes smooth ones, or uses face
    normals for a :class:`Part` that is not ``smooth``)."""

    v: np.ndarray
    f: np.ndarray
    uv: np.ndarray
    n: np.ndarray | None = None


@dataclass
class Part:
    """One mesh with one BSDF. ``bsdf``: a Mitsuba plugin dict whose values may be numpy
    arrays ``[H, W(, 3)]`` (``{"type": "bitmap", "data": array}``: a texture over the mesh's
    UVs). ``smooth``: interpolate vertex normals (else flat faces)."""

    mesh: Mesh
    bsdf: dict
    smooth: bool = True
    name: str = "part"


@dataclass
class Tile:
    """A preset's microgeometry: its parts and a short description (for the BTF header)."""

    parts: list[Part]
    about: str = ""
    extra: dict = field(default_factory=dict)

    def bounds(self) -> tuple[float, float]:
        """``(zmin, zmax)`` over every part."""
        z = np.concatenate([p.mesh.v[:, 2] for p in self.parts])
        return float(z.min()), float(z.max())

    def triangles(self) -> int:
        return int(sum(len(p.mesh.f) for p in self.parts))

    def fingerprint(self) -> str:
        """16 hex digits of a SHA-256 over every part's name, shading flag, mesh arrays and
        BSDF (its numbers and bitmaps): the same for the same material, different for a
        variant of a preset (other keywords) or another version of it."""
        h = hashlib.sha256()

        def feed(x) -> None:
            if isinstance(x, dict):
                for k in sorted(x):
                    h.update(f"<{k}>".encode())
                    feed(x[k])
            elif isinstance(x, list | tuple):
                h.update(b"[")
                for y in x:
                    feed(y)
                h.update(b"]")
            elif isinstance(x, np.ndarray):
                a = np.ascontiguousarray(x)
                h.update(f"{a.dtype.str}{a.shape}".encode() + a.tobytes())
            else:
                h.update(repr(x).encode())

        for p in self.parts:
            m = p.mesh
            feed([p.name, p.smooth, m.v, m.f, m.uv, "no normals" if m.n is None else m.n])
            feed(p.bsdf)
        return h.hexdigest()[:16]


def heightfield(h: np.ndarray, size: float = 1.0) -> Mesh:
    """A periodic height field ``h [N, N]`` (row i = y, UV units) as an ``(N + 1)^2``-vertex grid
    over ``[0, size]^2`` (vertices at cell corners, heights averaged from the four cells around
    each corner, wrapping), with periodic normals, so copies of the tile join without a seam in
    position or shading. UV = (x, y) / size."""
    h = np.asarray(h, np.float64)
    n = h.shape[0]
    corner = 0.25 * (h + np.roll(h, 1, 0) + np.roll(h, 1, 1) + np.roll(np.roll(h, 1, 0), 1, 1))
    c = np.pad(corner, ((0, 1), (0, 1)), mode="wrap")  # [N + 1, N + 1], periodic
    dx = (np.roll(corner, -1, 1) - np.roll(corner, 1, 1)) * (n / (2.0 * size))
    dy = (np.roll(corner, -1, 0) - np.roll(corner, 1, 0)) * (n / (2.0 * size))
    nrm = np.stack([-dx, -dy, np.ones_like(dx)], -1)
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    nrm = np.pad(nrm, ((0, 1), (0, 1), (0, 0)), "wrap")
    t = np.linspace(0.0, 1.0, n + 1)
    x, y = np.meshgrid(t * size, t * size, indexing="xy")
    v = np.stack([x, y, c], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a = (i * (n + 1) + j).ravel()
    b, d, e = a + 1, a + n + 1, a + n + 2
    faces = np.concatenate([np.stack([a, b, e], -1), np.stack([a, e, d], -1)])
    uv = np.stack([x, y], -1).reshape(-1, 2) / size
    return _mesh(v, faces, uv, nrm.reshape(-1, 3))


def _mesh(v, f, uv, n=None) -> Mesh:
    return Mesh(
        np.asarray(v, np.float32),
        np.asarray(f, np.uint32),
        np.asarray(uv, np.float32),
        None if n is None else np.asarray(n, np.float32),
    )


def tube(path, radius, ref, sides: int = 8) -> Mesh:
    """An open tube of ``sides`` segments around the polyline ``path [K, 3]`` with ``radius``
    (scalar or ``[K]``; tapering to 0 closes the end to a point). The cross-section's frame
    comes from the fixed direction ``ref`` (``[3]``, not along the path), so a periodic path
    gives the same ring at its two ends (copies join without a crack). UV: u runs along the
    tube (0..1), v around it. Normals: the exact ring directions (for a tapering tube tilted
    by the taper)."""
    path = np.asarray(path, np.float64)
    k = len(path)
    r = np.broadcast_to(np.asarray(radius, np.float64), (k,))
    t = np.gradient(path, axis=0)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    nn = np.asarray(ref, np.float64)[None] - t * (t @ np.asarray(ref, np.float64))[:, None]
    nn /= np.linalg.norm(nn, axis=1, keepdims=True)
    bb = np.cross(t, nn)
    ang = 2 * np.pi * np.arange(sides) / sides
    ring = np.cos(ang)[None, :, None] * nn[:, None] + np.sin(ang)[None, :, None] * bb[:, None]
    v = (path[:, None] + r[:, None, None] * ring).reshape(-1, 3)
    seg = np.linalg.norm(np.gradient(path, axis=0), axis=1)
    slope = -np.gradient(r) / np.maximum(seg, 1e-12)  # taper tilts the normal along the tube
    nrm = ring + slope[:, None, None] * t[:, None]
    nrm = (nrm / np.linalg.norm(nrm, axis=-1, keepdims=True)).reshape(-1, 3)
    s = np.arange(sides)
    rows = []
    for i in range(k - 1):
        a, c = i * sides + s, i * sides + (s + 1) % sides
        rows += [np.stack([a, c, c + sides], -1), np.stack([a, c + sides, a + sides], -1)]
    faces = np.concatenate(rows)
    arc = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    u = arc / max(arc[-1], 1e-12)
    uv = np.stack(np.broadcast_arrays(u[:, None], (s / sides)[None, :]), -1).reshape(-1, 2)
    return _mesh(v, faces, uv, nrm)


def _icosphere(level: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit icosphere: vertices ``[N, 3]``, faces ``[F, 3]`` (outward, counter-clockwise)."""
    p = (1 + 5**0.5) / 2
    v = [(-1, p, 0), (1, p, 0), (-1, -p, 0), (1, -p, 0), (0, -1, p), (0, 1, p)]
    v += [(0, -1, -p), (0, 1, -p), (p, 0, -1), (p, 0, 1), (-p, 0, -1), (-p, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4)]
    f += [(11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8)]
    f += [(3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(x, np.float64) / np.linalg.norm(x) for x in v]
    faces = np.array(f)
    cache: dict[tuple[int, int], int] = {}

    def mid(a: int, b: int) -> int:
        key = (min(a, b), max(a, b))
        if key not in cache:
            m = verts[a] + verts[b]
            verts.append(m / np.linalg.norm(m))
            cache[key] = len(verts) - 1
        return cache[key]

    for _ in range(level):
        cache.clear()
        new = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = np.array(new)
    return np.array(verts), faces


def blob(rng, centre, radii, level: int = 3, bumps: float = 0.15) -> Mesh:
    """A pebble: an icosphere scaled to ``radii`` (x, y, z), randomly rotated about z, with
    low-frequency bumps of relative size ``bumps``. UV: a planar xy projection around the
    centre (so a texture does not stretch at the top). Normals: computed by the renderer."""
    v, f = _icosphere(level)
    k = rng.normal(size=(4, 3))
    phase = rng.uniform(0, 2 * np.pi, 4)
    bump = sum(np.sin(v @ k[i] * 2.0 + phase[i]) for i in range(4)) / 4.0
    v = v * (1.0 + bumps * bump)[:, None] * np.asarray(radii, np.float64)
    a = rng.uniform(0, 2 * np.pi)
    rot = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    v = v @ rot.T + np.asarray(centre, np.float64)
    uv = v[:, :2] - np.asarray(centre, np.float64)[:2] + 0.5
    return _mesh(v, f, uv)


def slab(corners, z0: float, top, bevel: float = 0.0) -> Mesh:
    """A prism over the convex polygon ``corners [K, 2]`` (counter-clockwise) from ``z0`` up
    to the plane ``z = top[0] + top[1] (x - cx) + top[2] (y - cy)`` (a tilted top; ``(cx,
    cy)`` the polygon's centroid); ``bevel`` insets the top face by that much, its rim
    sloping down to the full outline ``bevel`` lower. Flat faces (no normals). UV: xy."""
    c = np.asarray(corners, np.float64)
    k = len(c)
    cen = c.mean(0)

    def ztop(p, drop=0.0):
        return top[0] + top[1] * (p[:, 0] - cen[0]) + top[2] * (p[:, 1] - cen[1]) - drop

    inner = cen + (c - cen) * (1 - bevel / max(np.linalg.norm(c - cen, axis=1).min(), 1e-9))
    ring_top = np.column_stack([inner, ztop(inner)])
    ring_mid = np.column_stack([c, ztop(c, bevel)])
    ring_bot = np.column_stack([c, np.full(k, z0)])
    v = np.concatenate([ring_top, ring_mid, ring_bot, [[*cen, ztop(cen[None])[0]]]])
    s = np.arange(k)
    s1 = (s + 1) % k
    faces = [np.stack([np.full(k, 3 * k), s, s1], -1)]  # top fan
    for lo, hi in ((k, 0), (2 * k, k)):  # rim (top ring -> mid ring), side (mid -> bottom)
        faces += [np.stack([hi + s, lo + s, lo + s1], -1), np.stack([hi + s, lo + s1, hi + s1], -1)]
    return _mesh(v, np.concatenate(faces), v[:, :2])


def merge(meshes) -> Mesh:
    """Concatenate meshes into one (normals kept only when every mesh has them)."""
    meshes = list(meshes)
    off = np.cumsum([0] + [len(m.v) for m in meshes[:-1]])
    has_n = all(m.n is not None for m in meshes)
    return _mesh(
        np.concatenate([m.v for m in meshes]),
        np.concatenate([m.f + o for m, o in zip(meshes, off, strict=True)]),
        np.concatenate([m.uv for m in meshes]),
        np.concatenate([m.n for m in meshes]) if has_n else None,
    )
