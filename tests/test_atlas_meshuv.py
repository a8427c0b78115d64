"""A mesh's own UVs as its atlas: glTF TEXCOORD_1 and OBJ vt, the checks, --atlas-uv, and the
one-line errors for bad UV input (exit 2, nothing written)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from atlas_helpers import gutter_failures

from vrneural.atlas import build_atlas, load_mesh
from vrneural.bench.atlas_meshes import torus_with_lightmap, write_glb
from vrneural.cli import main


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VRNEURAL_CACHE", str(tmp_path / "cache"))


def _lightmap_glb(path, **change):
    pos, faces, nrm, uv0, uv1 = torus_with_lightmap(24, 12)
    parts = dict(pos=pos, faces=faces, normals=nrm, uv0=uv0, uv1=uv1) | change
    return write_glb(path, **parts)


def test_gltf_lightmap_uvs_are_the_atlas(tmp_path, rng):
    (mesh,) = load_mesh(_lightmap_glb(tmp_path / "lm.glb"))
    assert mesh.lightmap_uv is not None and mesh.lightmap_uv.shape == (len(mesh.positions), 2)
    a = build_atlas(mesh, 256, cache=False)
    s = a.stats
    assert s["uv_source"] == "mesh lightmap UVs (TEXCOORD_1)"
    assert s["uv_reason"] == "they passed the checks" and s["charts"] == 3
    assert s["unwrap_path"][-1] == "as in the file"  # 3 islands, 66 % of the square: kept
    np.testing.assert_array_equal(a.uv_atlas, a.mesh.lightmap_uv)  # exactly the file's UVs
    assert s["overlap_texels"] == 0 and s["triangles_without_texels"] == 0
    assert gutter_failures(a, rng) == 0
    # asked for an unwrap instead: the file's UVs are ignored
    b = build_atlas(mesh, 256, cache=False, atlas_uv="charts")
    assert b.stats["uv_source"] == "charts" and b.stats["uv_reason"] == "atlas_uv = charts"


def test_a_poorly_packed_lightmap_is_repacked_with_its_islands(tmp_path, rng):
    """Islands shrunk into a corner (15 % coverage) and pushed outside [0, 1]: the same three
    islands are re-packed."""
    pos, faces, nrm, uv0, uv1 = torus_with_lightmap(24, 12)
    (mesh,) = load_mesh(write_glb(tmp_path / "c.glb", pos, faces, nrm, uv0, uv1 * 0.4 + 0.7))
    s = build_atlas(mesh, 256, cache=False).stats
    assert s["uv_source"] == "mesh lightmap UVs (TEXCOORD_1)" and s["charts"] == 3
    assert s["unwrap_path"][-1].startswith("re-packed (outside [0, 1])")
    assert s["coverage_pct"] > 55 and s["overlap_texels"] == 0


def test_obj_vt_is_used_when_it_is_a_layout_not_when_it_tiles(tmp_path):
    from vrneural.atlas.builtin import grid_faces

    n = 8
    s, t = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1), indexing="xy")
    v = "".join(
        f"v {x - 0.5:.6f} 0 {y - 0.5:.6f}\n" for x, y in zip(s.ravel(), t.ravel(), strict=True)
    )
    f = grid_faces(n, n) + 1
    body = "".join(f"f {a}/{a} {b}/{b} {c}/{c}\n" for a, b, c in f)
    for scale, used in ((0.9, True), (3.0, False)):
        vt = "".join(
            f"vt {0.05 + scale * x:.6f} {0.05 + scale * y:.6f}\n"
            for x, y in zip(s.ravel(), t.ravel(), strict=True)
        )
        (tmp_path / "p.obj").write_text(v + vt + body)
        (mesh,) = load_mesh(tmp_path / "p.obj")
        st = build_atlas(mesh, 64, cache=False).stats
        if used:
            assert st["uv_source"] == "mesh UVs (TEXCOORD_0 / vt)", st["uv_reason"]
        else:
            assert st["uv_source"] == "charts"
            assert st["uv_reason"] == "UVs (TEXCOORD_0 / vt) leave [0, 1] (they tile a material)"


def _run(tmp_path, capsys, mesh, *extra, name="o.png"):
    out = tmp_path / name
    rc = main(["atlas", str(mesh), "--res", "128", "-o", str(out), *extra])
    err = capsys.readouterr().err
    return rc, err.split("\r")[-1].strip(), out


def test_overlapping_uvs_auto_repacks_a_lightmap_and_mesh_insists_with_an_error(tmp_path, capsys):
    """All three islands stacked on one square: auto re-packs a lightmap set's islands apart
    (or unwraps a material set); --atlas-uv mesh is one line naming the file, the part and the
    count, exit 2, nothing written."""
    pos, faces, nrm, uv0, uv1 = torus_with_lightmap(24, 12)
    stacked = uv1 - np.floor(uv1 * 2) / 2  # every island moved into [0, 0.5]^2
    glb = write_glb(tmp_path / "st.glb", pos, faces, nrm, uv0, stacked)
    rc, err, out = _run(tmp_path, capsys, glb, "--no-cache")
    assert rc == 0
    stats = json.loads((tmp_path / "o.png.config.json").read_text())["stats"][0]
    assert stats["uv_source"] == "mesh lightmap UVs (TEXCOORD_1)" and stats["charts"] == 3
    assert stats["unwrap_path"][-1] == "re-packed (islands overlap)"
    assert stats["overlap_texels"] == 0
    rc, err, out = _run(tmp_path, capsys, glb, "--atlas-uv", "mesh", name="m.png")
    assert rc == 2 and not out.exists() and not (tmp_path / "m.png.config.json").exists()
    head = f"vrneural atlas: error: {glb.name}:st: its lightmap UVs (TEXCOORD_1) cannot be the "
    assert err.startswith(head + "atlas: ") and err.count("\n") == 0, err
    n = int(err[len(head + "atlas: ") :].split()[0])  # triangles found sharing a texel centre
    assert 300 < n <= 576 and f"{n} triangles overlapping others of 576;" in err


def test_bad_uv_input_is_one_line_exit_2_and_nothing_written(tmp_path, capsys):
    pos, faces, nrm, uv0, uv1 = torus_with_lightmap(24, 12)
    nan = uv1.copy()
    nan[[3, 7, 9]] = np.nan
    cases = [
        (
            write_glb(tmp_path / "nan.glb", pos, faces, nrm, uv0, nan),
            (),
            "nan.glb:nan: TEXCOORD_1 of 3 vertices are NaN/Inf (the first is vertex index 3",
        ),
        (
            write_glb(tmp_path / "short.glb", pos, faces, nrm, uv0, uv1[:-5]),
            (),
            f"short.glb:short: TEXCOORD_1 has shape [{len(pos) - 5}, 2], expected [{len(pos)}, 2]",
        ),
        (
            write_glb(tmp_path / "nouv.glb", pos, faces, nrm),
            ("--atlas-uv", "mesh"),
            "nouv.glb:nouv: atlas_uv = mesh, but the mesh has no UVs of its own",
        ),
    ]
    (tmp_path / "vt.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n")
    cases.append((tmp_path / "vt.obj", (), "vt.obj:5: texture index 2; the file has 1"))
    (tmp_path / "flat.obj").write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 2 3 4\n")
    cases.append((tmp_path / "flat.obj", (), "flat.obj: all 2 triangles are degenerate"))
    for mesh, extra, message in cases:
        rc, err, out = _run(tmp_path, capsys, mesh, *extra)
        assert rc == 2 and message in err and err.count("\n") == 0, (mesh, err)
        assert not out.exists() and not (tmp_path / "o.png.config.json").exists()


def test_folded_uvs_are_refused_by_auto_and_an_error_for_mesh(tmp_path):
    from vrneural.atlas import make_mesh
    from vrneural.errors import VrnError

    pos, faces, nrm, uv0, uv1 = torus_with_lightmap(24, 12)
    folded = uv1.copy()
    folded[faces[:40].ravel()] = folded[faces[:40].ravel()][:, ::-1]  # a patch mirrored in place
    mesh = make_mesh("folded", pos, faces, uv=uv0, normals=nrm, lightmap_uv=folded)
    s = build_atlas(mesh, 128, cache=False).stats
    assert s["uv_source"] == "charts" and "TEXCOORD_1" in s["uv_reason"], s["uv_reason"]
    with pytest.raises(VrnError, match=r"folded: its lightmap UVs \(TEXCOORD_1\) cannot be"):
        build_atlas(mesh, 128, cache=False, atlas_uv="mesh")


def test_cache_key_follows_the_uv_choice_and_the_lightmap(tmp_path):
    import dataclasses

    from vrneural.atlas.cache import cache_key

    (mesh,) = load_mesh(_lightmap_glb(tmp_path / "k.glb"))
    k = cache_key(mesh, 64, 2)
    assert cache_key(mesh, 64, 2, "charts") != k
    moved = mesh.lightmap_uv.copy()
    moved[0, 0] += 1e-3
    assert cache_key(dataclasses.replace(mesh, lightmap_uv=moved), 64, 2) != k
    assert json.dumps(build_atlas(mesh, 64).stats["unwrap_path"])
