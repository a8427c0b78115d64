"""The per-frame host paths written for speed (#41) against the plain formulas they replace:
the head path, look rotation and frustum planes in scalar arithmetic, and the uniforms written
as words into the arena instead of record fields (the same bytes)."""

import numpy as np
import pytest

from vrneural.runtime.camera import OrbitPath, frustum_planes, look_rotation
from vrneural.runtime.interface import FRAME, LIGHT, TEXTURE_PARAMS
from vrneural.runtime.texture_pass import light_words, pack_lights_into, pack_params_into

RNG = np.random.default_rng(7)


def _look_numpy(forward, up=(0.0, 1.0, 0.0)):
    f = np.asarray(forward, np.float64)
    f = f / np.linalg.norm(f)
    r = np.cross(f, up)
    r = r / np.linalg.norm(r)
    return np.stack([r, np.cross(r, f), -f], 1)


def test_look_rotation_is_the_cross_product_formula():
    for f in [*RNG.normal(size=(50, 3)), (0.0, 0.0, -1.0), (1e-3, -1.0, 0.0)]:
        np.testing.assert_allclose(look_rotation(f), _look_numpy(f), rtol=0, atol=1e-15)
        r = look_rotation(f)
        np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-14)
    up = (0.3, 0.2, 0.9)
    np.testing.assert_allclose(
        look_rotation((1, 2, 3), up), _look_numpy((1, 2, 3), up), rtol=0, atol=1e-15
    )


def test_orbit_path_pose_is_the_ellipse_looking_at_the_target():
    path = OrbitPath()
    for t in (0.0, 0.7, 3.1, 8.0, 123.4):
        a = 2 * np.pi * t / path.period
        want = np.asarray(path.centre) + path.sway * np.array([np.sin(a), 0.3 * np.sin(2 * a), 0])
        p, rot = path.pose(t)
        np.testing.assert_allclose(p, want, rtol=0, atol=1e-15)
        np.testing.assert_allclose(rot, _look_numpy(np.asarray(path.target) - want), atol=1e-15)


