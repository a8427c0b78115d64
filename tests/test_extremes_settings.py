"""Extreme run settings: texture resolution (2, odd, above the maximum), reuse N = 0 and 1000,
0 and 16 lights, 1 eye, 1 frame — through RunConfig -> resolve -> Renderer."""

import pytest
from extremes import settings as sett

from vrneural.errors import VrnError


@pytest.mark.gpu
@pytest.mark.parametrize(
    ("res", "msg"), [(2, "out of range"), (6, "out of range"), (129, "must be even")]
)
def test_texture_resolution_rejections(res, msg):
    with pytest.raises(VrnError, match=msg) as e:
        sett.render(frames=1, texture_res=res)
    assert "--texture-res" in str(e.value) and "\n" not in str(e.value)


@pytest.mark.gpu
def test_cli_accepts_zero_lights(tmp_path):
    from vrneural.cli import main

    scene = tmp_path / "s.toml"
    scene.write_text(sett.SCENE_TOML)  # no [[lights]]
    out = tmp_path / "run"
    argv = ["run", str(scene), "--profile", "tiny", "--lights", "0", "--frames", "1"]
    code = main([*argv, "--eyes", "1", "--eye-res", "32x32", "--out", str(out)])
    assert code == 0 and (out / "summary.json").is_file()
    assert (out / "mono.mp4").is_file() and not (out / "stereo.mp4").exists()  # one eye
