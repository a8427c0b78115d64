"""The terminator check: is a sphere's radiance continuous where a light sets?

One sphere (the built-in ``sphere`` mesh, radius ``RADIUS`` m) at the origin, one eye at
``(0, 0, EYE_DIST)`` looking down -z, one point light far along +x (``LIGHT_DIST`` m, intensity
``LIGHT_DIST^2`` W/sr, so the irradiance at the sphere is about 1 W/m^2). The terminator is then
(nearly) the sphere's vertical great circle through its centre as the eye sees it, and every
image row through the middle of the sphere crosses it once, from lit (x > 0) to dark.

The measure, per row: walking from the lit side, the last pixel above ``DARK`` of the object's
peak before the row goes dark; its value over the peak is the row's **step** (the jump to black
there). A radiance that tapers like ``cos(theta_i)`` steps by about one pixel's worth of slope
(``1 / (radius in pixels)`` of the peak); a hard cut at the horizon steps by whatever the
material gives there. The analytic Lambertian profile (ray-sphere intersection per pixel,
``albedo / pi * max(n.l, 0) * I / d^2``) gives that floor at the same resolution, and the
rendered Lambertian pack is compared with it pixel by pixel.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vrneural.runtime.camera import HeadPath, look_rotation

RADIUS = 0.5  # m
EYE_DIST = 1.6  # m, from the sphere's centre
LIGHT_DIST = 20.0  # m
FOV_Y = 48.0  # degrees
DARK = 1e-6  # of the peak: a pixel at or below it counts as dark
ROW_BAND = 0.6  # rows within this fraction of the sphere's image radius around its centre


class FixedHead(HeadPath):
    """A head that stays at ``position`` looking at ``target``."""

    def __init__(self, position, target=(0.0, 0.0, 0.0)):
        self.p = np.asarray(position, np.float64)
        self.r = look_rotation(np.asarray(target, np.float64) - self.p)

    def pose(self, t: float):
        return self.p, self.r


def sphere_scene(material, light_dir=(1.0, 0.0, 0.0), mesh: str = "sphere"):
    """The check's scene: a sphere (``mesh``: the built-in one or a mesh file, scaled to radius
    ``RADIUS``) with ``material`` (a ``MaterialDesc``), one light ``LIGHT_DIST`` m away along
    ``light_dir`` (unit, world)."""
    from vrneural.runtime.assets import get_mesh
    from vrneural.runtime.lights import PointLight
    from vrneural.runtime.scene import ObjectDesc, Scene, model_matrix

    p = get_mesh(mesh).positions
    scale = 2 * RADIUS / float((p.max(0) - p.min(0)).max())
    obj = ObjectDesc("sphere", mesh, model_matrix((0, 0, 0), (0, 0, 0), scale), material)
    d = np.asarray(light_dir, np.float64)
    light = PointLight(tuple(d / np.linalg.norm(d) * LIGHT_DIST), (1, 1, 1), LIGHT_DIST**2)
    return Scene("terminator", [obj], [light], "preview", None, "orbit", Path.cwd())


def render_sphere(
    material, mode: str, eye_res=(480, 512), texture_res=1024, precision="f32", mesh="sphere"
):
    """Linear RGB ``[H, W, 3]`` of the sphere seen by one eye (frame 0, everything shaded)."""
    from vrneural.gpu.device import adapter_summary
    from vrneural.runtime.config import RunConfig, resolve
    from vrneural.runtime.renderer import Renderer

    scene = sphere_scene(material, mesh=mesh)
    cfg = RunConfig(
        eyes=1,
        frames=1,
        mode=mode,
        reuse=0,
        eye_res=f"{eye_res[0]}x{eye_res[1]}",
        texture_res=texture_res,
        precision=precision,
    )
    s = resolve(cfg, scene, adapter_summary())
    s.fov_y = FOV_Y
    r = Renderer(scene, s)
    r.head = FixedHead((0.0, 0.0, EYE_DIST))
    r.frame(0)
    return r.read_eyes()[0][..., :3].astype(np.float64)


def analytic_lambert(eye_res=(480, 512), albedo=(0.8, 0.5, 0.2)) -> np.ndarray:
    """``[H, W, 3]``: a perfect sphere, Lambertian ``albedo``, the check's eye and light."""
    w, h = eye_res
    f = 1.0 / np.tan(np.radians(FOV_Y) / 2)
    ys, xs = np.mgrid[0:h, 0:w] + 0.5
    d = np.stack([(2 * xs / w - 1) * w / h / f, (1 - 2 * ys / h) / f, -np.ones_like(xs)], -1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    o = np.array([0.0, 0.0, EYE_DIST])
    b = (d * o).sum(-1)
    disc = b * b - (o @ o - RADIUS**2)
    hit = disc >= 0
    t = -b - np.sqrt(np.where(hit, disc, 0))
    p = o + t[..., None] * d
    n = p / RADIUS
    lp = np.array([LIGHT_DIST, 0.0, 0.0])
    lv = lp - p
    d2 = (lv * lv).sum(-1)
    cos_i = np.maximum((n * lv).sum(-1) / np.sqrt(d2), 0)
    e = cos_i * LIGHT_DIST**2 / d2
    return np.where(hit[..., None], np.asarray(albedo) / np.pi * e[..., None], 0.0)


def row_steps(img: np.ndarray) -> dict:
    """The step at the terminator on each row through the middle of the sphere (see the
    module docstring): ``{"peak", "steps": [R] (fraction of the peak), "max", "median",
    "rows": [R] and "columns": [R] (the last lit pixel of each row)}``."""
    y = img.max(-1)  # [H, W] brightest channel
    peak = float(y.max())
    rows = np.nonzero((y > 0).any(1))[0]
    cy, ry = (rows[0] + rows[-1]) / 2, (rows[-1] - rows[0]) / 2
    band = [r for r in rows if abs(r - cy) <= ROW_BAND * ry]
    steps, cols, used = [], [], []
    for r in band:
        lit = np.nonzero(y[r] > DARK * peak)[0]
        if len(lit) == 0:
            continue
        # the light is along +x: everything left of the terminator is unlit, so the row's
        # leftmost lit pixel is the last one before it goes dark
        k = int(lit.min())
        steps.append(float(y[r, k]) / peak)
        cols.append(k)
        used.append(int(r))
    s = np.asarray(steps)
    return {
        "peak": peak,
        "steps": s,
        "rows": np.asarray(used),
        "columns": np.asarray(cols),
        "max": float(s.max()) if len(s) else float("nan"),
        "median": float(np.median(s)) if len(s) else float("nan"),
    }


def interior_error(img: np.ndarray, ana: np.ndarray, margin: int = 3) -> float:
    """Largest ``|img - ana|`` over pixels at least ``margin`` pixels inside the analytic
    sphere's silhouette (the mesh's polygon and the perfect sphere differ at the rim), as a
    fraction of the analytic peak."""
    from scipy.ndimage import binary_erosion

    inside = binary_erosion(ana.max(-1) > 0, iterations=margin)
    return float(np.abs(img - ana).max(-1)[inside].max() / ana.max())


#: the target: the step at the terminator at most this fraction of the object's peak
STEP_MAX = 0.01
#: the rendered Lambertian pack against the perfect sphere, inside the silhouette: measured
#: 0.65% of the peak (screen, reference) and 0.82% (texture) on lavapipe, the 64 x 32 UV
#: sphere's polygon and interpolated normals against the analytic sphere
LAMBERT_TOL = 0.015


def terminator_materials(quick: bool) -> dict:
    """``{name: MaterialDesc}``: the exact Lambertian pack (its own reference) and the bundled
    neural packs (each with its teacher as the reference); quick: Lambertian and leather."""
    from vrneural.material import lambertian_material
    from vrneural.runtime.scene import MaterialDesc, builtin_material

    lam = lambertian_material()
    out = {"lambert": MaterialDesc("neural", lam, "lambertian", 1.0, reference=lam)}
    for k in ("leather",) if quick else ("leather", "fabric", "wood"):
        out[k] = builtin_material(k)
    return out


def case_dir_terminator(quick: bool) -> dict:
    """Each material on the sphere under one side light, in texture, screen and reference
    modes (480 x 512, one eye): the largest step at the terminator over the rows, against
    :data:`STEP_MAX`; the Lambertian pack also against the analytic image."""
    res = (480, 512)
    ana = analytic_lambert(res)
    rec = {"analytic_step": row_steps(ana)["max"], "steps": {}}
    worst, ok = 0.0, True
    for name, desc in terminator_materials(quick).items():
        for mode in ("texture", "screen", "reference"):
            img = render_sphere(desc, mode, res)
            rows = row_steps(img)
            step = rows["max"]
            rec["steps"][f"{name}/{mode}"] = step
            worst = max(worst, step)
            # more than 100 rows measured: the sphere is there and the light sets on it
            ok &= bool(np.isfinite(img).all()) and step <= STEP_MAX and len(rows["steps"]) > 100
            if name == "lambert":
                err = interior_error(img, ana)
                rec[f"lambert_{mode}_vs_analytic"] = err
                ok &= err <= LAMBERT_TOL
    rec.update(ok=ok, max_step=worst, note="step: fraction of the peak; target <= 1%")
    return rec
