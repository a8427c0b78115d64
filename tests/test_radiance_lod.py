"""Level of detail of the radiance textures: coverage-weighted mip chains (twin and GPU), the
forward pass sampling them, and each object's texture side from its size on screen."""

import dataclasses

import numpy as np
import pytest

from vrneural.runtime.radiance_mips import mip_chain, mip_count
from vrneural.runtime.screen_res import choose, level_sides, wanted_side


def test_mip_levels_are_coverage_weighted():
    """A chart edge averages only its shaded texels: colour / alpha stays the chart's colour
    (empty texels would darken it by half in a plain mean)."""
    lv0 = np.zeros((16, 16, 4), np.float32)
    lv0[:, :5] = (0.3, 0.6, 0.9, 1.0)  # a chart 5 texels wide; the rest empty (0)
    chain = mip_chain(lv0, 3)
    assert [c.shape[0] for c in chain] == [16, 8, 4]
    for c in chain[1:]:
        a = c[..., 3]
        covered = a > 0
        ratio = c[covered][:, :3] / a[covered][:, None]
        np.testing.assert_allclose(ratio, np.broadcast_to([0.3, 0.6, 0.9], ratio.shape), rtol=2e-3)
        assert 0 < a[covered].min() < 1  # the edge texels are partly covered
    assert mip_count(1200) == 7 and mip_count(64) == 4 and mip_count(8) == 1


def test_screen_levels_and_their_hysteresis():
    assert level_sides(1200) == (1200, 1024, 512, 256, 128, 64, 32, 16)
    assert level_sides(512) == (512, 256, 128, 64, 32, 16)
    sides = level_sides(1024)
    # one texel per pixel: a side inversely proportional to the distance
    w1 = wanted_side(1.0, 0.6, 1.0, 96.0, 2208)
    assert abs(wanted_side(1.0, 0.6, 10.0, 96.0, 2208) * 10 - w1) < 1e-6 * w1
    assert choose(sides, 256, 300) == 512  # up at once
    assert choose(sides, 512, 250) == 512  # 256 would hold 250 but not with the margin
    assert choose(sides, 512, 200) == 256  # down with the margin
    # a want wobbling around a level boundary does not flip the level
    cur, seen = 512, set()
    for want in 256 * (1 + 0.1 * np.sin(np.arange(40))):
        cur = choose(sides, cur, want)
        seen.add(cur)
    assert seen == {512}


@pytest.mark.gpu
def test_gpu_mip_chain_equals_its_twin():
    from runtime_helpers import quad_atlas

    from vrneural.gpu.device import get_device
    from vrneural.gpu.readback import read_texture
    from vrneural.material import random_material
    from vrneural.runtime.gpu_material import GpuAtlas
    from vrneural.runtime.texture_pass import CounterBuffer, TextureSpacePass, TextureTarget

    at = quad_atlas(64)
    tp = TextureSpacePass(random_material(2), "f32", 1)
    tgt = TextureTarget(tp, GpuAtlas(at), CounterBuffer(1), mips=True)
    tgt.update(
        np.eye(4), (0.2, 0.1, 1.5), (4, 4, 0, 0), np.float32([[0.3, 0.4, 2.0]]), np.ones((1, 3))
    )
    enc = get_device().create_command_encoder()
    tgt.encode(enc)
    get_device().queue.submit([enc.finish()])
    levels = tgt.texture.mip_level_count
    assert levels == mip_count(64) == 4
    want = mip_chain(read_texture(tgt.texture, 0).astype(np.float32), levels)
    for k in range(1, levels):
        got = read_texture(tgt.texture, k).astype(np.float32)
        # f16 storage of each level on both sides: one f16 ulp of the largest value
        np.testing.assert_allclose(got, want[k], atol=2.0**-10 * max(1.0, want[k].max()))


def _render(scene, s, frames=1, target=None):
    """Render ``frames`` frames; ``target``: a point the still head looks at (default: the
    scene's head path)."""
    from vrneural.bench import poses
    from vrneural.runtime.camera import OrbitPath
    from vrneural.runtime.renderer import Renderer

    r = Renderer(scene, s)
    if target is not None:
        r.head = OrbitPath(tuple(poses.HEAD), tuple(target), sway=0.0)  # still
    st = [r.frame(f) for f in range(frames)]
    return r, st, r.read_eyes()[0][..., :3]


