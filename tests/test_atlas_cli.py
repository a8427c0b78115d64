"""`vrneural atlas`: outputs, stats, and one-line errors with exit code 2."""

from __future__ import annotations

import json

import imageio.v3 as iio
import numpy as np
import pytest
import trimesh

from vrneural.cli import main


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VRNEURAL_CACHE", str(tmp_path / "cache"))


def test_builtin_to_png_with_json(tmp_path, capsys):
    out = tmp_path / "a.png"
    assert main(["atlas", "torus", "--res", "128", "-o", str(out), "--json"]) == 0
    stats = json.loads(capsys.readouterr().out)
    for key in (
        "coverage_pct",
        "charts",
        "triangles",
        "texels_per_triangle_min",
        "texels_per_triangle_median",
        "triangles_without_texels",
        "total_s",
    ):
        assert key in stats
    assert stats["triangles"] == 9216 and stats["cache"] == "miss"
    img = iio.imread(out)
    assert img.shape == (128, 128, 3) and img.dtype == np.uint8
    empty = (img == 0).all(axis=-1)
    assert 0.05 < empty.mean() < 0.95  # charts and black background
    assert 100 - stats["filled_pct"] == pytest.approx(100 * empty.mean(), abs=0.01)
    assert (tmp_path / "a.png.config.json").exists()


