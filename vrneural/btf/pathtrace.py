"""Path-traced BTF slices with Mitsuba 3 (`vrneural btf render`).

A :class:`~vrneural.btf.pt_geometry.Tile` (triangle meshes of the microgeometry, one Mitsuba
BSDF plugin per part) becomes one Mitsuba scene: the tile is a ``shapegroup`` instanced at
every whole-tile shift ``(dx, dy)`` with ``|dx|, |dy| <= ring`` (:func:`copy_ring`), so a ray
that leaves the central tile sideways meets the neighbouring microgeometry, and edge texels
are lit, shadowed and masked like interior ones (instances share one acceleration structure:
49 copies of a 100k-triangle tile load in a fraction of a second). Light: Mitsuba's
``directional`` emitter of unit irradiance (measured perpendicular to its direction) from
``wi``; integrator: ``path`` (unidirectional path tracing with next-event estimation,
``max_depth = bounces + 1``), so the radiance leaving toward ``wo`` is the BTF value with
cos(theta_i) inside (docs/conventions.md section 2).

Rectified slices: the camera is an ``orthographic`` sensor whose camera-to-world matrix is
sheared so that the ray through film position ``(fx, fy) in [0, 1]^2`` travels along ``-wo``
and crosses the reference plane ``z = z_ref`` at ``(x, y) = (fx, fy)``: pixel ``(x, y)`` of a
``res x res`` film is the texel whose centre is UV ``((x + 0.5) / res, (y + 0.5) / res)``, as
`btf synth` and UBO2014 have it. Samples are spread over the pixel (box filter): the texel's
footprint on the reference plane. The sampler is Mitsuba's ``multijitter`` by default
(stratified in every dimension pair, so pixel footprint, light path and BSDF samples converge
faster than with ``independent``; `RenderConfig.sampler`). ``z_ref`` is the mean height of
the top surface seen from above (:func:`height_field`), as `btf synth`'s heightfields have
mean 0.

Mitsuba runs in its ``scalar_rgb`` variant (CPU, multi-threaded by block); ``llvm_ad_rgb``
aborts on some CPUs (an LLVM "Cannot select fminimum" error). Each slice is rendered with its
own seed (:func:`slice_seed`), so a render is the same for the same settings.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vrneural.btf.pt_geometry import Tile
from vrneural.errors import VrnError

INSTALL_HINT = "pip install 'vrneural[render]' (or: pip install mitsuba)"
VARIANT = "scalar_rgb"


def load_mitsuba():
    """The ``mitsuba`` module in the ``scalar_rgb`` variant, or a one-line :class:`VrnError`
    naming the extra to install."""
    try:
        import mitsuba as mi
    except ImportError:
        raise VrnError(
            f"Mitsuba 3 is not installed (btf render path-traces with it); install the "
            f"render extra: {INSTALL_HINT}"
        ) from None
    if mi.variant() != VARIANT:
        mi.set_variant(VARIANT)
    mi.set_log_level(mi.LogLevel.Error)
    return mi


def _plugin(mi, d):
    """A plugin dict with ``{"type": "bitmap", "data": array}`` textures made Mitsuba
    bitmaps (linear values: ``raw``, repeating, bilinear)."""
    if isinstance(d, dict):
        if d.get("type") == "bitmap" and "data" in d:
            data = np.ascontiguousarray(d["data"], np.float32)
            rest = {k: v for k, v in d.items() if k != "data"}
            return {
                "raw": True,
                "wrap_mode": "repeat",
                "filter_type": "bilinear",
                **rest,
                "bitmap": mi.Bitmap(data),
            }
        return {k: _plugin(mi, v) for k, v in d.items()}
    return d


def _mesh(mi, name: str, m, bsdf: dict, smooth: bool):
    """A Mitsuba mesh from numpy arrays (see :class:`~vrneural.btf.pt_geometry.Mesh`)."""
    import drjit as dr

    props = mi.Properties()
    props["bsdf"] = mi.load_dict(_plugin(mi, bsdf))
    if not smooth:
        props["face_normals"] = True
    has_n = smooth
    mesh = mi.Mesh(
        name, len(m.v), len(m.f), props=props, has_vertex_normals=has_n, has_vertex_texcoords=True
    )
    p = mi.traverse(mesh)
    p["vertex_positions"] = dr.scalar.ArrayXf(np.ascontiguousarray(m.v, np.float32).ravel())
    p["faces"] = dr.scalar.ArrayXu(np.ascontiguousarray(m.f, np.uint32).ravel())
    p["vertex_texcoords"] = dr.scalar.ArrayXf(np.ascontiguousarray(m.uv, np.float32).ravel())
    if smooth and m.n is not None:
        p["vertex_normals"] = dr.scalar.ArrayXf(np.ascontiguousarray(m.n, np.float32).ravel())
    p.update()
    if smooth and m.n is None:
        mesh.recompute_vertex_normals()
    return mesh


def copy_ring(zspan: float, max_theta_deg: float, most: int = 6) -> int:
    """Copies of the tile needed on each side (at least 1, at most ``most``): within the
    height range ``zspan`` (tile widths) a camera ray at ``max_theta_deg`` from the normal
    travels up to ``zspan tan(theta)`` sideways before it hits, and the shadow ray from there
    as far again, from wherever in the central tile it starts."""
    reach = 2.0 * zspan * np.tan(np.radians(min(max_theta_deg, 89.0)))
    return int(min(most, max(1, np.ceil(reach))))


@dataclass
class PtScene:
    """A loaded scene: Mitsuba's scene, its parameters (to turn the light), the top of the
    geometry ``zmax`` and the reference plane's height ``z_ref`` (tile widths)."""

    mi: object
    scene: object
    params: object
    zmin: float
    zmax: float
    z_ref: float = 0.0
    ring: int = 1