def test_frustum_planes_are_the_clip_rows():
    for _ in range(20):
        m = RNG.normal(size=(4, 4))
        planes = np.stack([m[3] + m[0], m[3] - m[0], m[3] + m[1], m[3] - m[1], m[2], m[3] - m[2]])
        want = planes / np.linalg.norm(planes[:, :3], axis=1, keepdims=True)
        np.testing.assert_allclose(frustum_planes(m), want, rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("n, k", [(1, 1), (3, 2), (4, 4)])
def test_light_words_are_the_light_records(n, k):
    lp, lc = RNG.normal(size=(k, 3)) * 5, RNG.random((k, 3)) * 3
    origin = RNG.normal(size=3)
    for o in (None, origin):
        rec = LIGHT.zeros(n)
        pack_lights_into(rec, lp, lc, o)
        words = np.full(8 * n, np.nan, np.float32)  # stale values everywhere: all rewritten
        light_words(words, lp, lc, o)
        assert words.tobytes() == rec.tobytes()


@pytest.mark.gpu
def test_texture_target_update_writes_the_params_record():
    """TextureTarget.update's words == pack_params_into + pack_lights_into, written into an
    arena whose regions held other values before (every word is rewritten)."""
    atlas_mod = pytest.importorskip("vrneural.atlas")
    from vrneural.gpu.uniforms import UniformArena
    from vrneural.material import random_material
    from vrneural.runtime.gpu_material import GpuAtlas
    from vrneural.runtime.texture_pass import CounterBuffer, TextureSpacePass, TextureTarget

    at = atlas_mod.build_atlas(atlas_mod.builtin_mesh("sphere"), 32, cache=False)
    tp = TextureSpacePass(random_material(3), "f32", 3)
    arena = UniformArena("test")
    tgt = TextureTarget(tp, GpuAtlas(at), CounterBuffer(2), arena)
    arena.words(0, arena.size)[:] = np.nan
    for rep in range(3):
        model = np.eye(4)
        model[:3, :3] = RNG.normal(size=(3, 3))
        model[:3, 3] = RNG.normal(size=3) * 100  # far from the origin: float64 first
        eye = RNG.normal(size=3) * 100 + model[:3, 3]
        lp, lc = RNG.normal(size=(2, 3)), RNG.random((2, 3))
        tiling, phase, period, slot, margin = (2.0, 3.0, 0.5, 0.25), rep % 2, 2, rep % 2, 0.03
        scale = 1.0 + 0.7 * rep
        tgt.update(model, eye, tiling, lp, lc, phase, period, slot, margin, scale)
        p = TEXTURE_PARAMS.zeros()
        span = tgt.gatlas.block_list(period)[1][phase]
        pack_params_into(p, model, eye, tiling, *span, slot, margin, lod_scale=scale)
        got = arena.host[tgt.p_off : tgt.p_off + TEXTURE_PARAMS.size]
        assert got.tobytes() == p.tobytes()
        lights = LIGHT.zeros(3)
        pack_lights_into(lights, lp, lc, eye)
        got = arena.host[tgt.l_off : tgt.l_off + 3 * LIGHT.size]
        assert got.tobytes() == lights.tobytes()
    assert arena.lo <= tgt.p_off and arena.hi >= tgt.l_off + 3 * LIGHT.size  # sent at flush


@pytest.mark.gpu
def test_eye_targets_update_writes_the_frame_record():
    from vrneural.gpu.uniforms import UniformArena
    from vrneural.runtime import forward as fw

    arena = UniformArena("test")
    et = fw.EyeTargets(8, 8, 3, arena=arena)
    arena.words(0, arena.size)[:] = np.nan
    vp, pos = RNG.normal(size=(4, 4)), RNG.normal(size=3)
    lp, lc = RNG.normal(size=(2, 3)), RNG.random((2, 3))
    et.update(vp, pos, lp, lc)
    f = FRAME.zeros()
    f["view_proj"] = vp.T
    f["eye"] = (*pos, 0.0)
    f["info"] = (2, 0, 0, 0)
    assert arena.host[et.f_off : et.f_off + FRAME.size].tobytes() == f.tobytes()
    lights = LIGHT.zeros(3)
    pack_lights_into(lights, lp, lc)
    assert arena.host[et.l_off : et.l_off + 3 * LIGHT.size].tobytes() == lights.tobytes()


@pytest.mark.gpu
def test_visibility_of_all_objects_at_once_is_each_objects():
    from vrneural.runtime.renderer import Renderer, Settings
    from vrneural.runtime.scene import builtin_scene

    r = Renderer(builtin_scene(2), Settings(eyes=2, texture_res=64, eye_res=(16, 16)))
    seen = set()
    for _ in range(40):  # heads turned all round, some objects in view, some not
        f = RNG.normal(size=3)
        head = (RNG.normal(size=3) * 0.5 + (0, 1.2, 1.0), look_rotation(f))
        eyes = r.eyes_at(0, head=head)
        want = [r._visible(n, eyes) for n in r.neural]
        assert r._visible_all(eyes) == want
        seen.add(tuple(want))
    assert len(seen) > 2  # the poses did cull and show objects


def test_light_arrays_are_the_lights_positions_and_radiance():
    from vrneural.runtime.lights import PointLight, default_lights, light_arrays

    lights = [*default_lights(3), PointLight((0.5, 2.0, -1.0), (0.2, 0.4, 0.9), 7.5)]
    for t in (0.0, 1.3, 42.0):
        pos, rgb = light_arrays(lights, t)
        for lt, p, c in zip(lights, pos, rgb, strict=True):
            want = np.asarray(lt.position, np.float64)
            if lt.motion == "circle":
                a = lt.phase + 2 * np.pi * t / lt.period
                want = want + lt.radius * np.array([np.cos(a), 0.0, np.sin(a)])
            np.testing.assert_allclose(p, want, rtol=0, atol=1e-15)
            np.testing.assert_array_equal(p, lt.at(t))
            assert (
                c.tobytes()
                == (np.asarray(lt.colour, np.float64) * lt.intensity).astype(np.float32).tobytes()
            )
        assert pos.dtype == np.float64 and rgb.dtype == np.float32
    pos, rgb = light_arrays([], 0.0)
    assert pos.shape == rgb.shape == (0, 3)


def test_look_rotation_straight_up_or_down_is_a_rotation():
    for f in ((0.0, 1.0, 0.0), (0.0, -3.0, 0.0)):
        r = look_rotation(f)
        np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-15)
        np.testing.assert_allclose(-r[:, 2], np.asarray(f) / np.linalg.norm(f))
        assert np.linalg.det(r) > 0
