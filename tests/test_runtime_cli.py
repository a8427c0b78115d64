"""`vrneural run` user errors: one line, exit code 2; and a tiny end-to-end run."""

import json
from pathlib import Path

import numpy as np
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
    msg = _err(capsys, [str(tmp_path), "--out", str(tmp_path / "o")])
    assert "is a directory, expected a scene file" in msg


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
        (["--target", "display", "--mode", "screen"], "--target display needs --mode texture"),
    ],
)
def test_bad_flags(capsys, tmp_path, argv, needle):
    msg = _err(capsys, ["--profile", "tiny", "--out", str(tmp_path / "o"), *argv])
    assert needle in msg and not (tmp_path / "o").exists()


def test_existing_output_needs_force(capsys, tmp_path):
    from vrneural.outputs import OutputDir, mark_output

    o = tmp_path / "o"
    with OutputDir(o, "run") as out:
        out.open()
        (o / "summary.json").write_text("{}")
    msg = _err(capsys, ["--profile", "tiny", "--out", str(o)])
    assert "--force" in msg
    # a bench's output is not a run's: --force does not help
    mark_output(o, "bench quality")
    msg = _err(capsys, ["--profile", "tiny", "--force", "--out", str(o)])
    assert "holds the output of `vrneural bench quality`, not of `vrneural run`" in msg
    assert (o / "summary.json").read_text() == "{}"


@pytest.mark.gpu
def test_tiny_run_writes_summary_and_frames(capsys, tmp_path):
    out = tmp_path / "o"
    rc = main(["run", "--profile", "tiny", "--frames", "6", "--out", str(out), "--quiet"])
    assert rc == 0
    sm = json.loads((out / "summary.json").read_text())
    assert sm["frames"] == 6 and sm["resolved"]["reuse"] == 4
    assert len(sm["per_frame"]["blocks_shaded"]) == 6
    assert sm["frame_wall_ms"]["p99"] >= sm["frame_wall_ms"]["median"] > 0
    # every pass is timed by timestamps or named as not covered by this adapter's (lavapipe:
    # the compute passes), never both
    assert {"texture", "forward"} == set(sm["gpu_ms"]) | set(sm["gpu_untimed"])
    assert not set(sm["gpu_ms"]) & set(sm["gpu_untimed"])
    assert sm["frames_in_flight"] == 2 and sm["host_cpu_ms"]["median"] > 0
    assert (out / "frame0000_eye1.png").is_file() and (out / "frame0005_eye0.exr").is_file()
    assert "frame ms" in capsys.readouterr().out


