"""The Python API (README: Python API) gives one-line VrnErrors for wrong values and types,
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


def test_eval_config_from_python(tmp_path):
    from vrneural.scoring.run import evaluate
    from vrneural.scoring.score import EvalConfig

    with pytest.raises(VrnError, match=r"--precision = 'half'.*f32, f16, both"):
        evaluate(EvalConfig(packs=("x.vrnm",), precision="half"), progress=False)
    with pytest.raises(VrnError, match=r"nope\.vrnm: no such pack"):  # a bare path is one pack
        evaluate(EvalConfig(packs=str(tmp_path / "nope.vrnm")), progress=False)


def test_renderer_wants_resolved_settings():
    with pytest.raises(VrnError, match=r"expected Settings.*resolve\("):
        Renderer(None, RunConfig(profile="tiny"))


def test_parse_res_takes_a_tuple():
    assert parse_res((64, 48)) == parse_res("64x48") == (64, 48)


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
    ]
    for kw, msg in bad:
        with pytest.raises(VrnError, match=msg):
            resolve(RunConfig(profile="tiny", **kw), scene, ad)
    with pytest.raises(VrnError, match=r"scene is a str, expected a Scene"):
        resolve(RunConfig(profile="tiny"), "demo/scene.toml", ad)
    with pytest.raises(VrnError, match=r"adapter must be adapter_summary\(\)"):
        resolve(RunConfig(profile="tiny"), scene, None)
    s = resolve(RunConfig(profile="tiny", frames=1, eye_res=(64, 48)), scene, ad)
    assert s.eye_res == (64, 48)
    r = Renderer(scene, s)
    r.frame(0)
    assert r.radiance(2, 1).shape[-1] == 4
    with pytest.raises(VrnError, match=r"obj = 3 is out of range.*3 neural objects"):
        r.radiance(obj=3)
    with pytest.raises(VrnError, match=r"eye = 2 is out of range"):
        r.radiance(eye=2)
    screen = Renderer(scene, resolve(RunConfig(profile="tiny", mode="screen"), scene, ad))
    with pytest.raises(VrnError, match=r"only in mode 'texture'"):
        screen.radiance()