def test_text_output_and_force(tmp_path, capsys):
    out = tmp_path / "p.png"
    assert main(["atlas", "plane", "--res", "64", "-o", str(out), "--color", "chart"]) == 0
    text = capsys.readouterr().out
    assert "coverage" in text and "texels/tri min" in text and "tris w/o texels" in text
    assert main(["atlas", "plane", "--res", "64", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "output exists; pass --force" in err
    assert main(["atlas", "plane", "--res", "64", "-o", str(out), "--force", "--no-cache"]) == 0
    assert "off" in capsys.readouterr().out


def test_crease_angle_splits_a_cube_without_normals(tmp_path, capsys):
    """An 8-vertex cube: at 60 degrees (the default) every normal is its face's, at 180 every
    corner's normal averages its three faces (none is axis-aligned)."""
    cube = tmp_path / "cube.obj"
    cube.write_text(
        "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
        "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
        "f 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n"
    )
    from vrneural.cli.atlas import _meshes

    (flat,) = _meshes(str(cube))
    (smooth,) = _meshes(str(cube), 180.0)
    np.testing.assert_allclose(np.abs(flat.normals).max(axis=1), 1.0, atol=1e-6)
    assert np.abs(smooth.normals).max(axis=1).max() < 0.9
    out = tmp_path / "c.png"
    argv = ["atlas", str(cube), "--res", "64", "-o", str(out), "--crease-angle", "180"]
    assert main(argv) == 0
    doc = json.loads((tmp_path / "c.png.config.json").read_text())
    assert doc["crease_angle"] == 180.0


def _two_mesh_file(path):
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.box(extents=(0.2, 0.3, 0.1)), node_name="a")
    scene.add_geometry(trimesh.creation.icosphere(1, 0.1), node_name="b")
    scene.export(path)
    return path


def test_mesh_file_with_two_meshes(tmp_path, capsys):
    _two_mesh_file(tmp_path / "s.glb")
    assert (
        main(
            [
                "atlas",
                str(tmp_path / "s.glb"),
                "--res",
                "64",
                "-o",
                str(tmp_path / "o.png"),
                "--json",
            ]
        )
        == 0
    )
    stats = json.loads(capsys.readouterr().out)
    assert len(stats) == 2
    assert (tmp_path / "o-0.png").exists() and (tmp_path / "o-1.png").exists()


@pytest.mark.parametrize(
    ("args", "out_name", "message"),
    [
        (["{tmp}/missing.obj"], "a.png", "missing.obj: no such file"),
        (["{tmp}/nan.obj"], "a.png", "nan.obj:3: vertex 3 has a NaN/Inf position (0 inf 0)"),
        (["sphere", "--res", "0"], "a.png", "--res = 0 is out of range; allowed [8, 8192]"),
        (["sphere", "--res", "-5"], "a.png", "--res = -5 is out of range"),
        (["sphere", "--res", "100000"], "a.png", "--res = 100000 is out of range"),
        (["sphere", "--res", "4"], "a.png", "--res = 4 is out of range; allowed [8, 8192]"),
        (
            ["sphere", "--res", "33"],
            "a.png",
            "--res = 33 must be even (2x2 blocks); allowed: even values in [8, 8192]",
        ),
        (["sphere", "--padding", "-1"], "a.png", "--padding = -1 is out of range; allowed [0, 64]"),
        (["sphere"], "a.txt", "output must be a .png file"),
        (["teapot"], "a.png", "teapot: no such file, and not a built-in mesh (sphere, torus"),
        (
            ["sphere", "--crease-angle", "200"],
            "a.png",
            "--crease-angle = 200.0 is out of range; allowed [0, 180]",
        ),
    ],
)
def test_errors_are_one_line_exit_2(tmp_path, capsys, args, out_name, message):
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n")
    out = tmp_path / out_name
    args = [a.format(tmp=tmp_path) for a in args]
    assert main(["atlas", *args, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize(
    ("mesh", "existing"),
    [
        ("two", "o-0.png"),  # the first per-mesh PNG (was overwritten)
        ("two", "o-1.png"),
        ("two", "o.png.config.json"),  # the sidecar (was overwritten)
        ("plane", "o.png.config.json"),  # the sidecar of a new single-mesh PNG
        ("plane", "o.png"),
    ],
)
def test_no_existing_output_is_overwritten_without_force(tmp_path, capsys, mesh, existing):
    """Every file the command writes is checked before any is written."""
    spec = str(_two_mesh_file(tmp_path / "s.glb")) if mesh == "two" else mesh
    out = tmp_path / "o.png"
    (tmp_path / existing).write_text("precious")
    assert main(["atlas", spec, "--res", "64", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{tmp_path / existing}: output exists; pass --force" in err
    assert (tmp_path / existing).read_text() == "precious"
    written = {p.name for p in tmp_path.iterdir()} - {existing, "s.glb"}
    assert not written, "nothing is written when one output exists"
    assert main(["atlas", spec, "--res", "64", "-o", str(out), "--force"]) == 0
    assert (tmp_path / existing).read_bytes() != b"precious"


def test_multi_mesh_file_does_not_need_force_for_out_itself(tmp_path, capsys):
    """OUT itself is not written for a file of several meshes (OUT-<k>.png are), so an
    existing OUT is left alone and needs no --force."""
    spec = str(_two_mesh_file(tmp_path / "s.glb"))
    (tmp_path / "o.png").write_text("precious")
    assert main(["atlas", spec, "--res", "64", "-o", str(tmp_path / "o.png"), "--json"]) == 0
    assert [r["output"] for r in json.loads(capsys.readouterr().out)] == [
        str(tmp_path / "o-0.png"),
        str(tmp_path / "o-1.png"),
    ]
    assert (tmp_path / "o.png").read_text() == "precious"


def test_json_stays_valid_with_warnings_on_stderr(tmp_path, capsys):
    """A mesh warning (skipped degenerate triangles) goes to stderr as one line; stdout is
    the JSON alone; the sidecar records the warning too."""
    obj = tmp_path / "degen.obj"
    obj.write_text(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 0 0\n"
        "f 1 2 3\nf 2 4 3\nf 1 2 5\nf 1 1 2\n"  # the last two: collinear, repeated index
    )
    out = tmp_path / "d.png"
    assert main(["atlas", str(obj), "--res", "64", "-o", str(out), "--json"]) == 0
    cap = capsys.readouterr()
    stats = json.loads(cap.out)
    assert stats["triangles"] == 2
    note = "degen.obj: skipped 2 degenerate triangles of 4"
    assert f"warning: {note}\n" in cap.err and "MeshWarning" not in cap.err
    assert json.loads((tmp_path / "d.png.config.json").read_text())["warnings"] == [note]
    assert main(["atlas", str(obj), "--res", "64", "-o", str(out), "--force"]) == 0
    cap = capsys.readouterr()
    assert "warning" not in cap.out and f"warning: {note}\n" in cap.err


def test_one_mesh_of_a_file_bad_faces_and_what_is_lost_are_said(tmp_path, capsys):
    """`FILE:NAME` picks one mesh as a scene does; a face naming a missing vertex is one line;
    too few texels for the triangles and --padding 0 are warnings (stderr and sidecar)."""
    glb = _two_mesh_file(tmp_path / "two.glb")
    out = tmp_path / "one.png"
    assert main(["atlas", f"{glb}:b", "--res", "64", "-o", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["triangles"] == 80  # icosphere(1), a dict
    assert main(["atlas", f"{glb}:nope", "--res", "64", "-o", str(tmp_path / "n.png")]) == 2
    assert "two.glb has no mesh 'nope'" in capsys.readouterr().err
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    assert main(["atlas", str(bad), "--res", "64", "-o", str(tmp_path / "b.png")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and f"{bad}:4: vertex index 9; the file has 3 vertices" in err
    # every other malformed OBJ line is named too (trimesh would raise a bare ValueError, or
    # silently drop the UVs a face misnames)
    for body, needle in (
        ("f 1 a 3", ":4: face corner 'a' is not an integer index"),
        ("f 1/x 2 3", ":4: face corner '1/x' holds 'x', is not an integer index"),
        ("f 1 2", ":4: a face has 2 corners; at least 3 needed"),
        ("f 1/9 2/1 3/1", ":4: texture index 9; the file has no texture coordinates"),
        ("vn 0 0 1\nf 1//1 2//1 3//-2", ":5: normal index -2 counts back past the first of"),
        ("f -9 2 3", ":4: vertex index -9 counts back past the first of the 3 vertices"),
        ("f 1/2/3/4 2 3", ":4: face corner '1/2/3/4' is not v, v/vt, v//vn or v/vt/vn"),
    ):
        bad.write_text(f"v 0 0 0\nv 1 0 0\nv 0 1 0\n{body}\n")
        assert main(["atlas", str(bad), "--res", "64", "-o", str(tmp_path / "b.png")]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and f"{bad}{needle}" in err, err
    for body, needle in (
        ("v 0 0 0\nv nan 0 0\nv 0 1 0", ":2: vertex 2 has a NaN/Inf position (nan 0 0)"),
        ("v 0 0 0\nv 1 0\nv 0 1 0", ":2: vertex 2 needs 3 numbers x y z, got 'v 1 0'"),
    ):
        bad.write_text(f"{body}\nf 1 2 3\n")
        assert main(["atlas", str(bad), "--res", "64", "-o", str(tmp_path / "b.png")]) == 2
        assert f"{bad}{needle}" in capsys.readouterr().err
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n")  # negative = from the end: fine
    assert main(["atlas", str(bad), "--res", "64", "-o", str(tmp_path / "neg.png")]) == 0
    capsys.readouterr()
    # OBJ counts from 1: a 0 (vertex, texture or normal index) is an error with its line, not
    # a face trimesh would silently build from the last vertex
    for face in ("f 0 1 2", "f 1/1 2/0 3/1", "f 1//1 2//1 -0"):
        bad.write_text(f"v 0 0 0\nv 1 0 0\nv 0 1 0\n{face}\n")
        assert main(["atlas", str(bad), "--res", "64", "-o", str(tmp_path / "b.png")]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and f"{bad}:4: face index 0; OBJ indices count from 1" in err
    assert not (tmp_path / "b.png").exists()
    # more than 4 triangles per texel: refused before any work, naming the smallest --res
    dense = tmp_path / "dense.png"
    assert main(["atlas", "highpoly", "--res", "64", "-o", str(dense)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and not dense.exists()
    assert "highpoly: 100800 triangles do not fit 64^2 = 4096 texels (at most 4 triangles" in err
    assert "use a resolution of at least 160" in err
    assert main(["atlas", "highpoly", "--res", "160", "--padding", "0", "-o", str(dense)]) == 0
    err = capsys.readouterr().err
    assert "triangles own no texel at 160^2" in err and "--padding 0" in err
    side = json.loads((tmp_path / "dense.png.config.json").read_text())
    assert any("own no texel" in w for w in side["warnings"])


def test_parts_far_smaller_than_the_mesh_keep_their_area(tmp_path, capsys):
    """A 0.5 m sphere with a 0.5 mm one in the same mesh: xatlas used to flatten the small
    one's triangles to no area (a "have no area in the atlas" warning). vrneural's charts keep
    one texel density for the whole mesh, so the small part keeps its shape, at the size its
    area earns: at 128^2 it is about a texel, so its triangles are counted as owning no texel
    (a matter of resolution, as the warning for many such triangles says)."""
    big = trimesh.creation.icosphere(subdivisions=2, radius=0.5)
    small = trimesh.creation.icosphere(subdivisions=2, radius=0.0005)
    small.apply_translation([0.6, 0.0, 0.0])
    trimesh.util.concatenate([big, small]).export(tmp_path / "mixed.obj")
    out = tmp_path / "m.png"
    argv = ["atlas", str(tmp_path / "mixed.obj"), "--res", "128", "-o", str(out), "--json"]
    assert main(argv) == 0
    cap = capsys.readouterr()
    stats = json.loads(cap.out)
    assert stats["zero_area_triangles"] == 0 and "have no area" not in cap.err
    assert 250 <= stats["triangles_without_texels"] <= 320
