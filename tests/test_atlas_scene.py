"""The scene field `atlas_uv` and the announced set-up stages of `vrneural run`."""

from __future__ import annotations

import pytest
import tomllib

from vrneural.errors import VrnError
from vrneural.runtime.scene import parse_scene

SCENE = """
[[objects]]
mesh = "plane"
{extra}
[objects.material]
{material}
[[lights]]
position = [0.1, 0.6, 0.2]
"""


def _parse(tmp_path, extra="", material='procedural = "lambertian"'):
    text = SCENE.format(extra=extra, material=material)
    return parse_scene(tomllib.loads(text), "s.toml", tmp_path)


def test_atlas_uv_scene_field(tmp_path):
    assert _parse(tmp_path).objects[0].atlas_uv == "auto"
    assert _parse(tmp_path, 'atlas_uv = "mesh"').objects[0].atlas_uv == "mesh"
    with pytest.raises(VrnError) as e:
        _parse(tmp_path, 'atlas_uv = "lightmap"')
    assert str(e.value) == (
        "s.toml: objects[0].atlas_uv = 'lightmap' is not allowed; choose one of: auto, mesh, "
        "charts, xatlas"
    )
    with pytest.raises(VrnError, match=r"objects\[0\].atlas_uv is set on a plain object"):
        _parse(tmp_path, 'atlas_uv = "charts"', 'kind = "plain"')


@pytest.mark.gpu
def test_run_set_up_stages_are_announced(tmp_path):
    """Mesh load, atlas and shader compile of each object go to the progress callback (`run`
    shows them on a transient bar), in that order; the atlas uses the scene's atlas_uv."""
    from vrneural.runtime.renderer import Renderer, Settings

    seen = []
    s = Settings(eyes=1, reuse=0, texture_res=64, eye_res=(32, 32), n_lights=1)
    r = Renderer(_parse(tmp_path, 'atlas_uv = "xatlas"'), s, progress=seen.append)
    assert seen == [
        "plane: load mesh plane",
        "plane: atlas 64^2, 512 triangles",
        "plane: compile shaders (texture mode)",
    ]
    assert r.neural[0].atlas.stats["unwrap_path"][0] == "xatlas"
