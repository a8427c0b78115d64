"""The last resort: triangles in pairs (two-triangle strips) on a grid of square cells.

Used only when charts cannot be packed (:mod:`vrneural.atlas.generate`); it always succeeds.
Triangles are paired with a neighbour across a shared edge (a greedy matching, vectorised), and
each pair fills one k x k cell of a regular grid: the shared edge is the cell's diagonal, so the
pair's shading is continuous across it; a triangle without a partner takes half a cell. Cells
are ``gap`` texels apart (``padding + 1``, at least 3, as charts), less when that does not fit,
and at worst smaller than a texel (then triangles share texels: counted in
``triangles_without_texels``). Texel density is not uniform here: every triangle gets the same
texel area whatever its size, and its shape is sheared to a right isosceles triangle.
"""

from __future__ import annotations

import numpy as np

#: greedy matching rounds (each pairs mutually chosen free neighbours)
MATCH_ROUNDS = 6


def pair_triangles(n_faces: int, fa: np.ndarray, fb: np.ndarray) -> np.ndarray:
    """[F] int: each face's partner across a shared edge, or -1 (greedy matching)."""
    mate = np.full(n_faces, -1, np.int64)
    a = np.concatenate([fa, fb])
    b = np.concatenate([fb, fa])
    for _ in range(MATCH_ROUNDS):
        free = (mate[a] < 0) & (mate[b] < 0)
        a, b = a[free], b[free]
        if not len(a):
            break
        choice = np.full(n_faces, n_faces, np.int64)
        np.minimum.at(choice, a, b)  # each face proposes to its lowest free neighbour
        both = np.flatnonzero(
            (choice < n_faces) & (choice[np.minimum(choice, n_faces - 1)] == np.arange(n_faces))
        )
        mate[both] = choice[both]
    return mate


def _shared(fi: np.ndarray, fj: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For face rows ``fi``, ``fj`` [P, 3] (welded vertex ids) sharing an edge: the corner
    index (0-2) in ``fi`` of the vertex not on the shared edge, and the corners in ``fj``
    of the shared edge's two vertices (in the order they follow the lone corner in ``fi``)."""
    in_j = (fi[:, :, None] == fj[:, None, :]).any(2)  # [P, 3]
    lone = np.argmin(in_j, axis=1)
    u = fi[np.arange(len(fi)), (lone + 1) % 3]
    v = fi[np.arange(len(fi)), (lone + 2) % 3]
    cu = np.argmax(fj == u[:, None], axis=1)
    cv = np.argmax(fj == v[:, None], axis=1)
    return lone, cu, cv


def strip_layout(welded: np.ndarray, fa: np.ndarray, fb: np.ndarray, R: int, padding: int):
    """Corner texel coordinates [F, 3, 2] and cell side (texels) of the strip packing of faces
    ``welded`` [F, 3] (vertex ids welded by position) with adjacency ``(fa, fb)``."""
    n = len(welded)
    mate = pair_triangles(n, fa, fb)
    # a pair is two triangles with exactly two (welded) vertices in common; others go single
    p = np.flatnonzero(mate > np.arange(n))
    common = (welded[p][:, :, None] == welded[mate[p]][:, None, :]).any(2).sum(1)
    broken = p[common != 2]
    mate[mate[broken]] = -1
    mate[broken] = -1
    first = np.flatnonzero((mate < 0) | (np.arange(n) < mate))  # one cell per pair or single
    cells = len(first)
    side, gap, per_row = _grid(cells, R, padding)
    cx = (np.arange(cells) % per_row) * (side + gap) + gap / 2
    cy = (np.arange(cells) // per_row) * (side + gap) + gap / 2
    out = np.zeros((n, 3, 2))
    corner = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])  # lone, u, v of the first face
    paired = mate[first] >= 0
    i = first
    lone, cu, cv = (np.zeros(len(i), np.int64) for _ in range(3))
    if paired.any():
        lone[paired], cu[paired], cv[paired] = _shared(welded[i[paired]], welded[mate[i[paired]]])
    base = np.stack([cx, cy], 1)[:, None, :]
    for k in range(3):  # corner k of face i: lone -> (0, 0), next -> (1, 0), next -> (0, 1)
        out[i, (lone + k) % 3] = base[:, 0] + side * corner[k]
    j = mate[i[paired]]
    if len(j):
        pj = np.arange(len(i))[paired]
        lone_p = 3 - cu[paired] - cv[paired]
        out[j, cu[paired]] = base[pj, 0] + side * np.array([1.0, 0.0])
        out[j, cv[paired]] = base[pj, 0] + side * np.array([0.0, 1.0])
        out[j, lone_p] = base[pj, 0] + side * np.array([1.0, 1.0])
    return out, side


def _grid(cells: int, R: int, padding: int) -> tuple[float, float, int]:
    """``(side, gap, cells per row)`` of the largest square cells that fit ``cells`` cells
    into R x R."""
    for gap in (max(padding + 1, 3), 1, 0):
        for side in range(R, 0, -1):
            per = R // (side + gap)
            if per and -(-cells // per) * (side + gap) <= R:
                return float(side), float(gap), per
    per = int(np.ceil(np.sqrt(cells)))
    return R / per, 0.0, per
