"""Built-in test meshes (procedural, deterministic), in metres, y up, with material UVs.

All are smooth surfaces: their normals are smoothed everywhere (no crease angle; the cloth's
folds over the hidden sphere bend by up to 70 degrees between neighbouring triangles).

Material UV is arc length on the surface divided by :data:`TILE_M` (one BTF tile per
0.25 m before the per-object tiling scale), so texels are roughly isotropic on every mesh.

========== ============================================================== ==========
name       shape                                                          triangles
========== ============================================================== ==========
sphere     UV sphere, radius 0.25 m, 64 x 32 segments (no pole fans:     3 968
           each pole triangle has its own pole vertex)
torus      ring radius 0.3 m, tube radius 0.1 m, 96 x 48 segments        9 216
plane      1 x 1 m square in the xz plane facing +y, 16 x 16 quads        512
cloth      0.8 m square of 128 x 128 quads draped over a hidden          32 768
           0.15 m sphere: smooth drape plus 9 radial folds growing
           toward the hem; UV = the undeformed fabric coordinates
highpoly   (2, 3) torus knot, tube radius 0.035 m, 800 x 63 segments,    100 800
           with fine sinusoidal ridges (the 100k-triangle benchmark mesh)
========== ============================================================== ==========
"""

from __future__ import annotations

import numpy as np

from vrneural.atlas.geometry import make_mesh
from vrneural.atlas.types import Mesh
from vrneural.errors import check_choice

TILE_M = 0.25
BUILTIN_MESHES = ("sphere", "torus", "plane", "cloth", "highpoly")


def builtin_mesh(name: str, crease_deg: float | None = None) -> Mesh:
    """The built-in mesh ``name`` (one of :data:`BUILTIN_MESHES`); smooth everywhere unless a
    crease angle (degrees) is given."""
    check_choice("mesh", name, BUILTIN_MESHES)
    pos, faces, uv = _BUILDERS[name]()
    return make_mesh(
        name,
        pos,
        faces,
        uv=uv,
        crease_deg=180.0 if crease_deg is None else crease_deg,
        uv_source="builtin",
    )


def grid_faces(nu: int, nv: int) -> np.ndarray:
    """[2 nu nv, 3] faces of a (nu+1) x (nv+1) vertex grid (u fastest), CCW seen from +normal."""
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="xy")
    a = (j * (nu + 1) + i).reshape(-1)
    b, c, d = a + 1, a + nu + 1, a + nu + 2
    return np.concatenate([np.stack([a, c, b], 1), np.stack([b, c, d], 1)])


def _grid(nu: int, nv: int) -> tuple[np.ndarray, np.ndarray]:
    """Parameters s, t in [0, 1] of a (nu+1) x (nv+1) grid, flattened u-fastest."""
    s, t = np.meshgrid(np.linspace(0, 1, nu + 1), np.linspace(0, 1, nv + 1), indexing="xy")
    return s.reshape(-1), t.reshape(-1)


def _sphere(r: float = 0.25, nu: int = 64, nv: int = 32):
    s, t = _grid(nu, nv)
    phi, theta = 2 * np.pi * s, np.pi * t
    pos = np.stack(
        [r * np.sin(theta) * np.cos(phi), r * np.cos(theta), -r * np.sin(theta) * np.sin(phi)], 1
    )
    uv = np.stack([s * 2 * np.pi * r, t * np.pi * r], 1) / TILE_M
    faces = grid_faces(nu, nv)
    # drop the zero-area half of each pole quad (two vertices at the same pole point)
    p0, p1, p2 = (pos[faces[:, k]] for k in range(3))
    area = np.linalg.norm(np.cross(p1 - p0, p2 - p0), axis=1)
    faces = faces[area > 1e-12]
    return pos, _orient_outward(pos, faces), uv


def _orient(pos: np.ndarray, faces: np.ndarray, front) -> np.ndarray:
    """Flip the faces whose normal points against ``front`` (``[F, 3]`` per face, or ``[3]``):
    the direction their front side should face."""
    p0, p1, p2 = (pos[faces[:, k]] for k in range(3))
    inward = np.sum(np.cross(p1 - p0, p2 - p0) * front, axis=1) < 0
    faces = faces.copy()
    faces[inward] = faces[inward][:, [0, 2, 1]]
    return faces


