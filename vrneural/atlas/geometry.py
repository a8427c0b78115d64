"""Mesh validation and the per-vertex shading frame: normals, material-UV tangents, box UVs.

Everything here is numpy only. :func:`make_mesh` is the one way a :class:`Mesh` is assembled
(loaded files and built-in meshes both go through it), so the conventions of
:mod:`vrneural.atlas.types` hold for every mesh:

- NaN/Inf positions, no faces, or face indices out of range -> :class:`VrnError` (one line).
- Degenerate triangles (a repeated index or zero 3D area) are *skipped* with a counted
  :class:`MeshWarning`; ``make_mesh(..., drop_degenerate=False)`` keeps them instead.
- Normals: kept when given and finite, else computed with a crease angle
  (:data:`CREASE_DEG`, 60 degrees by default, as Unity's importer): each triangle corner gets
  the area-weighted sum of the normals of the triangles around its position (over all vertices
  at that position, so UV seams do not crease the shading) that are within the crease angle of
  its own triangle's normal. Vertices whose corners disagree are split, so a cube's edges are
  sharp and a sphere stays smooth; 180 smooths everything, 0 gives flat facets.
- Tangents: MikkTSpace-like. Each triangle's tangent/bitangent come from its material-UV
  derivatives, normalised and weighted by the corner angle, accumulated per vertex,
  Gram-Schmidt orthogonalised against the normal; ``w = sign(dot(cross(n, t), b))``.
"""

from __future__ import annotations

import warnings

import numpy as np

from vrneural.atlas.types import Mesh
from vrneural.errors import VrnError, count
from vrneural.warn import VrnWarning

#: Default crease angle (degrees) for meshes without normals: adjacent triangles meeting at a
#: sharper angle than this are shaded with separate normals (a hard edge)
CREASE_DEG = 60.0

#: Relative 3D area below which a triangle counts as degenerate (times the mean edge^2).
DEGENERATE_REL_AREA = 1e-12


class MeshWarning(VrnWarning):
    """A recoverable mesh problem (e.g. skipped degenerate triangles), with a count; printed as
    one line, ``warning: <message>`` (:mod:`vrneural.warn`)."""


#: The largest vertex coordinate (metres) accepted: squared distances of anything farther
#: overflow float32 (3.4e38) in the shaders, and positions past 3.4e38 become Inf outright
MAX_COORD = 1e18


def check_geometry(name: str, pos: np.ndarray, fac: np.ndarray) -> None:
    """Raise :class:`VrnError` (one line, naming the mesh) unless ``pos`` is a finite ``[V, 3]``
    array and ``fac`` a non-empty ``[F, 3]`` array of vertex indices in ``[0, V)``."""
    if pos.ndim != 2 or pos.shape[1] != 3:
        raise VrnError(f"{name}: positions have shape {list(pos.shape)}, expected [V, 3]")
    if fac.size == 0:
        raise VrnError(f"{name}: mesh has no faces (only triangle meshes are supported)")
    if fac.ndim != 2 or fac.shape[1] != 3:
        raise VrnError(f"{name}: faces have shape {list(fac.shape)}, expected [F, 3] triangles")
    bad = ~np.isfinite(pos).all(axis=1)
    if bad.any():
        n = int(bad.sum())
        raise VrnError(
            f"{name}: {count(n, 'vertex', 'vertices')} {'has a' if n == 1 else 'have'} NaN/Inf "
            f"position{'s' if n > 1 else ''} "
            f"(the first is vertex index {int(np.argmax(bad))}, counted from 0)"
        )
    big = np.abs(pos).max(axis=1) > MAX_COORD
    if big.any():
        i = int(np.argmax(big))
        n = int(big.sum())
        raise VrnError(
            f"{name}: {count(n, 'vertex', 'vertices')} {'lies' if n == 1 else 'lie'} beyond "
            f"{MAX_COORD:.0e} m of the origin (the first is vertex index {i}, counted from 0, "
            f"at {np.abs(pos[i]).max():.3g}); "
            "float32 shading overflows there: scale or move the mesh"
        )
    if fac.min() < 0 or fac.max() >= len(pos):
        raise VrnError(
            f"{name}: face indices out of range [{int(fac.min())}, {int(fac.max())}]; "
            f"allowed [0, {len(pos) - 1}]"
        )


