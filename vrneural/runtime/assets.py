"""Meshes and atlases for the runtime.

Uses :mod:`vrneural.atlas` (``builtin_mesh``, ``load_mesh``, ``build_atlas``) when it provides
them; otherwise falls back to the small built-ins here (``plane``, ``sphere``) whose material UVs
are already a non-overlapping parameterization, so the atlas is that UV layout shrunk into
``[pad, 1 - pad]`` with a triangle-ID texture rasterized on the CPU and dilated into a gutter.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vrneural.atlas.types import EMPTY, Atlas, Mesh
from vrneural.errors import VrnError

FALLBACK_MESHES = ("plane", "sphere")


def _atlas_api():
    try:
        import vrneural.atlas as a
    except ImportError:  # pragma: no cover
        return None
    if all(hasattr(a, k) for k in ("builtin_mesh", "build_atlas", "load_mesh")):
        return a
    return None


#: Fraction of a mesh's triangles that may own no atlas texel before `run` and `atlas` warn
LOST_TRIANGLES = 0.5


def lost_triangles(stats: dict, res: int, shown_as: str) -> str | None:
    """The warning for an atlas (its ``stats``) in which more than :data:`LOST_TRIANGLES` of
    the triangles own no texel at ``res``^2, else None; ``shown_as`` says what those triangles
    show instead."""
    lost, n_tri = int(stats.get("triangles_without_texels", 0)), int(stats.get("triangles", 0))
    if not n_tri or lost <= LOST_TRIANGLES * n_tri:
        return None
    return (
        f"{lost} of {n_tri} triangles own no texel at {res}^2 (too small in the atlas; {shown_as})"
    )


def collapsed_triangles(stats: dict) -> str | None:
    """The warning for an atlas (its ``stats``) in which xatlas gave triangles no area (each
    far smaller than the mesh, or degenerate), else None. Unlike texel-less triangles this is
    not a matter of resolution: every such triangle shows the one texel its uvs fall on."""
    n, n_tri = int(stats.get("zero_area_triangles", 0)), int(stats.get("triangles", 0))
    if not n:
        return None
    return (
        f"{n} of {n_tri} triangles have no area in the atlas (far smaller than the rest of the "
        "mesh, so xatlas flattened them; each shows one texel's shading at any resolution): "
        "make such small parts separate objects or meshes"
    )


def builtin_names() -> tuple[str, ...]:
    a = _atlas_api()
    return tuple(a.BUILTIN_MESHES) if a is not None else FALLBACK_MESHES


def get_mesh(
    spec: str, base: Path | None = None, field: str = "mesh", crease_deg: float | None = None
) -> Mesh:
    """A built-in mesh by name, or a mesh file (relative to ``base``).

    ``crease_deg``: the crease angle for computed normals (None: smooth built-ins, 60 degrees
    for files without normals; see :mod:`vrneural.atlas.geometry`).

    A file holding several meshes (a glTF scene, say) needs the one to use named after a
    colon, ``"room.glb:chair"`` (the names ``vrneural atlas`` prints), or its index,
    ``"room.glb:0"``.
    """
    a = _atlas_api()
    if spec in builtin_names():
        return a.builtin_mesh(spec, crease_deg) if a is not None else fallback_mesh(spec)

    def where(s: str) -> Path:
        p = Path(s)
        return base / p if base is not None and not p.is_absolute() else p

    p, part = where(spec), None
    if not p.is_file() and ":" in spec:
        head, tail = spec.rsplit(":", 1)
        if where(head).is_file():
            p, part = where(head), tail
    if not p.is_file():
        looked = f"no such file ({p})" if base is not None and str(p) != spec else "no such file"
        raise VrnError(
            f"{field} = {spec!r}: {looked} and not a built-in mesh ({', '.join(builtin_names())})"
        )
    if a is None:
        raise VrnError(f"{field} = {spec!r}: mesh files need vrneural.atlas (not available)")
    meshes = a.load_mesh(p, crease_deg)
    names = [m.name.split(":", 1)[1] if ":" in m.name else str(i) for i, m in enumerate(meshes)]
    if part is None:
        if len(meshes) == 1:
            return meshes[0]
        raise VrnError(
            f"{field} = {spec!r} holds {len(meshes)} meshes ({', '.join(names[:6])}"
            f"{', ...' if len(names) > 6 else ''}); name one, e.g. "
            f"{spec + ':' + names[0]!r}, one object each"
        )
    if len(meshes) == 1 and part != "0" and part not in names:
        raise VrnError(
            f"{field} = {spec!r}: {p.name} holds one mesh (its objects are merged on loading); "
            f"write {spec.rsplit(':', 1)[0]!r}"
        )
    if part in names:
        return meshes[names.index(part)]
    if part.isdigit() and int(part) < len(meshes):
        return meshes[int(part)]
    raise VrnError(
        f"{field} = {spec!r}: {p.name} has no mesh {part!r}; it has {', '.join(names[:6])}"
        f"{', ...' if len(names) > 6 else ''} (or an index 0-{len(meshes) - 1})"
    )


def get_atlas(
    mesh: Mesh, resolution: int, padding: int = 2, atlas_uv: str = "auto", progress: bool = False
) -> Atlas:
    a = _atlas_api()
    if a is not None:
        return a.build_atlas(
            mesh, resolution, padding=padding, atlas_uv=atlas_uv, progress=progress
        )
    return fallback_atlas(mesh, resolution, padding)


def tangents_from_uv(pos, faces, normals, uv) -> np.ndarray:
    """Per-vertex tangents ``[V, 4]`` along +u of ``uv`` (area-weighted, Gram-Schmidt)."""
    f = faces.astype(np.int64)
    p0, p1, p2 = pos[f[:, 0]], pos[f[:, 1]], pos[f[:, 2]]
    t0, t1, t2 = uv[f[:, 0]], uv[f[:, 1]], uv[f[:, 2]]
    e1, e2 = p1 - p0, p2 - p0
    d1, d2 = t1 - t0, t2 - t0
    r = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    r = np.where(np.abs(r) < 1e-20, 1e-20, r)
    tu = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) / r[:, None]
    tv = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) / r[:, None]
    acc_u = np.zeros_like(pos, dtype=np.float64)
    acc_v = np.zeros_like(pos, dtype=np.float64)
    for k in range(3):
        np.add.at(acc_u, f[:, k], tu)
        np.add.at(acc_v, f[:, k], tv)
    t = acc_u - normals * (acc_u * normals).sum(1, keepdims=True)
    ln = np.linalg.norm(t, axis=1, keepdims=True)
    t = np.where(ln > 1e-12, t / np.maximum(ln, 1e-12), [[1.0, 0, 0]])
    w = np.where((np.cross(normals, t) * acc_v).sum(1) < 0, -1.0, 1.0)
    return np.concatenate([t, w[:, None]], 1).astype(np.float32)


def fallback_mesh(name: str) -> Mesh:
    """``plane``: 1 m square in xz facing +y (a floor tile); ``sphere``: radius 0.5 m UV sphere."""
    if name == "plane":
        n = 8
        g = np.linspace(0, 1, n + 1)
        u, v = np.meshgrid(g, g)
        pos = np.stack([u.ravel() - 0.5, 0 * u.ravel(), v.ravel() - 0.5], 1)
        uv = np.stack([u.ravel(), v.ravel()], 1)
    elif name == "sphere":
        nu, nv = 48, 24
        u, v = np.meshgrid(np.linspace(0, 1, nu + 1), np.linspace(0, 1, nv + 1))
        th, ph = v.ravel() * np.pi, u.ravel() * 2 * np.pi
        pos = 0.5 * np.stack([np.sin(th) * np.cos(ph), np.cos(th), -np.sin(th) * np.sin(ph)], 1)
        uv = np.stack([u.ravel(), v.ravel()], 1)
        n = None
    else:
        raise VrnError(f"mesh = {name!r} is not a built-in mesh ({', '.join(FALLBACK_MESHES)})")
    cols = (nu if name == "sphere" else n) + 1
    rows = nv if name == "sphere" else n
    faces = []
    for r in range(rows):
        for c in range(cols - 1):
            a, b = r * cols + c, r * cols + c + 1
            faces += [[a, cols + a, b], [b, cols + a, cols + b]]
    faces = np.asarray(faces, np.uint32)
    if name == "plane":
        normals = np.tile([0.0, 1.0, 0.0], (len(pos), 1))
    else:
        normals = pos / np.linalg.norm(pos, axis=1, keepdims=True)
    # drop triangles with zero area (sphere poles)
    p = pos[faces.astype(np.int64)]
    area = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    faces = faces[area > 1e-12]
    tan = tangents_from_uv(pos, faces, normals, uv)
    return Mesh(
        name,
        pos.astype(np.float32),
        faces,
        normals.astype(np.float32),
        tan,
        uv.astype(np.float32),
    )


def fallback_atlas(mesh: Mesh, resolution: int, padding: int = 2) -> Atlas:
    """Atlas of a mesh whose material UVs in ``[0, 1]`` do not overlap (see module doc)."""
    from scipy import ndimage

    R = resolution
    m = padding / R
    uva = (m + (1 - 2 * m) * mesh.uv).astype(np.float32)
    ids = np.full((R, R), EMPTY, np.uint32)
    f = mesh.faces.astype(np.int64)
    px = uva[f] * R - 0.5  # [F, 3, 2] in texel-centre coordinates
    for i in range(len(f)):
        a, b, c = px[i]
        lo = np.floor(px[i].min(0)).astype(int)
        hi = np.ceil(px[i].max(0)).astype(int)
        xs = np.arange(max(lo[0], 0), min(hi[0], R - 1) + 1)
        ys = np.arange(max(lo[1], 0), min(hi[1], R - 1) + 1)
        if not len(xs) or not len(ys):
            continue
        X, Y = np.meshgrid(xs, ys)
        v0, v1 = b - a, c - a
        den = v0[0] * v1[1] - v1[0] * v0[1]
        if abs(den) < 1e-12:
            continue
        l1 = ((X - a[0]) * v1[1] - v1[0] * (Y - a[1])) / den
        l2 = (v0[0] * (Y - a[1]) - (X - a[0]) * v0[1]) / den
        inside = (l1 >= -1e-6) & (l2 >= -1e-6) & (l1 + l2 <= 1 + 1e-6)
        ids[Y[inside], X[inside]] = i
    empty = ids == EMPTY
    if empty.all():
        raise VrnError(f"mesh {mesh.name!r}: no triangle covers a texel at resolution {R}")
    dist, (iy, ix) = ndimage.distance_transform_edt(empty, return_indices=True)
    grow = empty & (dist <= padding + 0.5)
    ids[grow] = ids[iy[grow], ix[grow]]
    return Atlas(mesh, uva, ids, R, padding, {"fallback": True})
