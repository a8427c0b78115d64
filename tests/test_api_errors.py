"""The Python API (docs/python-api.md) gives one-line VrnErrors for wrong values and types,
as the CLI does, instead of tracebacks from deep inside."""

from __future__ import annotations

import numpy as np
import pytest

from vrneural.errors import VrnError
from vrneural.material import material_forward, random_material
from vrneural.runtime.config import RunConfig, parse_res
from vrneural.runtime.renderer import Renderer
from vrneural.scoring.score import pick_slices, predict_slice, texel_blocks


def test_numpy_functions_name_the_bad_argument():
    mat = random_material(0)
    uv = texel_blocks(4, 4)
    with pytest.raises(VrnError, match=r"15x15.*even"):
        texel_blocks(15, 15)
    with pytest.raises(VrnError, match=r"wi has shape \[2, 3\], expected \[3\]"):
        predict_slice(mat, np.zeros((2, 3)), np.array([0, 0, 1.0]), uv, 4, 4, "f32")
    with pytest.raises(VrnError, match=r"wi has shape \[3\], expected \[N, 3\].*wi\[None\]"):
        material_forward(mat, np.array([0, 0, 1.0]), np.array([0, 0, 1.0]), uv[:1])
    assert pick_slices(3, 10, 64) == pick_slices("3", 10, 64)  # an int from Python
    # NaN directions gave NaN values, silently
    up = np.array([[0, 0, 1.0]])
    with pytest.raises(VrnError, match=r"material_forward: wo holds NaN/Inf values"):
        material_forward(mat, up, np.array([[np.nan, 0, 1.0]]), uv[:1])


def test_score_pairs_and_atlas_sizes_are_checked(tmp_path):
    """An index past the BTF's slices was an IndexError and a negative one wrapped around;
    a string resolution was a TypeError, a float one was taken."""
    import trimesh

    from vrneural.atlas import build_atlas, make_mesh
    from vrneural.btf import direction_set, read_btf, write_btf
    from vrneural.scoring.score import score

    d = direction_set(3)
    btf = read_btf(write_btf(tmp_path / "t.btf", np.ones((3, 3, 4, 4, 3)), d, d, {"name": "t"}))
    for p in (9, -1, 2.0, True):
        with pytest.raises(VrnError, match=rf"score: pair {p!r} is out of range.*\[0, 8\]"):
            score([random_material(0)], btf, [0, p], ["f32"])
    assert len(score([random_material(0)], btf, [0, 8], ["f32"])["scores"]) == 1
    box = trimesh.creation.box()
    mesh = make_mesh("box", box.vertices, box.faces)
    for res, msg in (("64", "'64' must be a whole number"), (64.0, "64.0 must be a whole")):
        with pytest.raises(VrnError, match=f"resolution = {msg}"):
            build_atlas(mesh, res, cache=False)


def test_eval_config_from_python(tmp_path):
    from vrneural.scoring.config import EvalConfig
    from vrneural.scoring.run import evaluate

    with pytest.raises(VrnError, match=r"--precision = 'half'.*f32, f16, both"):
        evaluate(EvalConfig(packs=("x.vrnm",), precision="half"), progress=False)
    with pytest.raises(VrnError, match=r"nope\.vrnm: no such pack"):  # a bare path is one pack
        evaluate(EvalConfig(packs=str(tmp_path / "nope.vrnm")), progress=False)


def test_renderer_wants_resolved_settings():
    with pytest.raises(VrnError, match=r"expected Settings.*resolve\("):
        Renderer(None, RunConfig(profile="tiny"))


def test_parse_res_takes_a_tuple():
    assert parse_res((64, 48)) == parse_res("64x48") == parse_res(" 64 X 48 ") == (64, 48)


@pytest.mark.parametrize(
    "text", ["+32x+32", "\u0663\u0662x\u0663\u0662", "32x", "32x32x1", "1e2x32"]
)
def test_parse_res_takes_plain_digits_only(text):
    """int() takes signs, other scripts' digits and spaces inside: those were accepted."""
    with pytest.raises(VrnError, match="must be WIDTHxHEIGHT"):
        parse_res(text)


@pytest.mark.gpu
def test_resolve_and_radiance_checks(adapter):
    from vrneural.gpu.device import adapter_summary
    from vrneural.runtime.config import resolve
    from vrneural.runtime.scene import builtin_scene

    ad, scene = adapter_summary(), builtin_scene()
    bad = [
        (dict(mode="bogus"), r"--mode = 'bogus' is not allowed"),
        (dict(schedule="Burst"), r"--schedule = 'Burst' is not allowed"),
        (dict(frames="4"), r"--frames = '4' must be a whole number"),
        # these were TypeErrors from a comparison, or (floats) silently truncated
        (dict(reuse="4"), r"--reuse = '4' must be a whole number"),  # or 'auto'
        (dict(reuse=2.5), r"--reuse = 2.5 must be a whole number"),
        (dict(texture_res="128"), r"--texture-res = '128' must be a whole number"),
        (dict(lights=1.7), r"--lights = 1.7 must be a whole number"),
        (dict(profile=""), r"--profile is empty; choose one of: quest3"),
        # run-only fields were ignored: the bundled materials rendered instead of the pack
        (dict(pack="/nonexistent/x.vrnm"), r"RunConfig.pack = .*use_pack\(scene, path\)"),
        (dict(scene="s.toml"), r"RunConfig.scene = 's.toml' is the command line's"),
    ]
    for kw, msg in bad:
        with pytest.raises(VrnError, match=msg):
            resolve(RunConfig(**{"profile": "tiny", **kw}), scene, ad)
    with pytest.raises(VrnError, match=r"scene is a str, expected a Scene"):
        resolve(RunConfig(profile="tiny"), "demo/scene.toml", ad)
    with pytest.raises(VrnError, match=r"adapter must be adapter_summary\(\)"):
        resolve(RunConfig(profile="tiny"), scene, None)
    s = resolve(RunConfig(profile="tiny", frames=1, eye_res=(64, 48)), scene, ad)
    assert s.eye_res == (64, 48)
    r = Renderer(scene, s)
    for f, msg in (("2", "'2' must be a whole"), (1.5, "1.5 must be a whole"), (-1, "-1 is out")):
        with pytest.raises(VrnError, match=f"frame = {msg}"):
            r.frame(f)
    r.frame(0)
    with pytest.raises(VrnError, match=r"radiance: obj = 1.0 must be a whole number"):
        r.radiance(obj=1.0)
    with pytest.raises(VrnError, match=r"builtin_scene: n_lights = '3' must be a whole number"):
        builtin_scene("3")
    assert r.radiance(2, 1).shape[-1] == 4
    with pytest.raises(VrnError, match=r"obj = 3 is out of range.*3 neural objects"):
        r.radiance(obj=3)
    with pytest.raises(VrnError, match=r"eye = 2 is out of range"):
        r.radiance(eye=2)
    screen = Renderer(scene, resolve(RunConfig(profile="tiny", mode="screen"), scene, ad))
    with pytest.raises(VrnError, match=r"only in mode 'texture'"):
        screen.radiance()
