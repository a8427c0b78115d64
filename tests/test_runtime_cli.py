"""`vrneural run` user errors: one line, exit code 2; and a tiny end-to-end run."""

import json

import pytest

from vrneural.cli import main

SCENE = """
[[objects]]
mesh = "plane"
[objects.material]
procedural = "lambertian"
scale = {scale}
[[lights]]
position = [0, 1, 0]
intensity = 1.0
"""


def _err(capsys, argv):
    rc = main(["run", *argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert len(err) == 1 and err[0].startswith("vrneural run: error:")
    return err[0]


def test_missing_scene_file(capsys, tmp_path):
    msg = _err(capsys, [str(tmp_path / "nope.toml"), "--out", str(tmp_path / "o")])
    assert "nope.toml" in msg and "not found" in msg


def test_bad_scene_field_is_named_by_path(capsys, tmp_path):
    p = tmp_path / "scene.toml"
    p.write_text(SCENE.format(scale=-1))
    msg = _err(capsys, [str(p), "--out", str(tmp_path / "o")])
    assert "scene.toml: objects[0].material.scale = -1" in msg and "out of range" in msg


def test_missing_pack_file(capsys, tmp_path):
    p = tmp_path / "scene.toml"
    p.write_text(SCENE.format(scale=1).replace('procedural = "lambertian"', 'pack = "x.vrnm"'))
    msg = _err(capsys, [str(p), "--out", str(tmp_path / "o")])
    assert "objects[0].material.pack" in msg and "not found" in msg


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["--eyes", "3"], "--eyes = 3"),
        (["--reuse", "-1"], "--reuse = -1"),
        (["--texture-res", "99999"], "--texture-res = 99999"),
        (["--eye-res", "12xfoo"], "--eye-res"),
        (["--mode", "reference", "--reference", "missing.vrnm"], "'missing.vrnm': file not"),
        (["--reference", "t.vrnm"], "only used by --mode reference"),
    ],
)
def test_bad_flags(capsys, tmp_path, argv, needle):
    msg = _err(capsys, ["--profile", "tiny", "--out", str(tmp_path / "o"), *argv])
    assert needle in msg and not (tmp_path / "o").exists()


def test_existing_output_needs_force(capsys, tmp_path):
    (tmp_path / "o").mkdir()
    msg = _err(capsys, ["--profile", "tiny", "--out", str(tmp_path / "o")])
    assert "--force" in msg


@pytest.mark.gpu
def test_tiny_run_writes_summary_and_frames(capsys, tmp_path):
    out = tmp_path / "o"
    rc = main(["run", "--profile", "tiny", "--frames", "6", "--out", str(out), "--quiet"])
    assert rc == 0
    sm = json.loads((out / "summary.json").read_text())
    assert sm["frames"] == 6 and sm["resolved"]["reuse"] == 4
    assert len(sm["per_frame"]["blocks_shaded"]) == 6
    assert sm["frame_wall_ms"]["p99"] >= sm["frame_wall_ms"]["median"] > 0
    assert {"texture", "forward"} <= set(sm["gpu_ms"])
    assert (out / "frame0000_eye1.png").is_file() and (out / "frame0005_eye0.exr").is_file()
    assert "frame ms" in capsys.readouterr().out


@pytest.mark.gpu
def test_force_replaces_only_vrneurals_own_output(capsys, tmp_path):
    tiny = ["--profile", "tiny", "--frames", "2", "--quiet", "--force"]
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep")
    msg = _err(capsys, [*tiny, "--out", str(mine)])
    assert "not a vrneural output directory" in msg and (mine / "notes.txt").read_text() == "keep"
    a_file = tmp_path / "file.txt"
    a_file.write_text("keep")
    assert "is not a directory" in _err(capsys, [*tiny, "--out", str(a_file)])
    assert a_file.read_text() == "keep"
    out = tmp_path / "o"
    assert main(["run", *tiny, "--out", str(out)]) == 0
    (out / "frame0000_eye0.png").unlink()
    (out / "stale.txt").write_text("from an old run")
    assert main(["run", *tiny, "--out", str(out)]) == 0  # our own output: replaced
    assert (out / "frame0000_eye0.png").is_file() and not (out / "stale.txt").exists()


@pytest.mark.gpu
def test_a_run_that_fails_in_setup_writes_nothing(capsys, tmp_path):
    from vrneural.formats.vrnm import write_vrnm
    from vrneural.material import random_material

    write_vrnm(tmp_path / "big.vrnm", random_material(0, arch="single", width=160))
    scene = tmp_path / "scene.toml"
    text = SCENE.format(scale=1).replace('procedural = "lambertian"', 'pack = "big.vrnm"')
    scene.write_text(text)
    out = tmp_path / "o"
    msg = _err(capsys, [str(scene), "--profile", "tiny", "--frames", "2", "--out", str(out)])
    assert "objects[0] (" in msg and "big.vrnm" in msg and "MACs/texel" in msg
    assert not out.exists()  # so the retry the message suggests needs no --force


@pytest.mark.gpu
def test_profile_lights_are_capped_at_the_scenes(capsys, tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE.format(scale=1))  # one light; the tiny profile has more
    out = tmp_path / "o"
    argv = [str(scene), "--profile", "tiny", "--frames", "2", "--quiet", "--out", str(out)]
    assert main(["run", *argv]) == 0
    assert json.loads((out / "summary.json").read_text())["resolved"]["n_lights"] == 1
    msg = _err(capsys, [str(scene), "--lights", "2", "--out", str(tmp_path / "o2")])
    assert "--lights = 2 but the scene has 1 lights" in msg


@pytest.mark.gpu
def test_ctrl_c_keeps_the_frames_rendered_so_far(capsys, tmp_path, monkeypatch):
    from vrneural.runtime import renderer

    class Interrupted(renderer.Renderer):
        def frame(self, f):
            if f == 3:
                raise KeyboardInterrupt
            return super().frame(f)

    monkeypatch.setattr(renderer, "Renderer", Interrupted)
    out = tmp_path / "o"
    argv = ["run", "--profile", "tiny", "--frames", "8", "--save-frames", "all", "--quiet"]
    assert main([*argv, "--out", str(out)]) == 130
    err = capsys.readouterr().err
    assert "interrupted after 3 of 8 frames" in err and "--force" in err
    sm = json.loads((out / "summary.json").read_text())
    assert sm["interrupted"] is True and sm["frames"] == 3
    assert (out / "stereo.mp4").stat().st_size > 0
    assert sorted(p.name for p in out.glob("*.png")) == [
        f"frame{f:04d}_eye{e}.png" for f in range(3) for e in (0, 1)
    ]
    # the interrupted output is vrneural's own: --force replaces it
    monkeypatch.undo()
    assert main([*argv, "--frames", "2", "--force", "--out", str(out)]) == 0
    assert json.loads((out / "summary.json").read_text())["interrupted"] is False