def make_mesh(
    name: str,
    positions: np.ndarray,
    faces: np.ndarray,
    uv: np.ndarray | None = None,
    normals: np.ndarray | None = None,
    drop_degenerate: bool = True,
    crease_deg: float = CREASE_DEG,
    lightmap_uv: np.ndarray | None = None,
    uv_source: str = "file",
) -> Mesh:
    """Validate arrays and build a :class:`Mesh` with normals and tangents.

    positions: [V, 3] metres; faces: [F, 3] int; uv: [V, 2] material UV or None (then
    :func:`box_uv` generates it, splitting vertices); normals: [V, 3] or None (then
    :func:`creased_normals` computes them with ``crease_deg``, splitting vertices at creases);
    lightmap_uv: [V, 2] the asset's lightmap UV set or None (NaN/Inf or a wrong shape ->
    :class:`VrnError`); uv_source: where ``uv`` came from ("file", "builtin"; "box" when
    generated here).
    """
    if not (isinstance(crease_deg, (int, float)) and 0.0 <= crease_deg <= 180.0):
        raise VrnError(f"{name}: crease angle {crease_deg!r} is out of range [0, 180] degrees")
    pos = np.asarray(positions, dtype=np.float64)
    fac = np.asarray(faces)
    check_geometry(name, pos, fac)
    fac = fac.astype(np.int64)
    if uv is not None:
        uv = np.asarray(uv, dtype=np.float64)
        if uv.shape != (len(pos), 2) or not np.isfinite(uv).all():
            uv = None  # unusable material UVs: regenerate (documented in load_mesh)
    lm = None if lightmap_uv is None else check_uv(name, "lightmap UV", lightmap_uv, len(pos))
    if normals is not None:
        normals = np.asarray(normals, dtype=np.float64)
        if normals.shape != (len(pos), 3) or not np.isfinite(normals).all():
            normals = None
    degen = degenerate_faces(pos, fac)
    if degen.any() and drop_degenerate:
        warnings.warn(
            f"{name}: skipped {count(int(degen.sum()), 'degenerate triangle')} of {len(fac)}",
            MeshWarning,
            stacklevel=2,
        )
        fac = fac[~degen]
        if len(fac) == 0:
            n = int(degen.sum())
            every = "its only triangle is" if n == 1 else f"all {n} triangles are"
            raise VrnError(f"{name}: {every} degenerate")
    if uv is None:
        src, fac, uv = box_uv(pos, fac)
        pos, uv_source = pos[src], "box"
        normals = None if normals is None else normals[src]
        lm = None if lm is None else lm[src]
    if normals is None:
        src, fac, normals = creased_normals(pos, fac, crease_deg)
        pos, uv = pos[src], uv[src]
        lm = None if lm is None else lm[src]
    else:
        normals = _normalize(normals, fallback=vertex_normals(pos, fac))
    tangents = vertex_tangents(pos, fac, uv, normals)
    return Mesh(
        name=name,
        positions=pos.astype(np.float32),
        faces=fac.astype(np.uint32),
        normals=normals.astype(np.float32),
        tangents=tangents.astype(np.float32),
        uv=uv.astype(np.float32),
        lightmap_uv=None if lm is None else lm.astype(np.float32),
        uv_source=uv_source,
    )


def check_uv(name: str, what: str, uv, n_vertices: int) -> np.ndarray:
    """``uv`` as float64 [V, 2]; :class:`VrnError` (one line: the mesh, the UV set, the count)
    for a wrong shape or NaN/Inf values."""
    a = np.asarray(uv, dtype=np.float64)
    if a.shape != (n_vertices, 2):
        raise VrnError(
            f"{name}: {what} has shape {list(a.shape)}, expected [{n_vertices}, 2] (one per vertex)"
        )
    bad = ~np.isfinite(a).all(axis=1)
    if bad.any():
        n = int(bad.sum())
        raise VrnError(
            f"{name}: {what} of {count(n, 'vertex', 'vertices')} {'is' if n == 1 else 'are'} "
            f"NaN/Inf (the first is vertex index {int(np.argmax(bad))}, counted from 0)"
        )
    return a


def degenerate_faces(pos: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """[F] bool: a repeated vertex index or a 3D area below the relative threshold."""
    rep = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 0] == faces[:, 2])
    p0, p1, p2 = (pos[faces[:, k]] for k in range(3))
    area2 = np.linalg.norm(np.cross(p1 - p0, p2 - p0), axis=1)
    edge2 = (
        np.sum((p1 - p0) ** 2, axis=1) + np.sum((p2 - p1) ** 2, axis=1) + np.sum((p0 - p2) ** 2, 1)
    )
    return rep | (area2 <= DEGENERATE_REL_AREA * np.maximum(edge2, 1e-300))