def _orient_outward(pos: np.ndarray, faces: np.ndarray, center=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Flip faces whose normal points toward ``center`` (closed, star-shaped surfaces)."""
    centroid = sum(pos[faces[:, k]] for k in range(3)) / 3
    return _orient(pos, faces, centroid - np.asarray(center))


def _torus(R: float = 0.3, r: float = 0.1, nu: int = 96, nv: int = 48):
    s, t = _grid(nu, nv)
    phi, theta = 2 * np.pi * s, 2 * np.pi * t
    ring = R + r * np.cos(theta)
    pos = np.stack([ring * np.cos(phi), r * np.sin(theta), -ring * np.sin(phi)], 1)
    uv = np.stack([s * 2 * np.pi * R, t * 2 * np.pi * r], 1) / TILE_M
    faces = grid_faces(nu, nv)
    # outward = away from the tube centre line
    c = np.stack([R * np.cos(phi), 0 * phi, -R * np.sin(phi)], 1)
    return pos, _orient(pos, faces, pos[faces[:, 0]] - c[faces[:, 0]]), uv


def _plane(size: float = 1.0, n: int = 16):
    s, t = _grid(n, n)
    pos = np.stack([(s - 0.5) * size, 0 * s, (t - 0.5) * size], 1)
    uv = np.stack([s, t], 1) * size / TILE_M
    return pos, _orient(pos, grid_faces(n, n), (0.0, 1.0, 0.0)), uv  # normals with y > 0


def _cloth(size: float = 0.8, n: int = 128, r0: float = 0.15, folds: int = 9):
    """A square cloth draped over a sphere of radius r0: the smooth part follows the cap, the
    hanging part falls off; folds are radial sinusoids whose amplitude grows toward the hem,
    and the hem is pulled inward (gathered) so the folds look like hanging fabric."""
    s, t = _grid(n, n)
    x0, z0 = (s - 0.5) * size, (t - 0.5) * size
    rho = np.hypot(x0, z0)
    ang = np.arctan2(z0, x0)
    on_cap = np.minimum(rho / r0, 1.0)
    cap = r0 * np.sqrt(1.0 - on_cap**2) * (rho < r0)
    hang = np.maximum(rho - r0, 0.0)
    # the part beyond the cap hangs down at a steepening slope (smooth at rho = r0)
    y = cap - 0.9 * hang**2 / (hang + 0.05) + r0
    fold_amp = 0.04 * (hang / (size / 2)) ** 1.2
    rr = rho - 0.45 * hang + fold_amp * np.sin(folds * ang + 3.0 * hang / size)
    y = y + 0.5 * fold_amp * np.cos(folds * ang)
    pos = np.stack([rr * np.cos(ang), y, rr * np.sin(ang)], 1)
    uv = np.stack([s, t], 1) * size / TILE_M
    # the front faces away from a point below the cloth
    return pos, _orient_outward(pos, grid_faces(n, n), (0.0, -1.0, 0.0)), uv


def _knot(nu: int = 800, nv: int = 63, p: int = 2, q: int = 3, r: float = 0.035):
    s, t = _grid(nu, nv)
    a = 2 * np.pi * s
    scale = 0.1

    def curve(a):
        rad = 2.0 + np.cos(q * a)
        return scale * np.stack([rad * np.cos(p * a), -np.sin(q * a), rad * np.sin(p * a)], -1)

    c = curve(a)
    tan = curve(a + 1e-4) - curve(a - 1e-4)
    tan /= np.linalg.norm(tan, axis=1, keepdims=True)
    ref = np.broadcast_to([0.0, 1.0, 0.0], tan.shape)
    nrm = np.cross(tan, ref)
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    bin_ = np.cross(tan, nrm)
    theta = 2 * np.pi * t
    ridge = 1.0 + 0.06 * np.sin(40 * a) * np.cos(7 * theta)
    off = (np.cos(theta)[:, None] * nrm + np.sin(theta)[:, None] * bin_) * (r * ridge)[:, None]
    pos = c + off
    length = np.sum(np.linalg.norm(np.diff(curve(np.linspace(0, 2 * np.pi, 4001)), axis=0), axis=1))
    uv = np.stack([s * length, t * 2 * np.pi * r], 1) / TILE_M
    faces = grid_faces(nu, nv)
    return pos, _orient(pos, faces, pos[faces[:, 0]] - c[faces[:, 0]]), uv  # off the centre line


_BUILDERS = {
    "sphere": _sphere,
    "torus": _torus,
    "plane": _plane,
    "cloth": _cloth,
    "highpoly": _knot,
}
