"""The on-disk atlas cache: hit/miss, key invalidation, corrupt entries, location, determinism."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from vrneural.atlas import build_atlas, builtin_mesh
from vrneural.atlas.cache import CacheWarning, cache_dir, cache_key

R = 256


@pytest.fixture
def cache_env(tmp_path, monkeypatch):
    monkeypatch.setenv("VRNEURAL_CACHE", str(tmp_path / "c"))
    return tmp_path / "c" / "atlas"


def _same(a, b):
    for attr in ("positions", "faces", "normals", "tangents", "uv"):
        np.testing.assert_array_equal(getattr(a.mesh, attr), getattr(b.mesh, attr))
    np.testing.assert_array_equal(a.uv_atlas, b.uv_atlas)
    np.testing.assert_array_equal(a.tri_ids, b.tri_ids)


def test_hit_miss_and_identical_result(cache_env):
    mesh = builtin_mesh("sphere")
    a = build_atlas(mesh, R, 2)
    assert a.stats["cache"] == "miss" and cache_dir() == cache_env
    files = list(cache_env.glob("*.vrna"))
    assert len(files) == 1 and files[0].stem == cache_key(mesh, R, 2)
    b = build_atlas(mesh, R, 2)
    assert b.stats["cache"] == "hit" and b.mesh.name == "sphere"
    _same(a, b)
    assert b.stats["charts"] == a.stats["charts"]
    c = build_atlas(mesh, R, 2, cache=False)  # a fresh build is deterministic
    assert c.stats["cache"] == "off"
    _same(a, c)
    assert not list(cache_env.glob(".*tmp*")), "no temporary files left behind"


def test_hit_under_another_name_reports_that_name(cache_env):
    mesh = builtin_mesh("sphere")
    build_atlas(mesh, R, 2)
    hit = build_atlas(dataclasses.replace(mesh, name="globe.obj"), R, 2)
    assert hit.stats["cache"] == "hit"
    assert hit.stats["mesh"] == "globe.obj" and hit.mesh.name == "globe.obj"


def test_key_changes_with_content_resolution_padding():
    mesh = builtin_mesh("sphere")
    k = cache_key(mesh, R, 2)
    moved = mesh.positions.copy()
    moved[5, 0] += 1e-6
    assert cache_key(dataclasses.replace(mesh, positions=moved), R, 2) != k
    uv = mesh.uv.copy()
    uv[0, 1] += 0.5
    assert cache_key(dataclasses.replace(mesh, uv=uv), R, 2) != k
    faces = mesh.faces.copy()
    faces[0] = faces[0][[1, 2, 0]]
    assert cache_key(dataclasses.replace(mesh, faces=faces), R, 2) != k
    assert cache_key(mesh, R + 1, 2) != k and cache_key(mesh, R, 1) != k
    assert cache_key(builtin_mesh("sphere"), R, 2) == k


def test_changed_vertex_is_a_miss(cache_env):
    mesh = builtin_mesh("plane")
    build_atlas(mesh, 64, 2)
    pos = mesh.positions.copy()
    pos[0, 1] += 0.01
    b = build_atlas(dataclasses.replace(mesh, positions=pos), 64, 2)
    assert b.stats["cache"] == "miss"
    np.testing.assert_array_equal(b.mesh.positions[b.mesh.faces], pos[mesh.faces])
    assert len(list(cache_env.glob("*.vrna"))) == 2


@pytest.mark.parametrize("damage", ["truncate", "flip", "garbage", "empty"])
def test_corrupt_entry_is_rebuilt(cache_env, damage):
    mesh = builtin_mesh("plane")
    a = build_atlas(mesh, 64, 2)
    (path,) = cache_env.glob("*.vrna")
    data = bytearray(path.read_bytes())
    if damage == "truncate":
        data = data[: len(data) // 2]
    elif damage == "flip":
        data[-100] ^= 0xFF  # inside the ID texture: its CRC no longer matches
    elif damage == "garbage":
        data = bytearray(b"junk" * 10)
    else:
        data = bytearray()
    path.write_bytes(bytes(data))
    with pytest.warns(CacheWarning, match="rebuilding"):
        b = build_atlas(mesh, 64, 2)
    assert b.stats["cache"] == "miss"
    _same(a, b)
    assert build_atlas(mesh, 64, 2).stats["cache"] == "hit"  # rewritten, usable again


def test_corrupt_entry_warning_is_one_grammatical_line(cache_env):
    """The warning names the file and the problem on one line: "not a vrneural atlas cache"
    (was "not a atlas cache"), formatted as ``warning: <message>`` (vrneural.warn)."""
    import warnings

    mesh = builtin_mesh("plane")
    build_atlas(mesh, 32, 1)
    (path,) = cache_env.glob("*.vrna")
    path.write_bytes(b"junk" * 10)
    with pytest.warns(CacheWarning) as rec:
        build_atlas(mesh, 32, 1)
    (w,) = rec
    msg = str(w.message)
    assert f"atlas cache: {path}: wrong magic" in msg and "rebuilding" in msg
    assert "not a vrneural atlas cache" in msg and "a atlas" not in msg
    text = warnings.formatwarning(w.message, w.category, w.filename, w.lineno)
    assert text == f"warning: {msg}\n"


def test_unwritable_cache_dir_warns(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    monkeypatch.setenv("VRNEURAL_CACHE", str(blocker))  # a file, so atlas/ cannot be created
    with pytest.warns(CacheWarning, match="cannot write"):
        a = build_atlas(builtin_mesh("plane"), 32, 1)
    assert a.stats["cache_file"] is None


def test_build_rejects_bad_meshes_and_counts_degenerate_triangles():
    from vrneural.errors import VrnError

    mesh = builtin_mesh("plane")
    pos = mesh.positions.copy()
    pos[3] = np.nan
    with pytest.raises(VrnError, match="plane: 1 vertex has a NaN/Inf position"):
        build_atlas(dataclasses.replace(mesh, positions=pos), 64, cache=False)
    with pytest.raises(VrnError, match="plane: mesh has no faces"):
        build_atlas(dataclasses.replace(mesh, faces=np.zeros((0, 3), np.uint32)), 64, cache=False)
    with pytest.raises(VrnError, match="resolution = 4 is out of range"):
        build_atlas(mesh, 4, cache=False)
    # kept with a count: a repeated index and a collinear (zero-area) triangle
    extra = np.array([[0, 0, 1], [0, 1, 2]], np.uint32)  # vertices 0, 1, 2 lie on one row
    faces = np.concatenate([mesh.faces, extra])
    a = build_atlas(dataclasses.replace(mesh, faces=faces), 64, cache=False)
    assert a.stats["zero_area_triangles"] == 2 and a.stats["triangles_without_texels"] == 0
    assert len(a.mesh.faces) == len(faces)
    assert not np.isin(a.tri_ids, [len(faces) - 2, len(faces) - 1]).any()
    # their split vertices are not shared with the real triangles
    real = set(a.mesh.faces[:-2].ravel().tolist())
    assert not real & set(a.mesh.faces[-2:].ravel().tolist())