def _normalize(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=1, keepdims=True)
    ok = n[:, 0] > 1e-20
    out = fallback.copy()
    out[ok] = v[ok] / n[ok]
    return out


def vertex_normals(pos: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """[V, 3] unit normals: area-weighted face normals summed over coincident positions."""
    return _smooth_normals(pos, faces, *_welded_face_normals(pos, faces))


def _welded_face_normals(pos: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(fn [F, 3], weld [V])``: area-weighted (unnormalised) face normals, and for every
    vertex the index of its position among the distinct positions."""
    fn = np.cross(pos[faces[:, 1]] - pos[faces[:, 0]], pos[faces[:, 2]] - pos[faces[:, 0]])
    _, weld = np.unique(pos, axis=0, return_inverse=True)
    return fn, weld.reshape(-1)


def _smooth_normals(pos, faces, fn, weld) -> np.ndarray:
    acc = np.zeros((weld.max() + 1, 3))
    for k in range(3):
        np.add.at(acc, weld[faces[:, k]], fn)
    up = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (len(pos), 3))
    return _normalize(acc[weld], fallback=np.array(up))


#: Most (corner, neighbour-corner) pairs :func:`creased_normals` holds at once (memory bound
#: for vertices of very high valence, e.g. the centre of a fan)
_PAIR_CHUNK = 1 << 22


def creased_normals(
    pos: np.ndarray, faces: np.ndarray, crease_deg: float = CREASE_DEG
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normals with a crease angle; vertices split where their corners' normals differ.

    Each triangle corner gets the area-weighted sum of the normals of all triangles around its
    position (welded over vertices at the same position) whose unit normal is within
    ``crease_deg`` of its own triangle's; a vertex whose corners get different sums is split.
    Returns ``(src [V'], faces [F, 3], normals [V', 3])``: new vertex ``i`` copies old vertex
    ``src[i]``. The first ``V`` entries are the old vertices in order, so a mesh without
    creases keeps its indexing. ``crease_deg >= 180`` is :func:`vertex_normals` exactly.
    """
    nv = len(pos)
    if crease_deg >= 180.0:
        return np.arange(nv), faces, vertex_normals(pos, faces)
    fn, weld = _welded_face_normals(pos, faces)
    fl = np.linalg.norm(fn, axis=1, keepdims=True)
    fu = np.where(fl > 1e-300, fn / np.maximum(fl, 1e-300), 0.0)
    cv = faces.reshape(-1)  # corner -> vertex
    cf = np.repeat(np.arange(len(faces)), 3)  # corner -> face
    order = np.argsort(weld[cv], kind="stable")  # corners grouped by position
    grp = weld[cv][order]
    start = np.flatnonzero(np.r_[True, grp[1:] != grp[:-1]])
    size = np.diff(np.r_[start, len(grp)])
    g_of = np.repeat(np.arange(len(start)), size)  # sorted corner -> its group
    n_pair = size[g_of]  # pairs each sorted corner makes
    cos_min = np.cos(np.radians(crease_deg)) - 1e-9
    acc = np.zeros((len(cv), 3))
    ends = np.cumsum(n_pair)
    lo = 0
    while lo < len(cv):  # chunks of sorted corners holding at most _PAIR_CHUNK pairs
        base = ends[lo - 1] if lo else 0
        hi = max(lo + 1, int(np.searchsorted(ends, base + _PAIR_CHUNK, side="right")))
        me = np.repeat(np.arange(lo, hi), n_pair[lo:hi])
        first = np.repeat(start[g_of[lo:hi]] - (ends[lo:hi] - n_pair[lo:hi] - base), n_pair[lo:hi])
        other = first + np.arange(len(me))  # partner (sorted index) of each pair
        f_me, f_other = cf[order[me]], cf[order[other]]
        keep = np.sum(fu[f_me] * fu[f_other], axis=1) >= cos_min
        w = fn[f_other] * keep[:, None]
        for k in range(3):
            acc[lo:hi, k] = np.bincount(me - lo, weights=w[:, k], minlength=hi - lo)
        lo = hi
    cn = np.empty_like(acc)
    cn[order] = acc
    cn = _normalize(cn, fallback=np.where(fl[cf] > 1e-300, fu[cf], [[0.0, 0.0, 1.0]]))
    key = np.column_stack([cv, np.ascontiguousarray(cn).view(np.int64)])
    ukey, rep, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    is_first = np.r_[True, ukey[1:, 0] != ukey[:-1, 0]]  # ukey sorted by vertex first
    new = np.where(is_first, ukey[:, 0], nv + np.cumsum(~is_first) - 1)
    src = np.r_[np.arange(nv), ukey[~is_first, 0]]
    normals = np.zeros((len(src), 3))
    normals[:nv] = _smooth_normals(pos, faces, fn, weld)  # for vertices no face uses
    normals[new] = cn[rep]
    return src, new[inv.reshape(-1)].reshape(-1, 3), normals


def _corner_angles(pos: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """[F, 3] interior angle at each corner (radians)."""
    out = np.zeros(faces.shape)
    for k in range(3):
        a = pos[faces[:, (k + 1) % 3]] - pos[faces[:, k]]
        b = pos[faces[:, (k + 2) % 3]] - pos[faces[:, k]]
        na = np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1)
        cos = np.sum(a * b, axis=1) / np.maximum(na, 1e-300)
        out[:, k] = np.arccos(np.clip(cos, -1.0, 1.0))
    return out


def vertex_tangents(
    pos: np.ndarray, faces: np.ndarray, uv: np.ndarray, normals: np.ndarray
) -> np.ndarray:
    """[V, 4]: unit tangent along +u of ``uv`` orthogonal to the normal, and bitangent sign."""
    p0, p1, p2 = (pos[faces[:, k]] for k in range(3))
    t0, t1, t2 = (uv[faces[:, k]] for k in range(3))
    e1, e2 = p1 - p0, p2 - p0
    d1, d2 = t1 - t0, t2 - t0
    r = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    ok = np.abs(r) > 1e-20
    rs = np.where(ok, r, 1.0)[:, None]
    ft = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) / rs
    fb = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) / rs
    ft, fb = ft * ok[:, None], fb * ok[:, None]
    ft /= np.maximum(np.linalg.norm(ft, axis=1, keepdims=True), 1e-300)
    fb /= np.maximum(np.linalg.norm(fb, axis=1, keepdims=True), 1e-300)
    ang = _corner_angles(pos, faces)
    acc_t = np.zeros((len(pos), 3))
    acc_b = np.zeros((len(pos), 3))
    for k in range(3):
        np.add.at(acc_t, faces[:, k], ft * ang[:, k : k + 1])
        np.add.at(acc_b, faces[:, k], fb * ang[:, k : k + 1])
    n = normals
    t = acc_t - n * np.sum(acc_t * n, axis=1, keepdims=True)
    t = _normalize(t, fallback=_any_perpendicular(n))
    w = np.where(np.sum(np.cross(n, t) * acc_b, axis=1) < 0.0, -1.0, 1.0)
    return np.concatenate([t, w[:, None]], axis=1)