@pytest.mark.gpu
def test_display_target_run_writes_png_frames_and_video_without_exr(capsys, tmp_path):
    """`--target display`: the eyes drawn into 8-bit sRGB targets; the saved PNGs within one
    level of the HDR run's (its tonemap of the same frames), no EXR, a video, and the summary
    says which target it used."""
    import imageio.v3 as iio

    outs = {}
    for target in ("hdr", "display"):
        outs[target] = out = tmp_path / target
        argv = ["--profile", "tiny", "--frames", "3", "--target", target, "--out", str(out)]
        assert main(["run", *argv, "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert printed.count("(+ .exr)") == 1  # the HDR run's frames line, not the display run's
    assert printed.count("target=display") == 1  # the display run's run line
    disp = outs["display"]
    assert not list(disp.glob("*.exr")) and (disp / "stereo.mp4").is_file()
    assert json.loads((disp / "summary.json").read_text())["config"]["target"] == "display"
    for name in ("frame0000_eye0.png", "frame0002_eye1.png"):
        a, b = (iio.imread(outs[t] / name).astype(int) for t in ("hdr", "display"))
        assert a.shape == b.shape and np.abs(a - b).max() <= 1 and b.max() > 50


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
    (out / "notes.md").write_text("added by the user after the run")
    msg = _err(capsys, [*tiny, "--out", str(out)])  # --force never deletes what it did not write
    assert "1 file(s) vrneural did not write there (notes.md)" in msg
    assert (out / "notes.md").is_file() and (out / "summary.json").is_file()
    (out / "notes.md").unlink()
    assert main(["run", *tiny, "--out", str(out)]) == 0  # our own output: replaced
    assert (out / "frame0000_eye0.png").is_file()


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
    assert "--lights = 2 but the scene has 1 light" in msg


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
    assert err.strip().startswith("vrneural run: interrupted after") and err.count("\n") == 1, err
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


@pytest.mark.gpu
@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_a_real_ctrl_c_stops_between_frames_and_keeps_them_whole(
    capsys, tmp_path, monkeypatch, sig
):
    """SIGINT (what a terminal's Ctrl-C sends) or SIGTERM (kill, timeout, batch schedulers)
    during frame 3: that frame is finished, and the summary, the video and the default
    --save-frames first,last agree on 4 frames."""
    import os
    import signal

    import imageio.v2 as iio2

    from vrneural.runtime import renderer

    class Interrupted(renderer.Renderer):
        def frame(self, f):
            if f == 3:
                os.kill(os.getpid(), getattr(signal, sig))
            return super().frame(f)

    monkeypatch.setattr(renderer, "Renderer", Interrupted)
    out = tmp_path / "o"
    assert main(["run", "--profile", "tiny", "--frames", "8", "--quiet", "--out", str(out)]) == 130
    err = capsys.readouterr().err
    assert "interrupted after 4 of 8 frames" in err and "stereo.mp4 (4 frames)" in err
    assert json.loads((out / "summary.json").read_text())["frames"] == 4
    with iio2.get_reader(str(out / "stereo.mp4")) as rd:
        assert rd.count_frames() == 4
        # the default --video-scale keeps small eyes whole (96 px: scale 1, not 4's 24 px)
        assert rd.get_meta_data()["size"] == (192, 96)
    assert sorted(p.name for p in out.glob("*.png")) == [
        f"frame{f:04d}_eye{e}.png" for f in (0, 3) for e in (0, 1)
    ]


@pytest.mark.gpu
def test_two_runs_in_the_same_second_get_two_directories(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("time.strftime", lambda fmt, *a: "out/run-20260101-000000")
    argv = ["run", "--profile", "tiny", "--frames", "1", "--quiet", "--no-video"]
    assert main(argv) == 0 and main(argv) == 0
    runs = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert runs == ["run-20260101-000000", "run-20260101-000000-2"]
    assert all((tmp_path / "out" / r / "summary.json").is_file() for r in runs)


def test_a_run_that_fails_at_setup_leaves_no_directory(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "--profile", "tiny", "--eyes", "3", "--quiet"]) == 2
    assert "--eyes" in capsys.readouterr().err
    assert list(tmp_path.glob("out/run-*")) == []
    assert not (tmp_path / "out").exists()  # nor the out/ it made for it
    (tmp_path / "out").mkdir()  # one that was there before stays
    assert main(["run", "--profile", "tiny", "--eyes", "3", "--quiet"]) == 2
    assert (tmp_path / "out").is_dir() and not list((tmp_path / "out").iterdir())
    assert main(["run", "--out", "", "--quiet"]) == 2
    assert "--out is empty" in capsys.readouterr().err


def _scene(tmp_path, text: str, name: str = "s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def _two_meshes(path):
    """A glTF file holding two meshes, "box" (12 triangles) and "ball" (80)."""
    import trimesh

    trimesh.Scene({"box": trimesh.creation.box(), "ball": trimesh.creation.icosphere(1)}).export(
        path
    )


OBJ = """
[[objects]]
mesh = "{mesh}"
{extra}
[objects.material]
{mat}
[[lights]]
{light}
"""


@pytest.mark.parametrize(
    "fields, needle",
    [
        (
            {"extra": "position = [0, 1e300, 0]"},
            "s.toml: objects[0].position = [0, 1e+300, 0] is out",
        ),
        ({"extra": "scale = 1e300"}, "s.toml: objects[0].scale = 1e+300 is out of range"),
        # 1e-100 was a singular-matrix traceback (0 in float32)
        ({"extra": "scale = 1e-100"}, "objects[0].scale = 1e-100 is out of range; allowed [1e-09"),
        (
            {"light": 'motion = "circle"\nradius = 1e9'},
            "s.toml: lights[0].radius = 1000000000.0 is out of range; allowed [0, 10000000]",
        ),
        (
            {"extra": "texture_res = 6"},
            "objects[0].texture_res = 6 is out of range; allowed [8, 8192]",
        ),
        ({"extra": "min_texture_res = 130000"}, "objects[0].min_texture_res = 130000 is out"),
        ({"extra": "min_texture_res = 255"}, "objects[0].min_texture_res = 255 must be even"),
        ({"mat": 'pack = "leather.vrnm"\nprocedural = "random"'}, "procedural and pack are both"),
        ({"mat": 'pack = "leather.vrnm"\nseed = 3'}, "material.seed only applies to procedural"),
        (  # the seed options' range (it had no upper bound)
            {"mat": 'procedural = "random"\nseed = 4294967296'},
            "material.seed = 4294967296 is out of range; allowed [0, 4294967295]",
        ),
        (
            {"mat": 'procedural = "random"\nseed = 3\nalbedo = [1, 1, 1]'},
            'material.albedo only applies to procedural = "lambertian"',
        ),
        ({"mat": "scale = 2.0"}, 'objects[0].material needs pack = "X.vrnm"'),
        (
            {"extra": "texture_res = 64\nmin_texture_res = 256"},
            "objects[0].min_texture_res = 256 is above texture_res = 64",
        ),
        ({"mat": 'pack = "nope.vrnm"'}, "material.pack = 'nope.vrnm': file not found"),
        ({"mat": 'reference = "nope.vrnm"'}, "material.reference = 'nope.vrnm': file not found"),
        ({"light": "colour = [1, 1, 1]\ncolor = [1, 0, 0]"}, "lights[0].color and colour are both"),
        ({"mesh": "two.glb"}, "objects[0].mesh = 'two.glb' holds 2 meshes"),
        ({"mesh": "two.glb:teapot"}, "two.glb has no mesh 'teapot'"),
        ({"extra": "crease_angle = 181"}, "objects[0].crease_angle = 181 is out of range"),
        (
            {"light": "radius = 3\nperiod = 2"},
            'lights[0].radius is given but the light does not move; add motion = "circle" or '
            "drop radius, period",
        ),
        (
            {"mat": 'kind = "plain"', "extra": "texture_res = 64"},
            "objects[0].texture_res is set on a plain object; only neural ones have a radiance",
        ),
    ],
)
def test_bad_scene_fields(capsys, tmp_path, fields, needle):
    _two_meshes(tmp_path / "two.glb")
    f = {"mesh": "plane", "extra": "", "mat": 'procedural = "random"'} | fields
    f["light"] = "position = [0, 1, 0]\n" + f.get("light", "")
    msg = _err(
        capsys,
        [_scene(tmp_path, OBJ.format(**f)), "--profile", "tiny", "--out", str(tmp_path / "o")],
    )
    assert needle in msg and not (tmp_path / "o").exists()


def test_scene_profile_is_checked_as_a_scene_field_even_under_a_cli_profile(capsys, tmp_path):
    text = 'profile = "vive"\n' + OBJ.format(
        mesh="plane", extra="", mat="", light="position = [0, 1, 0]"
    )
    for extra in ([], ["--profile", "tiny"]):
        msg = _err(capsys, [_scene(tmp_path, text), *extra, "--out", str(tmp_path / "o")])
        assert "s.toml: profile = 'vive' is not allowed; choose one of: quest3" in msg


def test_scene_mesh_files_by_name_or_index_and_bundled_packs(tmp_path):
    from vrneural.runtime.assets import get_mesh
    from vrneural.runtime.scene import load_scene

    _two_meshes(tmp_path / "two.glb")
    by_name = {n: len(get_mesh(f"two.glb:{n}", tmp_path).faces) for n in ("box", "ball")}
    assert by_name == {"box": 12, "ball": 80}
    assert len(get_mesh("two.glb:1", tmp_path).faces) in by_name.values()
    mat = 'pack = "leather.vrnm"\nreference = "leather.teacher.vrnm"'
    sc = load_scene(
        _scene(
            tmp_path,
            OBJ.format(
                mesh="two.glb:box",
                extra="min_texture_res = 64",
                mat=mat,
                light="position = [0, 1, 0]",
            ),
        )
    )
    o = sc.objects[0]
    assert o.min_texture_res == 64 and o.texture_res is None and o.name == "two:box"
    assert o.material.source.endswith("vrneural/data/materials/leather.vrnm")
    assert o.material.reference.arch == "single" and sc.src.endswith("/s.toml")
    assert o.crease_angle is None


def test_scene_crease_angle_reaches_the_mesh(tmp_path):
    """crease_angle = 0 on a built-in sphere: flat facets, so more (split) vertices."""
    from vrneural.runtime.assets import get_mesh
    from vrneural.runtime.scene import load_scene

    text = OBJ.format(
        mesh="sphere", extra="crease_angle = 0", mat='kind = "plain"', light="position = [0, 1, 0]"
    )
    o = load_scene(_scene(tmp_path, text)).objects[0]
    assert o.crease_angle == 0.0
    flat, smooth = get_mesh("sphere", crease_deg=o.crease_angle), get_mesh("sphere")
    assert len(flat.positions) > len(smooth.positions) and len(flat.faces) == len(smooth.faces)


@pytest.mark.gpu
@pytest.mark.gpu
def test_video_scale_without_a_video_is_a_warning(capsys, tmp_path):
    argv = ["run", "--profile", "tiny", "--frames", "1", "--quiet", "--no-video"]
    assert main([*argv, "--video-scale", "-5", "--out", str(tmp_path / "o")]) == 0
    assert "--video-scale only applies to the video, and --no-video writes none" in (
        capsys.readouterr().err
    )


def test_video_scale_that_leaves_no_pixels_is_refused_before_rendering(capsys, tmp_path):
    msg = _err(capsys, ["--profile", "tiny", "--video-scale", "1000", "--out", str(tmp_path / "o")])
    assert "--video-scale = 1000 is out of range; allowed [1, " in msg
    assert not (tmp_path / "o").exists()


@pytest.mark.gpu
def test_reference_mode_needs_a_teacher_for_a_pack(capsys, tmp_path):
    text = OBJ.format(
        mesh="sphere", extra="", mat='pack = "leather.vrnm"', light="position = [0, 1, 0]"
    )
    msg = _err(capsys, [_scene(tmp_path, text), "--profile", "tiny", "--mode", "reference",
                        "--frames", "1", "--out", str(tmp_path / "o")])  # fmt: skip
    assert "objects[0] (sphere): --mode reference needs a teacher for leather.vrnm" in msg
    assert not (tmp_path / "o").exists()


@pytest.mark.gpu
def test_triangles_without_texels_are_reported_not_hidden(capsys, tmp_path):
    text = OBJ.format(
        mesh="sphere",
        extra="texture_res = 64",
        mat='procedural = "random"',
        light="position = [0, 1, 0]",
    )
    out = tmp_path / "o"
    argv = ["run", _scene(tmp_path, text), "--profile", "tiny", "--frames", "1", "--no-video"]
    assert main([*argv, "--quiet", "--out", str(out)]) == 0
    cap = capsys.readouterr()
    err = cap.err
    assert f"warning: {tmp_path}/s.toml: objects[0] (sphere): " in err
    assert "own no texel at 64^2" in err
    assert "objects   sphere 64^2 " in cap.out and "tris w/o texel" in cap.out
    sm = json.loads((out / "summary.json").read_text())
    obj = sm["scene"]["objects"][0]
    assert obj["texture_res"] == 64 and obj["triangles_without_texels"] > 0.5 * obj["triangles"]
    assert len(sm["warnings"]) == 1
    # --texture-res on the command line beats the object's texture_res, and says so; screen
    # mode shades pixels, so no word about texels there
    assert main([*argv, "--quiet", "--out", str(tmp_path / "c"), "--texture-res", "128"]) == 0
    cap = capsys.readouterr()
    assert "objects[0] (sphere): --texture-res 128 overrides its texture_res = 64" in cap.err
    assert "objects   sphere 128^2 " in cap.out
    assert main([*argv, "--quiet", "--out", str(tmp_path / "s"), "--mode", "screen"]) == 0
    cap = capsys.readouterr()
    assert "own no texel" not in cap.err and "objects   " not in cap.out  # nor atlas texels


@pytest.mark.gpu
def test_builtin_scene_says_when_lights_are_generated(capsys, tmp_path):
    argv = ["run", "--profile", "tiny", "--frames", "1", "--no-video", "--quiet", "--out"]
    assert main([*argv, str(tmp_path / "o"), "--lights", "5"]) == 0
    assert "--lights 5: the built-in scene has 3 lights; 2 generated lights added" in (
        capsys.readouterr().err
    )
    assert main([*argv, str(tmp_path / "p"), "--lights", "3"]) == 0
    assert "generated" not in capsys.readouterr().err
    # the built-in scene defines its 3 lights whatever is shaded (tiny: the first 2; --lights
    # 0: none), and the work percentiles leave frame 0's full update out as the times do
    for k, lights in (("q", []), ("r", ["--lights", "0"])):
        frames = ["--frames", "6", "--reuse", "4", "--schedule", "burst"]
        assert main([*argv, str(tmp_path / k), *lights, *frames]) == 0
        sm = json.loads((tmp_path / k / "summary.json").read_text())
        assert sm["scene"]["scene_lights"] == 3
        assert sm["scene"]["lights"] == (2 if not lights else 0)
    sm = json.loads((tmp_path / "q" / "summary.json").read_text())
    blocks = sm["per_frame"]["blocks_shaded"]  # burst, N = 4: frames 0 and 5 update
    assert blocks[0] > 0 and blocks[5] > 0 and not any(blocks[1:5])
    assert sm["blocks_shaded_per_frame"]["mean"] == pytest.approx(blocks[5] / 5)  # frames 1-5


@pytest.mark.gpu
def test_pack_shows_your_own_material_on_the_builtin_scene(capsys, tmp_path):
    """`run --pack student.vrnm`: the user's pack on the demo's three objects; a sibling
    teacher.vrnm is the --mode reference; a checkpoint or a directory is a one-line error."""
    from vrneural.formats.vrnm import write_vrnm
    from vrneural.material import random_material

    write_vrnm(tmp_path / "student.vrnm", random_material(3))
    out = tmp_path / "o"
    argv = ["--profile", "tiny", "--frames", "1", "--quiet", "--no-video"]
    assert main(["run", *argv, "--pack", str(tmp_path / "student.vrnm"), "--out", str(out)]) == 0
    sm = json.loads((out / "summary.json").read_text())
    sources = [o["source"] for o in sm["scene"]["objects"] if o["material"] == "neural"]
    assert len(sources) == 3 and all(s.endswith("student.vrnm") for s in sources), sources
    names = {o["name"] for o in sm["scene"]["objects"] if o["material"] == "neural"}
    assert names == {"student sphere", "student cloth", "student torus"}  # not "leather sphere"
    (tmp_path / "student.pt").write_bytes(b"PK\x03\x04" + bytes(60))
    msg = _err(
        capsys, [*argv, "--pack", str(tmp_path / "student.pt"), "--out", str(tmp_path / "x")]
    )
    assert "PyTorch checkpoint" in msg and "vrneural export" in msg
    msg = _err(capsys, [*argv, "--pack", str(tmp_path), "--out", str(tmp_path / "x")])
    assert "a directory, not a pack file" in msg
    # a teacher pack is its own per-pixel reference
    teacher = random_material(4, arch="single", width=64)
    teacher.meta["method"] = "teacher"
    (tmp_path / "t").mkdir()
    write_vrnm(tmp_path / "t" / "teacher.vrnm", teacher)
    ref = [*argv, "--pack", str(tmp_path / "t" / "teacher.vrnm"), "--mode", "reference"]
    assert main(["run", *ref, "--out", str(tmp_path / "r")]) == 0
    scene = _scene(tmp_path, SCENE.format(scale=1))
    msg = _err(capsys, [scene, *argv, "--pack", str(tmp_path / "student.vrnm")])
    assert "with a SCENE file" in msg
    assert not (tmp_path / "x").exists()


@pytest.mark.gpu
def test_screen_mode_summary_does_not_claim_reuse_or_a_texture(capsys, tmp_path):
    argv = ["run", "--profile", "tiny", "--frames", "2", "--quiet", "--no-video", "--mode"]
    assert main([*argv, "screen", "--out", str(tmp_path / "s")]) == 0
    text = capsys.readouterr().out
    assert "mode=screen" in text and "(per pixel, every frame)" in text
    assert "reuse=" not in text and "texture=" not in text and "updates in" not in text
    assert "per frame pixels shaded" in text and "blocks shaded" not in text
    sm = json.loads((tmp_path / "s" / "summary.json").read_text())
    assert "blocks_shaded" not in sm["per_frame"] and "blocks_shaded_per_frame" not in sm
    assert sm["pixels_shaded_per_frame"]["median"] > 0 and "pixels_backfacing" in sm["per_frame"]
    assert "--reuse" not in capsys.readouterr().err  # not given: nothing to warn about
    assert main([*argv, "texture", "--out", str(tmp_path / "t")]) == 0
    text = capsys.readouterr().out
    assert "reuse=4" in text and "texture=" in text and "updates in" in text
    # texture space's knobs given with screen mode are said to do nothing; one frame's
    # timings are said to include shader compilation
    one = ["run", "--profile", "tiny", "--frames", "1", "--quiet", "--no-video", "--mode"]
    assert (
        main([*one, "screen", "--reuse", "2", "--schedule", "burst", "--out", str(tmp_path / "u")])
        == 0
    )
    out, err = capsys.readouterr()
    assert "warning: --reuse and --schedule only apply to --mode texture" in err
    assert "one frame: includes shader compilation" in out
    sm = json.loads((tmp_path / "u" / "summary.json").read_text())
    assert sm["note"].startswith("one frame:")


def test_lights_written_as_one_table_are_named_as_such(tmp_path):
    from vrneural.errors import VrnError
    from vrneural.runtime.scene import load_scene

    text = OBJ.format(mesh="plane", extra="", mat='procedural = "random"', light="").replace(
        "[[lights]]", "[lights]\nposition = [0, 1, 0]"
    )
    with pytest.raises(VrnError, match=r"lights must be an array of tables \(\[\[lights\]\]\)"):
        load_scene(_scene(tmp_path, text))


@pytest.mark.gpu
def test_what_a_run_drops_or_cannot_see_is_a_warning_kept_in_the_summary(capsys, tmp_path):
    """Lights beyond the profile's, a degenerate triangle skipped on loading and eyes inside
    the only neural object (all black) are each a warning on stderr and in summary.json."""
    (tmp_path / "degen.obj").write_text(
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 3 4\nf 1 2 5\n"
    )
    lights = "".join(f"[[lights]]\nposition = [1, 2, {k}]\n" for k in range(4))
    text = (
        'profile = "tiny"\n'  # the warning names the profile in force, here the scene's
        '[[objects]]\nmesh = "sphere"\nscale = 40\n[objects.material]\npack = "leather.vrnm"\n'
        '[[objects]]\nmesh = "degen.obj"\n[objects.material]\nkind = "plain"\n' + lights
    )
    out = tmp_path / "o"
    argv = ["run", _scene(tmp_path, text), "--frames", "1", "--no-video"]
    assert main([*argv, "--quiet", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    sm = json.loads((out / "summary.json").read_text())
    assert sm["scene"]["lights"] == 2 and sm["scene"]["scene_lights"] == 4
    warned = " | ".join(sm["warnings"])
    assert "the scene has 4 lights and the tiny profile shades the first 2" in warned
    assert "--lights 4 shades them all" in warned
    assert "degen.obj: skipped 1 degenerate triangle of 3" in warned
    assert "no texel or pixel of a neural object faced an eye in any frame" in warned
    assert all(f"warning: {w}" in err for w in sm["warnings"])
    dark = OBJ.format(mesh="plane", extra="", mat='procedural = "random"', light="")
    dark = dark.replace("[[lights]]\n", "")  # a scene without lights renders black: said
    argv = ["run", _scene(tmp_path, dark, "dark.toml"), "--profile", "tiny", "--frames", "1"]
    assert main([*argv, "--no-video", "--quiet", "--out", str(tmp_path / "d")]) == 0
    sm = json.loads((tmp_path / "d" / "summary.json").read_text())
    dark = "dark.toml: the scene has no [[lights]]: neural objects are black"
    assert any(w.endswith(dark) for w in sm["warnings"])
    argv = ["run", "--profile", "tiny", "--lights", "0", "--frames", "1", "--no-video"]
    assert main([*argv, "--quiet", "--out", str(tmp_path / "z")]) == 0  # asked for: said too
    sm = json.loads((tmp_path / "z" / "summary.json").read_text())
    assert any(w.startswith("--lights 0: none of the scene's ") for w in sm["warnings"])


@pytest.mark.gpu
def test_pack_finds_its_teacher_by_the_recorded_checkpoint_then_by_name(capsys, tmp_path):
    from vrneural.formats.vrnm import write_vrnm
    from vrneural.material import random_material

    student = random_material(3)
    student.meta["method"] = "student"
    student.meta["provenance"] = {"config": {"teacher": str(tmp_path / "far" / "big.pt")}}
    teacher = random_material(4, arch="single", width=16)
    teacher.meta["method"] = "teacher"
    d = tmp_path / "p"
    d.mkdir()
    write_vrnm(d / "mat.vrnm", student)
    argv = ["--profile", "tiny", "--frames", "1", "--quiet", "--no-video", "--mode", "reference"]
    argv += ["--pack", str(d / "mat.vrnm")]
    msg = _err(capsys, [*argv, "--out", str(tmp_path / "x")])
    assert "pass --reference TEACHER.vrnm (looked for" in msg and "scene" not in msg.split(":")[-1]
    assert "big.vrnm" in msg and "mat.teacher.vrnm" in msg and "teacher.vrnm" in msg
    write_vrnm(d / "mat.teacher.vrnm", teacher)  # the bundled packs' naming
    assert main(["run", *argv, "--out", str(tmp_path / "a")]) == 0
    sm = json.loads((tmp_path / "a" / "summary.json").read_text())
    refs = {o["reference"] for o in sm["scene"]["objects"] if o["material"] == "neural"}
    assert refs == {str((d / "mat.teacher.vrnm").resolve())}
    assert sm["resolved"]["precision"] == "f32"  # the teacher always runs in f32
    msg = _err(capsys, [*argv, "--precision", "f16", "--out", str(tmp_path / "x")])
    assert "--precision f16 does not apply to --mode reference" in msg
    (tmp_path / "far").mkdir()
    write_vrnm(tmp_path / "far" / "big.vrnm", teacher)  # the teacher the pack records wins
    assert main(["run", *argv, "--out", str(tmp_path / "b")]) == 0
    sm = json.loads((tmp_path / "b" / "summary.json").read_text())
    refs = {o["reference"] for o in sm["scene"]["objects"] if o["material"] == "neural"}
    assert refs == {str((tmp_path / "far" / "big.vrnm").resolve())}
    assert (
        main(["run", *argv, "--reference", str(d / "mat.vrnm"), "--out", str(tmp_path / "s")]) == 0
    )
    assert "the reference is a student pack, not a teacher" in capsys.readouterr().err
    forced = ["--reference", str(d / "mat.teacher.vrnm")]  # --reference is what shades
    assert main(["run", *argv, *forced, "--out", str(tmp_path / "c")]) == 0
    sm = json.loads((tmp_path / "c" / "summary.json").read_text())
    refs = {o["reference"] for o in sm["scene"]["objects"] if o["material"] == "neural"}
    assert refs == {str((d / "mat.teacher.vrnm").resolve())}


@pytest.mark.gpu
def test_teacher_pack_outside_reference_mode_says_what_to_do(capsys, tmp_path):
    import vrneural

    argv = ["--profile", "tiny", "--frames", "1", "--quiet", "--no-video"]
    teacher = str(Path(vrneural.__file__).parent / "data" / "materials" / "wood.teacher.vrnm")
    msg = _err(capsys, [*argv, "--pack", teacher, "--out", str(tmp_path / "o")])
    assert "built-in scene: objects[0] (wood.teacher sphere" in msg
    assert "is a teacher pack (35328 MACs/texel" in msg and "--mode reference" in msg
    assert not (tmp_path / "o").exists()


def test_scene_file_with_a_utf8_bom_loads(tmp_path):
    """Windows editors save UTF-8 with a byte-order mark; TOML parsers reject it at 1:1."""
    from vrneural.runtime.scene import load_scene

    text = OBJ.format(
        mesh="plane", extra="", mat='procedural = "random"', light="position = [0, 1, 0]"
    )
    p = tmp_path / "bom.toml"
    p.write_bytes(b"\xef\xbb\xbf" + text.encode())
    sc = load_scene(p)
    assert sc.name == "bom" and len(sc.objects) == 1 and len(sc.lights) == 1


def test_pose_log_times_count_from_its_first_row_and_separators_are_named(tmp_path):
    """A log of absolute timestamps (1000 s, 1001 s) plays from its start: half a second in,
    the head is half way. A ';'-separated log says commas are expected."""
    import numpy as np

    from vrneural.errors import VrnError
    from vrneural.runtime.camera import PoseLogPath

    p = tmp_path / "abs.csv"
    p.write_text("t,x,y,z,qx,qy,qz,qw\n1000,0,1,2,0,0,0,1\n1001,1.0,1,2,0,0,0,1\n")
    pos, _ = PoseLogPath(p).pose(0.5)
    np.testing.assert_allclose(pos, [0.5, 1, 2])
    semi = tmp_path / "semi.csv"
    semi.write_text("t;x;y;z;qx;qy;qz;qw\n0;0;1;2;0;0;0;1\n")
    with pytest.raises(VrnError, match=r"semi.csv:2: .*columns are separated by commas, not ';'"):
        PoseLogPath(semi)
    semi.write_text("0;0;1;2;0;0;0;1\n")
    with pytest.raises(VrnError, match=r"no rows of 8 numbers .*not ';'"):
        PoseLogPath(semi)
    # a bad row is named by its line (they were "the log has ..."), and a quaternion must be
    # a unit one (0 0 0 2 was taken)
    head = "t,x,y,z,qx,qy,qz,qw\n0,0,1,2,0,0,0,1\n"
    for row, msg in (
        ("1,0,nan,2,0,0,0,1", "NaN/Inf value in the row"),
        ("0,0,1,2,0,0,0,1", "time is not after the previous row's"),
        ("1,0,1,2,0,0,0,0", r"zero quaternion \(qx qy qz qw = 0 0 0 0\)"),
        ("1,0,1,2,0,0,0,2", r"quaternion of length 2; a unit one expected \(\+-0.01\)"),
    ):
        p.write_text(head + row + "\n")
        with pytest.raises(VrnError, match=rf"abs.csv:3: {msg}"):
            PoseLogPath(p)
    p.write_text(head + "1,0,1,2,0,0,0.0001,1.0004\n")  # few decimals: within the tolerance
    PoseLogPath(p)


def test_save_frames_parsing():
    from vrneural.errors import VrnError
    from vrneural.runtime.run import selected_frames

    assert selected_frames("first,last", 5) == [0, 4] and selected_frames("none", 5) == []
    assert selected_frames("all", 3) == [0, 1, 2] and selected_frames("2, 0", 5) == [0, 2]
    with pytest.raises(VrnError, match="--save-frames is empty; pass none"):
        selected_frames(" ", 5)
    with pytest.raises(VrnError, match=r"frame 5 is out of range; allowed \[0, 4\]"):
        selected_frames("5", 5)


def test_object_names_are_unique(tmp_path):
    """Default names (the mesh's) are numbered when a mesh repeats; a repeated given name is
    an error (messages and summary.json name objects by it)."""
    from vrneural.errors import VrnError
    from vrneural.runtime.scene import load_scene

    one = OBJ.format(mesh="sphere", extra="", mat='procedural = "random"', light="")
    text = (one + one).replace("[[lights]]\n", "") + "[[lights]]\nposition = [0, 1, 0]\n"
    sc = load_scene(_scene(tmp_path, text))
    assert [o.name for o in sc.objects] == ["sphere", "sphere 2"]
    # a part of a mesh file is named with its part (both were "room")
    parts = text.replace('"sphere"', '"room.obj:0"', 1).replace('"sphere"', '"room.obj:1"')
    sc = load_scene(_scene(tmp_path, parts, "p.toml"))
    assert [o.name for o in sc.objects] == ["room:0", "room:1"]
    named = text.replace('mesh = "sphere"', 'mesh = "sphere"\nname = "ball"')
    with pytest.raises(VrnError, match=r"objects\[1\]\.name = 'ball' is already another object's"):
        load_scene(_scene(tmp_path, named, "n.toml"))


def test_exr_writes_under_a_path_that_is_not_utf8(tmp_path):
    """OpenImageIO takes UTF-8 file names only; a folder named with a Latin-1 byte (a valid
    POSIX name) still gets its EXR frames, whole."""
    import os

    import numpy as np

    from vrneural.runtime.output import write_exr

    d = tmp_path / os.fsdecode(b"r\xe9sultats")
    d.mkdir()
    out = write_exr(d / "frame0000_eye0.exr", np.full((4, 6, 3), 0.5, np.float32))
    data = out.read_bytes()
    assert data[:4] == b"\x76\x2f\x31\x01" and len(data) > 100  # the OpenEXR magic
    assert [p.name for p in d.iterdir()] == ["frame0000_eye0.exr"]  # no temporary left


@pytest.mark.gpu
def test_a_write_error_mid_run_leaves_no_partial_video(capsys, tmp_path, monkeypatch):
    """A frame that cannot be written (a full disk): one line, exit 2, the partial video is
    removed and the output sealed, so a later --force can replace it."""
    from vrneural.errors import VrnError
    from vrneural.runtime import run as run_mod

    real = run_mod.write_png

    def full(path, img):
        if "frame0002" in str(path):
            raise VrnError(f"{path}: cannot write (No space left on device)")
        return real(path, img)

    monkeypatch.setattr(run_mod, "write_png", full)
    out = tmp_path / "o"
    argv = ["run", "--profile", "tiny", "--frames", "4", "--save-frames", "all", "--quiet"]
    msg = _err(capsys, [*argv[1:], "--out", str(out)])
    assert "frame0002_eye0.png: cannot write (No space left on device)" in msg
    assert not list(out.glob(".*.tmp.mp4"))
    monkeypatch.setattr(run_mod, "write_png", real)
    assert main([*argv, "--out", str(out), "--force"]) == 0


def test_run_line_names_the_objects_texture_sides():
    """The summary's run line gives the textures the objects used, not only the profile's."""
    from vrneural.runtime.run import _texture_text

    def sm(*sides):
        objs = [{"name": f"o{i}", "texture_res": t} for i, t in enumerate(sides)]
        return {"scene": {"objects": [*objs, {"name": "floor"}]}}

    assert _texture_text(128, sm(128, 128)) == "128^2"
    assert _texture_text(128, sm()) == "128^2"
    assert _texture_text(128, sm(1024)) == "1024^2 (per object; profile 128^2)"
    assert _texture_text(128, sm(256, 128, 1024)) == "128^2-1024^2 (per object; profile 128^2)"
    # a scene's min_texture_res over --texture-res 96: the 96 is the command line's
    assert _texture_text(96, sm(256), True) == "256^2 (per object; --texture-res 96^2)"


def test_a_pack_or_mesh_given_as_the_scene_says_where_it_goes(tmp_path):
    """`vrneural run leather.vrnm` said only "not a text file"."""
    from vrneural.errors import VrnError
    from vrneural.runtime.scene import load_scene

    for name, hint in (("m.vrnm", "goes to --pack"), ("m.glb", r"into a scene file's \[\[objects")):
        (tmp_path / name).write_bytes(b"\xff\xfe\x00binary")
        with pytest.raises(
            VrnError, match=rf"m\.\w+: not a text file \(a scene is TOML\);.*{hint}"
        ):
            load_scene(tmp_path / name)
    text = '[head]\npath = "spiral"\n' + OBJ.format(
        mesh="plane", extra="", mat="", light="position = [0, 1, 0]"
    )
    with pytest.raises(VrnError, match=r"pose log not found .*; the built-in path is orbit"):
        load_scene(_scene(tmp_path, text))


@pytest.mark.gpu
def test_video_line_names_the_eyes_it_holds(capsys, tmp_path):
    """The printed video line follows the eyes the run rendered, given or by default (two)."""
    for extra, name, what in (
        ([], "stereo.mp4", "(left eye | right eye)"),
        (["--eyes", "1"], "mono.mp4", "(one eye)"),
    ):
        out = tmp_path / f"o{len(extra)}"
        argv = ["run", "--profile", "tiny", "--frames", "2", "--quiet", "--out", str(out)]
        assert main([*argv, *extra]) == 0
        assert f"{name} {what}" in capsys.readouterr().out


@pytest.mark.gpu
def test_eyes_side_by_side_must_fit_the_adapter(capsys, tmp_path):
    """Mode texture draws both eyes into one target: two eyes each within the adapter's
    texture limit can still be too wide together (a one-line error, not wgpu's)."""
    from vrneural.errors import VrnError
    from vrneural.gpu.device import adapter_summary
    from vrneural.runtime.renderer import Renderer, Settings
    from vrneural.runtime.scene import builtin_scene

    m = adapter_summary().limits["max_texture_dimension_2d"]
    w = m // 2 + 2
    msg = _err(capsys, ["--profile", "tiny", "--eye-res", f"{w}x16", "--out", str(tmp_path / "o")])
    assert f"one target {2 * w} pixels wide, above the adapter maximum {m}" in msg
    assert f"use a width of at most {m // 2}" in msg and not (tmp_path / "o").exists()
    with pytest.raises(VrnError, match=f"one target {2 * w} pixels wide"):
        Renderer(builtin_scene(1), Settings(eyes=2, texture_res=64, eye_res=(w, 16)))
