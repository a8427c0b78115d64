"""Hand-made meshes and atlases for the runtime tests (independent of vrneural.atlas), the
multiply-add count of generated WGSL, and the check of a `vrneural run` option's choices."""

from __future__ import annotations

import re

import numpy as np
import pytest

from vrneural.atlas.types import Atlas, Mesh


def quad_mesh(size: float = 1.0, tilt: float = 0.0) -> Mesh:
    """A square ``size`` m wide in the xy plane (centred, normal +z, optionally rotated about x
    by ``tilt`` radians), material uv = (x, y) / size + 0.5, tangent +x."""
    s = size / 2
    p = np.array([[-s, -s, 0], [s, -s, 0], [-s, s, 0], [s, s, 0]], np.float32)
    c, si = np.cos(tilt), np.sin(tilt)
    rot = np.array([[1, 0, 0], [0, c, -si], [0, si, c]], np.float32)
    n = np.tile(rot @ np.float32([0, 0, 1]), (4, 1)).astype(np.float32)
    t = np.zeros((4, 4), np.float32)
    t[:, :3] = rot @ np.float32([1, 0, 0])
    t[:, 3] = 1.0
    uv = (p[:, :2] / size + 0.5).astype(np.float32)
    return Mesh(
        "quad",
        (p @ rot.T).astype(np.float32),
        np.array([[0, 1, 2], [1, 3, 2]], np.uint32),
        n,
        t,
        uv,
    )


def quad_atlas(
    res: int = 32, lo: float = 0.125, hi: float = 0.875, size: float = 1.0, tilt: float = 0.0
) -> Atlas:
    """The quad mapped to atlas square ``[lo, hi]^2``; texels outside are EMPTY (a 1-texel
    gutter keeps the nearest triangle)."""
    from extremes.fixtures import quad_atlas as fixture_quad_atlas

    return fixture_quad_atlas(res, lo, hi, mesh=quad_mesh(size, tilt))


def assert_moved_lookup_parity(
    at, mat, unmoved, eye, lp, lc, tiling, filtering: str = "exact"
) -> None:
    """The texture-space pass of ``mat`` (a pack whose lookups move: height parallax or the
    neural offset) at ``eye`` against its numpy twin: 99.9% of texels within 2 float16 ulps,
    none over 5%, and the move (``mat`` against ``unmoved``) at least 50x that error;
    ``filtering`` of the neural textures and the height field (codegen_sample.FILTERS)."""
    from vrneural.runtime import reference as ref
    from vrneural.runtime.texture_pass import shade_texture_space

    want, wc = ref.shade_texture_space(at, mat, np.eye(4), eye, lp, lc, tiling=tiling)
    got, gc = shade_texture_space(
        at, mat, np.eye(4), eye, lp, lc, tiling=tiling, filtering=filtering
    )
    np.testing.assert_array_equal(gc, wc)
    w16 = want.astype(np.float16).astype(np.float32)
    scale = 1e-2 * max(w16.max(), 1e-12)
    rel = np.abs(got - w16) / (np.abs(w16) + scale)
    # f32 math in another order; where a lane's march ends a step earlier or later the
    # refinement lands within float rounding, so only a few texels exceed 2 f16 ulps
    assert np.quantile(rel, 0.999) <= 2 * 2.0**-10
    assert rel.max() < 0.05
    base, _ = ref.shade_texture_space(at, unmoved, np.eye(4), eye, lp, lc, tiling=tiling)
    assert np.abs(base - want).max() > 50 * np.abs(got - w16).max()  # the move shows


def assert_auto_march_parity(mat, unmoved, filtering: str = "exact") -> None:
    """March ``"auto"`` of ``mat`` (a pack whose lookups move) on the sphere's atlas at a
    tiling where some blocks span at most half a texel of the march's grid per atlas texel and
    others more: both routes run in one dispatch, and the kernel follows the twin
    (:func:`assert_moved_lookup_parity`) at a grazing and a near-normal eye."""
    import dataclasses

    from vrneural.atlas import build_atlas
    from vrneural.parallax import auto_blocks
    from vrneural.runtime.assets import get_mesh
    from vrneural.runtime.reference import block_geometry

    auto = dataclasses.replace(mat, parallax={**mat.parallax, "march": "auto"})
    at = build_atlas(get_mesh("sphere"), 64)
    tl = (0.3, 0.3, 0.0, 0.0)
    per_block = auto_blocks(block_geometry(at)["foot"] * np.float32(0.3), auto.march_grid)
    assert 0.2 < per_block.mean() < 0.8, per_block.mean()  # both routes are taken
    lp, lc = np.float32([[0.3, 0.4, 2.0]]), np.ones((1, 3))
    for eye in (np.float32([0.0, 1.5, 0.8]), np.float32([1.2, 0.3, 0.5])):
        assert_moved_lookup_parity(at, auto, unmoved, eye, lp, lc, tl, filtering)