def _any_perpendicular(n: np.ndarray) -> np.ndarray:
    """[V, 3] a unit vector perpendicular to each ``n`` (for vertices without UV derivatives)."""
    axis = np.where((np.abs(n[:, 0]) < 0.9)[:, None], [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t = axis - n * np.sum(axis * n, axis=1, keepdims=True)
    return t / np.linalg.norm(t, axis=1, keepdims=True)


def box_uv(pos: np.ndarray, faces: np.ndarray, scale: float | None = None):
    """Material UVs by box (cube) projection, vertices split between projections:
    ``(src [V'], faces [F, 3], uv [V', 2])``, new vertex ``i`` a copy of ``src[i]``.

    Each face is projected along the axis its normal is most aligned with (x -> (z, y),
    y -> (x, z), z -> (x, y)), so every face gets an undistorted planar UV. ``uv = coord /
    scale`` with ``scale`` = the largest bounding-box extent by default, so the whole object
    spans about one BTF tile.
    """
    fn = np.cross(pos[faces[:, 1]] - pos[faces[:, 0]], pos[faces[:, 2]] - pos[faces[:, 0]])
    axis = np.argmax(np.abs(fn), axis=1)
    ext = np.ptp(pos, axis=0)
    s = float(scale or max(float(ext.max()), 1e-9))
    # one output vertex per distinct (input vertex, projection axis)
    key = faces * 3 + axis[:, None]
    uniq, inv = np.unique(key.reshape(-1), return_inverse=True)
    src, ax = uniq // 3, uniq % 3
    rel = (pos[src] - pos.min(axis=0)) / s
    pick = np.array([[2, 1], [0, 2], [0, 1]])[ax]
    return src, inv.reshape(-1, 3), np.take_along_axis(rel, pick, axis=1)
