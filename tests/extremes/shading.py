"""Extreme directions and precision: the numpy reference and the GPU texture-space kernel.

The scenes are a small quad whose local frame is the world frame (:func:`quad_atlas`), so a
light or eye placed far away along ``direction(theta)`` sets ``wi`` / ``wo`` at every texel.
Radiance units: W/(m^2 sr); light ``colour * intensity`` in W/sr; distances in metres.
"""

from __future__ import annotations

import numpy as np

from extremes.fixtures import (
    direction,
    finite_nonneg,
    quad_atlas,
    quad_mesh,
    step_bounds,
)
from vrneural.material import lambertian_material, material_forward, random_material
from vrneural.runtime import reference as ref

GRAZING = 89.99  # degrees


def _materials():
    return [random_material(3, "coarse_fine"), random_material(4, "single"), lambertian_material()]


def _uv(n: int) -> np.ndarray:
    return np.full((n, 4, 2), 0.37, np.float32) + np.float32([0, 0.01])


def grazing_sweep(mat, n: int = 400) -> dict:
    """``material_forward`` along theta_i = theta_o in [0, 89.99] deg (three azimuth pairs):
    finite, >= 0, and each step within its continuity bound (:func:`step_bounds`: the
    network's Lipschitz bound on the directions it sees, plus the light weight's change beyond
    the data's range)."""
    th = np.concatenate([np.linspace(0, GRAZING, n), [89.9, 89.999, 89.9999]])
    th.sort()
    worst, finite = 0.0, True
    for phi_i, phi_o in ((0, 180), (0, 90), (30, 0)):
        wi = np.stack([direction(t, phi_i) for t in th]).astype(np.float32)
        wo = np.stack([direction(t, phi_o) for t in th]).astype(np.float32)
        y = material_forward(mat, wi, wo, _uv(len(th)))
        finite &= finite_nonneg(y)
        dy = np.abs(np.diff(y.astype(np.float64), axis=0)).max(axis=(1, 2))
        # 1e-5 absorbs f32 evaluation rounding of nearly equal inputs
        worst = max(worst, float((dy / (step_bounds(mat, wi, wo, _uv(len(th))) + 1e-5)).max()))
    return {"ok": finite and worst <= 1.0, "max_step_over_bound": worst}


def case_dir_grazing(quick: bool) -> dict:
    recs = [grazing_sweep(m, 100 if quick else 1000) for m in _materials()[:2]]
    return {
        "ok": all(r["ok"] for r in recs),
        "max_step_over_bound": max(r["max_step_over_bound"] for r in recs),
        "note": "theta up to 89.9999 deg, both archs; 1.0 = the continuity bound",
    }


def case_dir_normal_and_opposite(quick: bool) -> dict:
    """wi = wo = n, and wi = -wo (degenerate half vector -> (0, 0, 1))."""
    z = np.float32([[0, 0, 1]])
    out, ok = [], True
    for m in _materials():
        y_n = material_forward(m, z, z, _uv(1))
        a = np.float32([[0.6, 0.0, 0.8], [0, 0, 1], [1, 0, 0]])
        y_o = material_forward(m, a, -a, _uv(3))
        ok &= finite_nonneg(y_n) and finite_nonneg(y_o)
        out.append(float(y_n.max()))
    lam = material_forward(lambertian_material((0.8, 0.5, 0.2)), z, z, _uv(1))[0, 0]
    ok &= bool(np.allclose(lam, np.float32([0.8, 0.5, 0.2]) / np.pi, rtol=1e-6))
    # shading: wi = -wo puts one of them below the horizon, so the kernel adds nothing
    pos = np.zeros((1, 3), np.float32)
    n, t, b = np.float32([[0, 0, 1]]), np.float32([[1, 0, 0]]), np.float32([[0, 1, 0]])
    eye = np.float32([0.3, 0, 0.4]) * 10
    rad, front, _, _ = ref.shade_points(
        _materials()[0], pos, n, t, b, _uv(1), eye, -eye[None], np.float32([[1, 1, 1]])
    )
    ok &= bool(front[0] and not rad.any())
    return {"ok": ok, "max_value_along_normal": max(out)}