def render_grazing_plane(tmp_path, pack, mode):
    """One eye (128^2, 70 deg) of a 1 m plane carrying ``pack`` (a file in ``tmp_path``), seen
    at 50-75 degrees, rendered in ``mode``; ``[128, 128, 3]`` float32."""
    import tomllib

    from vrneural.runtime.renderer import Renderer, Settings
    from vrneural.runtime.scene import parse_scene

    # a head 0.5 m above a 1 m plane, 1.2 m off to the side: views of 50-75 degrees
    pose = "t,x,y,z,qx,qy,qz,qw\n0,0,0.5,1.2,-0.3826834,0,0,0.9238795\n"
    (tmp_path / "pose.csv").write_text(pose)
    toml = f"""
[head]
path = "pose.csv"
[[objects]]
mesh = "plane"
[objects.material]
pack = "{pack}"
scale = 1.0
[[lights]]
position = [0.2, 0.8, 0.3]
intensity = 2.0
"""
    scene = parse_scene(tomllib.loads(toml), "t.toml", tmp_path)
    s = Settings(eyes=1, reuse=0, texture_res=512, eye_res=(128, 128), fov_y=70.0, n_lights=1,
                 mode=mode)  # fmt: skip
    r = Renderer(scene, s)
    r.frame(0)
    return r.read_eyes()[0][..., :3].astype(np.float32)


def mode_and_move_gaps(tmp_path, moved, unmoved) -> tuple[float, float]:
    """``(modes, move)``: the mean difference on the grazing plane between the texture-space
    and the screen-space render of ``moved`` (a pack whose lookups move), and between its
    screen-space render and that of ``unmoved``, over the pixels the plane covers (at least
    5% of the image)."""
    from vrneural.formats.vrnm import write_vrnm

    write_vrnm(tmp_path / "moved.vrnm", moved)
    write_vrnm(tmp_path / "unmoved.vrnm", unmoved)
    tex = render_grazing_plane(tmp_path, "moved.vrnm", "texture")
    scr = render_grazing_plane(tmp_path, "moved.vrnm", "screen")
    scr_unmoved = render_grazing_plane(tmp_path, "unmoved.vrnm", "screen")
    seen = scr.sum(-1) > 0
    assert seen.mean() > 0.05
    return float(np.abs(tex - scr)[seen].mean()), float(np.abs(scr_unmoved - scr)[seen].mean())


def count_macs(wgsl: str) -> int:
    """Multiply-adds by constant weights in unrolled WGSL (``<literal> * <value>`` terms)."""
    return len(re.findall(r"(?<![\w.])-?[0-9][0-9.e+-]*[fh] \* ", wgsl))


def assert_run_takes_choice(capsys, field: str, default, good, bad, match: str, **cfg) -> None:
    """`vrneural run --FIELD BAD` stops in argparse's choices (exit 2, one line naming the flag
    and the value); ``RunConfig``'s default is ``default``; ``resolve`` keeps ``good`` (beside
    the other fields ``cfg``) and refuses ``bad`` given in Python with ``match``."""
    from vrneural.cli import main
    from vrneural.errors import VrnError
    from vrneural.gpu.device import adapter_summary
    from vrneural.runtime.config import RunConfig, resolve
    from vrneural.runtime.scene import builtin_scene

    flag = "--" + field.replace("_", "-")
    with pytest.raises(SystemExit) as e:
        main(["run", flag, bad, "--profile", "tiny"])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and flag in err and bad in err
    assert getattr(RunConfig(), field) == default
    ad, scene = adapter_summary(), builtin_scene(1)
    got = resolve(RunConfig(profile="tiny", **cfg, **{field: good}), scene, ad)
    assert getattr(got, field) == good
    with pytest.raises(VrnError, match=match):
        resolve(RunConfig(profile="tiny", **{field: bad}), scene, ad)


def f16_rel_err(got: np.ndarray, want: np.ndarray) -> float:
    """The largest error of a GPU radiance texture ``got`` against its twin's ``want`` (stored
    as float16, as the GPU stores it), relative to each texel (1% of the maximum at least)."""
    w16 = want.astype(np.float16).astype(np.float32)
    return float((np.abs(got - w16) / (np.abs(w16) + 1e-2 * max(w16.max(), 1e-12))).max())


def assert_gpu_matches_twin(at, mat, eye, lp, lc, filtering="exact", **kw) -> np.ndarray:
    """The texture-space pass on the GPU against its numpy twin (``kw``: their shared options,
    tiling, lod_scale, taps, ...): the same counters, and the texels within 2 float16 ulps (f32
    math in another order, f16 storage on both sides). Returns the twin's texture."""
    from vrneural.runtime import reference as ref
    from vrneural.runtime.texture_pass import shade_texture_space

    want, wc = ref.shade_texture_space(at, mat, np.eye(4), eye, lp, lc, **kw)
    got, gc = shade_texture_space(at, mat, np.eye(4), eye, lp, lc, filtering=filtering, **kw)
    np.testing.assert_array_equal(gc, wc)
    assert f16_rel_err(got, want) <= 2 * 2.0**-10
    return want