def build_scene(tile: Tile, bounces: int, ring: int) -> PtScene:
    """The tile with ``ring`` copies on each side, a unit directional light and the path
    tracer (``max_depth = bounces + 1``: 1 bounce is direct light only)."""
    mi = load_mitsuba()
    objs: dict = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": bounces + 1, "rr_depth": bounces + 2},
        "light": {"type": "directional", "direction": [0.0, 0.0, -1.0], "irradiance": 1.0},
    }
    group = {"type": "shapegroup"}
    for k, part in enumerate(tile.parts):
        group[f"part{k}"] = _mesh(mi, f"part{k}", part.mesh, part.bsdf, part.smooth)
    objs["tile"] = group
    for dy in range(-ring, ring + 1):
        for dx in range(-ring, ring + 1):
            objs[f"copy_{dx}_{dy}"] = {
                "type": "instance",
                "shapegroup": {"type": "ref", "id": "tile"},
                "to_world": mi.ScalarTransform4f().translate([float(dx), float(dy), 0.0]),
            }
    scene = mi.load_dict(objs)
    zmin, zmax = tile.bounds()
    return PtScene(mi, scene, mi.traverse(scene), zmin, zmax, ring=ring)


def height_field(ps: PtScene, n: int) -> np.ndarray:
    """The top surface seen from straight above at the ``[n, n]`` grid cell centres
    ``((j + 0.5) / n, (i + 0.5) / n)`` (row i = y), in tile widths (absolute z; where a ray
    finds nothing, the lowest point of the geometry)."""
    mi = ps.mi
    out = np.empty((n, n), np.float32)
    top = ps.zmax + 1.0
    down = mi.ScalarVector3f(0.0, 0.0, -1.0)
    for i in range(n):
        y = (i + 0.5) / n
        for j in range(n):
            ray = mi.Ray3f(mi.ScalarPoint3f((j + 0.5) / n, y, top), down)
            si = ps.scene.ray_intersect(ray)
            out[i, j] = top - si.t if si.is_valid() else ps.zmin
    return out


def sensor(ps: PtScene, wo: np.ndarray, res: int, spp: int, sampler: str = "multijitter"):
    """The rectified orthographic camera for view ``wo`` (see the module docstring), with
    Mitsuba's ``sampler`` plugin (``multijitter``: ``spp`` must be its grid count)."""
    mi = ps.mi
    wo = np.asarray(wo, np.float64)
    if wo[2] <= 1e-4:
        raise VrnError(f"view direction {wo.tolist()} is at or below the horizon")
    t0 = (ps.zmax - ps.z_ref + 0.05) / wo[2]  # start above everything
    m = np.eye(4)
    m[:3, 0] = [-0.5, 0.0, 0.0]  # camera x in [-1, 1] -> u = fx in [0, 1]
    m[:3, 1] = [0.0, -0.5, 0.0]
    m[:3, 2] = -wo
    m[:3, 3] = np.array([0.5, 0.5, ps.z_ref]) + t0 * wo
    return mi.load_dict(
        {
            "type": "orthographic",
            "to_world": mi.ScalarTransform4f(m),
            "near_clip": 1e-4,
            "far_clip": float(t0 + (ps.zmax - ps.zmin + 2.0) / wo[2] + 10.0),
            "sampler": {"type": sampler, "sample_count": spp},
            "film": {
                "type": "hdrfilm",
                "width": res,
                "height": res,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
                "component_format": "float32",
                "sample_border": False,
            },
        }
    )


def set_light(ps: PtScene, wi: np.ndarray) -> None:
    """Point the unit directional light from ``wi`` (toward the light) at the tile."""
    mi = ps.mi
    d = -np.asarray(wi, np.float64)
    up = [0.0, 1.0, 0.0] if abs(d[1]) < 0.9 else [1.0, 0.0, 0.0]
    ps.params["light.to_world"] = mi.ScalarTransform4f().look_at(
        origin=[0.0, 0.0, 0.0], target=d.tolist(), up=up
    )
    ps.params.update()


def slice_seed(seed: int, light: int, view: int) -> int:
    """The Monte Carlo seed of slice ``(light, view)`` of a render seeded ``seed``."""
    return int(np.random.SeedSequence([seed, light, view]).generate_state(1)[0])


def render_slice(ps: PtScene, cam, wi: np.ndarray, spp: int, seed: int) -> np.ndarray:
    """One slice ``[res, res, 3]`` float32 (BTF values) lit from ``wi`` seen by ``cam``."""
    set_light(ps, wi)
    img = ps.mi.render(ps.scene, sensor=cam, spp=spp, seed=seed)
    return np.asarray(img, np.float32)[..., :3]
