"""Extreme run settings through the real path (``RunConfig`` -> ``resolve`` -> ``Renderer``):
texture resolution, reuse N, light count, eyes, frames. Tiny eye images (32 x 32) keep it fast.
"""

from __future__ import annotations

import numpy as np

from extremes.fixtures import finite_nonneg, quad_atlas
from vrneural.material import random_material
from vrneural.runtime import reference as ref

EYE_RES = "32x32"


#: A small scene of procedural neural materials (independent of the bundled packs), TOML.
SCENE_TOML = """
[[objects]]
mesh = "sphere"
position = [0.0, 0.9, 0.0]
scale = 0.4
material = { procedural = "random", seed = 3, scale = 0.5 }
[[objects]]
mesh = "plane"
position = [0.55, 0.55, 0.15]
rotation = [60, -30, 0]
scale = 0.2
material = { procedural = "lambertian", albedo = [0.7, 0.45, 0.25] }
[[objects]]
mesh = "plane"
scale = 3.0
material = { kind = "plain", albedo = [0.35, 0.35, 0.38] }
"""


def extreme_scene(n_lights: int):
    """:data:`SCENE_TOML` with ``n_lights`` of :func:`default_lights` (0 allowed)."""
    import tempfile
    from pathlib import Path

    from vrneural.runtime.lights import default_lights
    from vrneural.runtime.scene import load_scene

    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "extremes.toml"
        p.write_text(SCENE_TOML)
        sc = load_scene(p)
    sc.lights = default_lights(n_lights)
    return sc


def render(frames: int = 3, scene=None, **kw) -> dict:
    """Resolve ``RunConfig(**kw)`` on :func:`extreme_scene` (profile tiny) and render
    ``frames``. Returns per-frame stats, the last frame's eye images and radiance textures."""
    from vrneural.gpu.device import adapter_summary
    from vrneural.runtime.config import RunConfig, resolve
    from vrneural.runtime.renderer import Renderer

    kw.setdefault("eye_res", EYE_RES)
    cfg = RunConfig(profile="tiny", frames=frames, **kw)
    n = cfg.lights if cfg.lights is not None else 2
    sc = scene or extreme_scene(n)
    s = resolve(cfg, sc, adapter_summary())
    r = Renderer(sc, s)
    stats = [r.frame(f) for f in range(s.frames)]
    rads = [r.radiance(k, e) for k in range(len(r.neural)) for e in range(s.eyes)]
    return {"stats": stats, "eyes": r.read_eyes(), "radiance": rads, "settings": s}


def _images_ok(out: dict) -> bool:
    return all(finite_nonneg(im) for im in out["eyes"] + out["radiance"])


def case_set_lights_0(quick: bool) -> dict:
    out = render(lights=0)
    black = all(not r[..., :3].any() for r in out["radiance"])
    mlp = sum(s.mlp_coarse + s.mlp_fine for s in out["stats"])
    ok = _images_ok(out) and black and mlp == 0
    return {"ok": ok, "mlp_evals": mlp, "note": "neural objects black, no MLP work"}


def case_set_lights_16(quick: bool) -> dict:
    out = render(lights=16)
    lit = max(float(r[..., :3].max()) for r in out["radiance"])
    return {"ok": _images_ok(out) and lit > 0, "max_radiance": lit}


def _reuse(n: int, frames: int) -> dict:
    out = render(frames=frames, reuse=n)
    upd = [s.updated_objects for s in out["stats"]]
    return {"ok": _images_ok(out), "updates_per_frame": upd}


def case_set_reuse_0(quick: bool) -> dict:
    r = _reuse(0, 3)
    r["ok"] = r["ok"] and min(r["updates_per_frame"]) > 0  # N = 0: every frame updates
    return r


def case_set_reuse_1000(quick: bool) -> dict:
    r = _reuse(1000, 4)
    r["note"] = "one full update on first sight, then staggered slices of 1/1001"
    return r


def case_set_one_eye_one_frame(quick: bool) -> dict:
    out = render(frames=1, eyes=1)
    return {"ok": _images_ok(out) and len(out["eyes"]) == 1 and len(out["stats"]) == 1}


def case_set_tex_res_2(quick: bool) -> dict:
    render(frames=1, texture_res=2)  # the atlas stage needs R >= 8: one-line rejection
    return {"ok": False}