def horizon_profile(mat, precision="f32", gpu=False, R=8):
    """Radiance of texel ``(R/2, R/2)`` of a 1 mm quad while a light (1 W/sr, 10 m away)
    crosses the horizon, elevation +2 to -2 deg. Returns ``(elevations [K], values [K, 3],
    the spec's value there [K, 3])`` (the spec: material_forward at the block's own frame and
    material uvs, which extends the light beyond the data's range and weighs it to 0 at the
    horizon, :mod:`vrneural.grazing`)."""
    at = quad_atlas(R, mesh=quad_mesh(0.001))
    eye = direction(40, 200) * 5
    elev = np.array([2, 1, 0.1, 0.01, 1e-3, 1e-4, -1e-4, -1e-3, -0.01, -0.1, -1, -2])
    g = ref.texture_blocks(at, np.eye(4))
    k = np.argmax((g["tx"] == R // 2) & (g["ty"] == R // 2), axis=None)
    blk, tex = divmod(int(k), 4)
    pos = g["pos"][blk].astype(np.float64)
    wo = (eye - pos) / np.linalg.norm(eye - pos)
    lights = [direction(90 - e, 10) * 10 for e in elev]
    vals = shade_many(at, mat, eye, lights, precision, gpu)[:, R // 2, R // 2, :3]
    pred = []
    for lp in lights:
        lv = lp - pos
        d2 = float(lv @ lv)
        wi = lv / np.sqrt(d2)
        y = material_forward(
            mat, wi[None].astype(np.float32), wo[None].astype(np.float32), g["uvs"][blk][None]
        )[0, tex]
        pred.append(y / d2)
    return elev, vals, np.array(pred)


class GpuShade:
    """One compiled texture-space pass on one atlas, shaded repeatedly (like the renderer);
    ``shade(model, eye, light_pos [L, 3], light_rgb [L, 3]) -> [R, R, 4]`` float32."""

    def __init__(self, at, mat, precision="f32", n_lights=1, radiance_format="rgba16float"):
        from vrneural.runtime.gpu_material import GpuAtlas
        from vrneural.runtime.texture_pass import CounterBuffer, TextureSpacePass, TextureTarget

        tp = TextureSpacePass(mat, precision, n_lights, radiance_format=radiance_format)
        self.counters = CounterBuffer(1)
        self.tgt = TextureTarget(tp, GpuAtlas(at), self.counters)

    def shade(self, model, eye, light_pos, light_rgb, timer=None) -> np.ndarray:
        """One dispatch (timed as pass ``"texture"`` when a ``GpuTimer`` is given)."""
        from vrneural.gpu.device import get_device
        from vrneural.gpu.readback import read_texture

        self.counters.clear()
        self.tgt.update(model, eye, (1, 1, 0, 0), light_pos, light_rgb)
        enc = get_device().create_command_encoder()
        self.tgt.encode(enc, timestamp_writes=timer.writes("texture") if timer else None)
        if timer:
            timer.resolve(enc)
        get_device().queue.submit([enc.finish()])
        return read_texture(self.tgt.texture).astype(np.float32)


def shade_many(at, mat, eye, lights, precision="f32", gpu=False, lc=None) -> np.ndarray:
    """Radiance ``[K, R, R, 4]`` of ``at`` lit by one light at each of ``lights: [K, 3]``
    (``colour * intensity`` ``lc: [3]``, default 1 W/sr); one compiled GPU pass reused."""
    lc = np.ones((1, 3)) if lc is None else np.asarray(lc, np.float64).reshape(1, 3)
    if gpu:
        g = GpuShade(at, mat, precision)
        return np.stack([g.shade(np.eye(4), eye, np.reshape(lp, (1, 3)), lc) for lp in lights])
    return np.stack(
        [
            ref.shade_texture_space(at, mat, np.eye(4), eye, np.reshape(lp, (1, 3)), lc)[0]
            for lp in lights
        ]
    )


def horizon_check(mat, precision="f32", gpu=False) -> dict:
    """The light's value falls continuously to 0 at the horizon (no jump): the texel follows the
    spec above it, its value 1e-4 deg above the horizon is a tiny fraction of the value at 2 deg
    (a cos(theta_i) taper gives sin(1e-4 deg) / sin(2 deg) = 5e-5), and below it the light adds
    exactly nothing."""
    elev, v, p = horizon_profile(mat, precision, gpu)
    above, below = elev > 0, elev < 0
    # rtol covers f16 storage and the 1 mm quad's direction spread
    scale = np.abs(p[above]).max() + 1e-6
    dev = float(np.abs(v[above] - p[above]).max() / scale)
    tol = 0.02 if precision == "f32" else 0.1
    jump = float(v[above][-1].max() / (v[0].max() + 1e-30))
    ok = finite_nonneg(v) and not v[below].any() and dev <= tol and jump <= 1e-3
    return {"ok": bool(ok), "max_dev_from_spec": dev, "jump_over_value_at_2deg": jump}


def case_dir_horizon(quick: bool) -> dict:
    r = [horizon_check(m) for m in _materials()]
    return {
        "ok": all(x["ok"] for x in r),
        "max_dev_from_spec": max(x["max_dev_from_spec"] for x in r),
        "max_jump_over_value_at_2deg": max(x["jump_over_value_at_2deg"] for x in r),
        "note": "reference twin; light elevation +2..-2 deg (down to 1e-4 deg)",
    }


def case_dir_horizon_gpu(quick: bool) -> dict:
    r = [horizon_check(m, p, gpu=True) for m in _materials()[:2] for p in ("f32", "f16")]
    return {
        "ok": all(x["ok"] for x in r),
        "max_dev_from_spec": max(x["max_dev_from_spec"] for x in r),
        "max_jump_over_value_at_2deg": max(x["jump_over_value_at_2deg"] for x in r),
        "note": "GPU kernel, f32 and f16",
    }


def grazing_views(mat, precision="f32", gpu=False, R=16):
    """Eye and light at 89.99 deg (and exactly along the normal) on a 0.1 m quad, both 1000 m
    away (so every texel sees the same angles), 1e6 W/sr: list of (GPU or twin, twin)."""
    at = quad_atlas(R, mesh=quad_mesh(0.1))
    g = GpuShade(at, mat, precision) if gpu else None
    out = []
    for te, tl in ((GRAZING, GRAZING), (0.0, GRAZING), (GRAZING, 0.0), (0.0, 0.0)):
        eye = direction(te, 180) * 1000
        lp = direction(tl, 0)[None] * 1000
        lc = np.full((1, 3), 1e6)
        want, _ = ref.shade_texture_space(at, mat, np.eye(4), eye, lp, lc)
        out.append((g.shade(np.eye(4), eye, lp, lc) if gpu else want, want))
    return out


def case_dir_grazing_gpu(quick: bool) -> dict:
    worst, ok = 0.0, True
    for mat in _materials()[:2]:
        for prec in ("f32", "f16"):
            for got, want in grazing_views(mat, prec, gpu=True):
                ok &= finite_nonneg(got) and np.array_equal(got[..., 3], want[..., 3])
                w16 = want[..., :3].astype(np.float16).astype(np.float32)
                e = np.abs(got[..., :3] - w16) / (np.abs(w16) + 1e-2 * max(w16.max(), 1e-12))
                worst = max(worst, float(e.max()))
    return {"ok": bool(ok and worst <= 0.25), "max_rel_err_vs_twin": worst}


def unnormalized_check(gpu=False) -> dict:
    """Frames stored at scale 7 (normals) and 1e-3 (tangents), and a model matrix with a
    non-uniform scale, shade exactly like unit frames on the pre-scaled mesh."""
    mat = random_material(5)
    eye, lp, lc = np.float32([0.2, -0.3, 1.2]), np.float32([[0.4, 0.3, 0.9]]), np.ones((1, 3))
    a = quad_atlas(16)
    b = quad_atlas(16, mesh=quad_mesh(normal_scale=7.0, tangent_scale=1e-3))
    model = np.diag([2.0, 0.5, 3.0, 1.0])
    m2 = quad_mesh()
    m2.positions = (m2.positions * np.float32([2.0, 0.5, 3.0])).astype(np.float32)
    c = quad_atlas(16, mesh=m2)

    def shade(at, m):
        if gpu:
            return GpuShade(at, mat).shade(m, eye, lp, lc)
        return ref.shade_texture_space(at, mat, m, eye, lp, lc)[0]

    ra, rb, rm, rc = shade(a, np.eye(4)), shade(b, np.eye(4)), shade(a, model), shade(c, np.eye(4))
    d1 = float(np.abs(ra - rb).max())
    d2 = float((np.abs(rm - rc) / (np.abs(rc) + 1e-3)).max())
    # 2^-9: a couple of f16 ulps (f32 math in another order, then the rgba16float store)
    return {"ok": finite_nonneg(rb) and d1 <= 1e-6 and d2 <= 2.0**-9, "d_frames": d1, "d_scale": d2}


def case_dir_unnormalized(quick: bool) -> dict:
    r, g = unnormalized_check(False), unnormalized_check(True)
    return {
        "ok": r["ok"] and g["ok"],
        **{f"ref_{k}": v for k, v in r.items() if k != "ok"},
        **{f"gpu_{k}": v for k, v in g.items() if k != "ok"},
    }