def _plane_scene(mat, distance: float, tiling: float):
    """A 0.3 m neural square facing the eye ``distance`` m away (no floor), one light."""
    from pathlib import Path

    from vrneural.bench import poses
    from vrneural.runtime.assets import get_mesh
    from vrneural.runtime.lights import PointLight
    from vrneural.runtime.scene import MaterialDesc, ObjectDesc, Scene, model_matrix

    p = get_mesh("plane").positions
    scale = 0.3 / float((p.max(0) - p.min(0)).max())
    c = poses.HEAD + np.array([0.0, 0.0, -distance])
    obj = ObjectDesc("plane", "plane", model_matrix(tuple(c), (90, 0, 0), scale),
                     MaterialDesc("neural", mat, "m", tiling))  # fmt: skip
    light = PointLight(tuple(c + np.array([0.3, 0.4, 1.0])), (1, 1, 1), 2.0)
    return Scene("plane", [obj], [light], None, None, "orbit", Path.cwd())


@pytest.mark.gpu
def test_mips_leave_a_close_object_as_it_was_and_calm_a_far_one():
    """Up close (radiance texels magnified) the mip chain changes nothing but rounding; a
    finely tiled square far away (about 19 radiance texels per pixel) shows the average of its
    texels instead of aliasing: its pixels vary less across the square."""
    from vrneural.bench import trade_scene as ts
    from vrneural.material import random_material
    from vrneural.runtime.renderer import Settings

    mat = random_material(5)
    base = Settings(eyes=1, reuse=0, texture_res=256, eye_res=(64, 64), fov_y=40.0, n_lights=2)
    near = ts.Condition("near", "rest", 0.0, 1, [0], distance=0.12, tiling=4.0)
    imgs = [_render(ts.scene_for(near, mat), dataclasses.replace(base, mips=m))[2]
            for m in (False, True)]  # fmt: skip
    np.testing.assert_allclose(imgs[1], imgs[0], atol=2e-3 * imgs[0].max())
    s = dataclasses.replace(base, texture_res=512, fov_y=20.0, n_lights=1)
    from vrneural.bench import poses

    at = poses.HEAD + np.array([0.0, 0.0, -2.0])
    far = [_render(_plane_scene(mat, 2.0, 32.0), dataclasses.replace(s, mips=m), 1, at)[2]
           for m in (False, True)]  # fmt: skip
    on = far[0].max(-1) > 0
    assert 400 < on.sum() < 1200  # the square: about 27 x 27 pixels
    sd = [x[on].std(axis=0).mean() for x in far]  # across the square, per channel
    assert sd[1] < 0.6 * sd[0], sd


@pytest.mark.gpu
def test_a_far_object_is_shaded_at_a_smaller_side():
    """Resolution from the screen: at 10 m the sphere gets at most 1/10 of the texels it gets at
    1 m; a side it switches to is fully updated before it is shown (no empty texels show)."""
    from vrneural.bench import trade_scene as ts
    from vrneural.material import random_material
    from vrneural.runtime.renderer import Settings

    mat = random_material(5)
    s = Settings(eyes=1, reuse=4, texture_res=1024, eye_res=(128, 128), fov_y=96.0, n_lights=2,
                 screen_res=True, crop=(968, 1040, 2064, 2208))  # fmt: skip
    shaded, imgs = {}, {}
    for d in (0.3, 1.0, 10.0):
        cond = ts.Condition("d", "rest", 0.0, 1, [0], distance=d)
        _, st, imgs[d] = _render(ts.scene_for(cond, mat), s)
        shaded[d] = st[0].object_blocks[0]
        assert st[0].object_res[0] in level_sides(1024)
    assert shaded[10.0] <= shaded[1.0] / 10 < shaded[0.3] / 10
    # at 1 m, a smaller side than the cap, the same image as the cap's but for the texel
    # density: every pixel of the sphere shaded (no empty texel shows), no pop in brightness
    cond = ts.Condition("d", "rest", 0.0, 1, [0], distance=1.0)
    _, st, fixed = _render(ts.scene_for(cond, mat), dataclasses.replace(s, screen_res=False))
    got = imgs[1.0]
    on = fixed.max(-1) > 0
    assert ((got.max(-1) > 0) == on).mean() > 0.99
    assert np.abs(got[on] - fixed[on]).mean() < 0.1 * fixed[on].mean()


