"""The built-in demo: bundled packs (size, provenance, metrics), the built-in scene and its TOML
twin ``demo/scene.toml``, and a tiny-profile run of `vrneural run` with its defaults."""

import json
import math
from importlib.resources import files
from pathlib import Path

import numpy as np
import pytest

from vrneural.cli import main
from vrneural.errors import VrnError
from vrneural.formats.vrnm import read_vrnm
from vrneural.runtime import scene as scene_mod

ROOT = Path(__file__).resolve().parent.parent
DATA = Path(str(files("vrneural") / "data"))
PRESETS = ("leather", "fabric", "wood")


def test_package_data_is_small_and_found_by_importlib():
    total = sum(p.stat().st_size for p in DATA.rglob("*") if p.is_file())
    assert total < 10 * 2**20, f"package data is {total / 2**20:.1f} MB (limit 10 MB)"
    names = {p.name for p in (DATA / "materials").iterdir()}
    for k in PRESETS:
        assert {f"{k}.vrnm", f"{k}.teacher.vrnm"} <= names


@pytest.mark.parametrize("preset", PRESETS)
def test_packs_carry_provenance_and_metrics(preset):
    man = json.loads((DATA / "materials" / "manifest.json").read_text())["packs"][preset]
    for role, arch in (("", "coarse_fine"), (".teacher", "single")):
        mat = read_vrnm(DATA / "materials" / f"{preset}{role}.vrnm")
        assert mat.arch == arch
        meta = mat.meta
        prov, met = meta["provenance"], meta["metrics"]
        assert prov["btf"]["sha256"] and prov["seed"] == man["recipe"]["seed"]
        assert prov["config"]["epochs"] >= 1 and prov["epochs"] >= 1
        # quality figure of the held-out (wi, wo) pairs: finite and far below a useless fit
        # (a constant-grey prediction of these presets scores > 0.05)
        assert math.isfinite(met["test_l1"]) and 0 < met["test_l1"] < 0.03
        assert met["pack_vs_torch_max_abs"] < 1e-3
        assert meta["ranges"]
        build = meta["build"]
        assert [s["step"] for s in build["steps"]][:3] == ["btf synth", "teach", "distill"]
        assert all(s["seconds"] > 0 for s in build["steps"]) and build["total_seconds"] > 0
        assert man[f"{'teacher' if role else 'student'}_test_l1"] == met["test_l1"]


def test_builtin_scene_uses_the_bundled_packs():
    sc = scene_mod.builtin_scene(3)
    assert sc.profile == "quest3" and sc.head == "orbit"
    neural = [o for o in sc.objects if o.material.kind == "neural"]
    plain = [o for o in sc.objects if o.material.kind == "plain"]
    assert {o.mesh for o in neural} == {"sphere", "cloth", "torus"} and len(plain) == 1
    assert sorted(Path(o.material.source).stem for o in neural) == sorted(PRESETS)
    assert all(Path(o.material.source).is_file() for o in neural)  # by path, as a scene's
    for o in neural:
        assert o.material.neural.arch == "coarse_fine"
        assert o.material.reference is not None and o.material.reference.arch == "single"
    assert len(sc.lights) == 3 and [lt.motion for lt in sc.lights].count("circle") == 1
    assert len(scene_mod.builtin_scene(2).lights) == 2


def test_demo_scene_toml_matches_the_builtin_scene():
    toml = scene_mod.load_scene(ROOT / "demo" / "scene.toml")
    ref = scene_mod.builtin_scene(3)
    assert toml.profile == ref.profile and toml.head == ref.head
    assert [o.mesh for o in toml.objects] == [o.mesh for o in ref.objects]
    for a, b in zip(toml.objects, ref.objects, strict=True):
        np.testing.assert_allclose(a.model, b.model, atol=1e-9, err_msg=b.name)
        assert a.material.kind == b.material.kind and a.material.tiling == b.material.tiling
        assert (a.texture_res, a.min_texture_res) == (b.texture_res, b.min_texture_res), b.name
        if a.material.kind == "neural":
            assert Path(a.material.source).resolve() == Path(b.material.source).resolve()
            ra, rb = a.material.reference, b.material.reference  # what --mode reference shades
            assert ra is not None and rb is not None, b.name
            for k, t in rb.textures.items():
                np.testing.assert_array_equal(ra.textures[k], t)
        else:
            assert a.material.albedo == b.material.albedo
    for a, b in zip(toml.lights, ref.lights, strict=True):
        assert (a.position, a.colour, a.intensity, a.motion, a.radius, a.period) == (
            b.position, b.colour, b.intensity, b.motion, b.radius, b.period
        )  # fmt: skip


def test_missing_pack_is_one_clear_error(monkeypatch):
    monkeypatch.setitem(scene_mod.BUILTIN_MATERIALS, "wood", {"pack": "nope.vrnm", "scale": 1.0})
    with pytest.raises(VrnError, match=r"nope\.vrnm is missing.*make_assets"):
        scene_mod.builtin_scene(3)


@pytest.mark.gpu
def test_default_run_writes_video_frames_and_summary_to_a_new_dir(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = ["run", "--eyes", "2", "--reuse", "4", "--profile", "tiny", "--frames", "3", "--quiet"]
    assert main(argv) == 0
    assert main(argv) == 0  # a second run needs no --force: it gets its own directory
    runs = sorted((tmp_path / "out").glob("run-*"))
    assert len(runs) == 2
    out = runs[0]
    sm = json.loads((out / "summary.json").read_text())
    assert sm["out"] == str(Path("out") / out.name)
    assert (out / "stereo.mp4").stat().st_size > 0
    srcs = [Path(o["source"]) for o in sm["scene"]["objects"] if o["material"] == "neural"]
    assert sorted(p.stem for p in srcs) == sorted(PRESETS) and all(p.is_file() for p in srcs)
    import imageio.v3 as iio

    left, right = (iio.imread(out / f"frame0000_eye{e}.png") for e in (0, 1))
    assert left.shape == right.shape and left.std() > 5 and not np.array_equal(left, right)
    text = capsys.readouterr().out
    assert "stereo.mp4" in text and "frame ms" in text and "summary.json" in text


def test_full_pipeline_script_refuses_an_unknown_preset_before_making_anything(tmp_path):
    """demo/full_pipeline.sh checks PRESET first (its list is the synthesiser's), so the retry
    of a typo needs no new work directory."""
    import re
    import subprocess
    from pathlib import Path

    from vrneural.btf.presets import PRESETS

    script = Path(__file__).parents[1] / "demo" / "full_pipeline.sh"
    listed = re.search(r"^\s+([a-z|]+)\) ;;$", script.read_text(), re.M).group(1).split("|")
    assert sorted(listed) == sorted(PRESETS)
    work = tmp_path / "w"
    r = subprocess.run(["bash", str(script), str(work), "plastic"], capture_output=True, text=True)
    assert r.returncode == 2 and "preset 'plastic' is not one of" in r.stderr
    assert not work.exists()