def case_set_tex_res_odd(quick: bool) -> dict:
    render(frames=1, texture_res=129)
    return {"ok": False}


def case_set_tex_res_above_max(quick: bool) -> dict:
    from vrneural.gpu.device import adapter_summary

    render(frames=1, texture_res=int(adapter_summary().limits["max_texture_dimension_2d"]) + 2)
    return {"ok": False}


def kernel_at_resolution(R: int) -> dict:
    """The texture-space kernel alone on a hand-made quad atlas of side R (R = 2: one block)."""
    from extremes.shading import GpuShade

    at = quad_atlas(R, lo=0.0, hi=1.0) if R <= 4 else quad_atlas(R)
    mat = random_material(1)
    eye, lp, lc = np.float64([0.1, 0.2, 1.0]), np.float64([[0.3, 0.1, 0.8]]), np.ones((1, 3))
    got = GpuShade(at, mat).shade(np.eye(4), eye, lp, lc)
    want, _ = ref.shade_texture_space(at, mat, np.eye(4), eye, lp, lc)
    w16 = want.astype(np.float16).astype(np.float32)
    err = float((np.abs(got - w16) / (np.abs(w16) + 1e-2)).max())
    return {"ok": finite_nonneg(got) and err <= 2 * 2.0**-10, "max_rel_err_vs_twin": err}


def case_set_kernel_res_2(quick: bool) -> dict:
    return kernel_at_resolution(2)


def case_set_tex_res_max(quick: bool) -> dict:
    """The largest accepted radiance texture (``config.max_texture_res``: 5792 on lavapipe;
    1024 with --quick) on the built-in plane: atlas + kernel."""
    from extremes.shading import GpuShade
    from vrneural.atlas import build_atlas, builtin_mesh
    from vrneural.gpu.device import adapter_summary
    from vrneural.runtime.config import max_texture_res

    R = 1024 if quick else max_texture_res(adapter_summary())
    at = build_atlas(builtin_mesh("plane"), R, cache=False)
    got = GpuShade(at, random_material(1)).shade(
        np.eye(4), np.float64([0.1, 1.0, 0.2]), np.float64([[0.3, 0.8, 0.1]]), np.ones((1, 3))
    )
    return {"ok": finite_nonneg(got) and bool(got[..., 3].any()), "resolution": R}


def far_scene_images(offset: float, frames: int = 2) -> list:
    """:func:`extreme_scene` (objects, lights and a straight 2-pose head path) translated by
    ``offset`` m on every axis, rendered through the Renderer: eye images ``[H, W, 4]``."""
    import dataclasses
    import tempfile
    from pathlib import Path

    sc = extreme_scene(2)
    o = np.full(3, offset)
    objs = []
    for ob in sc.objects:
        m = np.array(ob.model, np.float64)
        m[:3, 3] += o
        objs.append(dataclasses.replace(ob, model=m))
    lights = [
        dataclasses.replace(lt, position=tuple(np.asarray(lt.position) + o)) for lt in sc.lights
    ]
    with tempfile.TemporaryDirectory() as d:
        log = Path(d) / "pose.csv"
        p0, p1 = np.array([0.0, 1.2, 1.6]) + o, np.array([0.05, 1.2, 1.55]) + o
        rows = [
            f"{t},{float(p[0])!r},{float(p[1])!r},{float(p[2])!r},-0.17,0,0,0.985"
            for t, p in ((0, p0), (1, p1))
        ]
        log.write_text("\n".join(rows) + "\n")
        scene = dataclasses.replace(sc, objects=objs, lights=lights, head=str(log))
        return render(frames=frames, scene=scene, eyes=1)["eyes"]


def case_set_far_origin_render(quick: bool) -> dict:
    """Whole scene + viewer 1e5 m from the origin: the rendered image equals the one at the
    origin (floating origin in the renderer, camera-relative texture pass)."""
    a, b = far_scene_images(0.0)[0], far_scene_images(1e5)[0]
    d = np.abs(a[..., :3] - b[..., :3])
    frac = float((d > 1e-2 * (np.abs(a[..., :3]) + 1e-2)).mean())
    ok = finite_nonneg(b) and frac <= 1e-3
    return {"ok": ok, "max_abs_diff": float(d.max()), "frac_pixels_off": frac}