@pytest.mark.gpu
def test_the_pixel_footprint_prefilters_what_a_rounded_up_side_leaves():
    """Resolution from the screen rounds the side up to a power of two, so a texel can be up to
    2.5x smaller than a pixel; with lod_footprint "pixel" the pyramid is looked up at the
    pixel's footprint there (the scale side / wanted side, in summary's object_lod_scale), and
    the tiled sphere's pixels vary less than with the texel's footprint (scale 1). "auto": the
    pixel's without radiance mips, the texel's with them (the mips filter the rest)."""
    from test_neural_lod import pyramid_material

    from vrneural.bench import trade_scene as ts
    from vrneural.runtime.renderer import Settings
    from vrneural.runtime.screen_res import wanted_side

    mat = pyramid_material(4)
    s = Settings(eyes=1, reuse=0, texture_res=1024, eye_res=(128, 128), fov_y=12.0, n_lights=2,
                 screen_res=True)  # fmt: skip
    cond = ts.Condition("d", "rest", 0.0, 1, [0], distance=3.0, tiling=2.0)
    got = {}
    for fp, mips in (("pixel", False), ("texel", False), ("auto", False), ("auto", True)):
        sc, s1 = ts.scene_for(cond, mat), dataclasses.replace(s, lod_footprint=fp, mips=mips)
        r, st, img = _render(sc, s1, 1, cond.centre())  # the sphere fills most of the eye
        n = r.neural[0]
        c, rad = r.world_sphere(n)
        d = float(np.linalg.norm(c - r.eyes_at(0)[0].position)) - rad
        cover = float(np.mean(n.levels[n.level_sides[0]][0].tri_ids != 0xFFFFFFFF))
        want = wanted_side(n.area, cover, d, s.fov_y, s.eye_res[1])
        side = st[0].object_res[0]
        assert side >= want  # rounded up
        scale = side / want if fp == "pixel" or (fp == "auto" and not mips) else 1.0
        assert st[0].object_lod_scale == [pytest.approx(scale, rel=1e-6)]
        got[fp + " mips" * mips] = img
    np.testing.assert_array_equal(got["auto"], got["pixel"])
    assert 1.2 < side / want < 2.0  # this case: a scale that moves the level
    on = got["texel"].max(-1) > 0
    assert ((got["pixel"].max(-1) > 0) == on).all()  # the same pixels covered
    sd = {k: np.abs(np.diff(v, axis=1))[on[:, 1:] & on[:, :-1]].mean() for k, v in got.items()}
    assert sd["pixel"] < 0.9 * sd["texel"], sd


def test_run_takes_the_lod_footprint_and_refuses_another(capsys):
    from runtime_helpers import assert_run_takes_choice

    match = r"--lod-footprint = 'screen' is not allowed; choose auto"
    assert_run_takes_choice(
        capsys, "lod_footprint", "auto", "texel", "screen", match, screen_res=True
    )


@pytest.mark.gpu
def test_run_with_screen_res_records_sides_and_footprint_scales(tmp_path):
    import json

    from vrneural.cli import main

    out = tmp_path / "run"
    argv = ["run", "--frames", "2", "--eyes", "1", "--profile", "tiny", "--screen-res",
            "--no-video", "--save-frames", "none", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    sm = json.loads((out / "summary.json").read_text())
    assert sm["resolved"]["lod_footprint"] == "auto" and sm["resolved"]["screen_res"]
    pf = sm["per_frame"]
    n = len(pf["object_res"][0])
    assert n >= 1 and all(len(x) == n for x in pf["object_lod_scale"])
    assert all(s >= 1.0 for x in pf["object_lod_scale"] for s in x)
