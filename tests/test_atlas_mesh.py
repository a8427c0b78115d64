"""Meshes: built-ins, validation, normals and tangents, box UVs, loading OBJ/PLY/GLB."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from vrneural.atlas import BUILTIN_MESHES, MeshWarning, builtin_mesh, load_mesh, make_mesh
from vrneural.atlas.geometry import box_uv, vertex_tangents
from vrneural.errors import VrnError


def _check_frame(m):
    assert m.positions.dtype == np.float32 and m.faces.dtype == np.uint32
    assert np.isfinite(m.positions).all() and np.isfinite(m.tangents).all()
    np.testing.assert_allclose(np.linalg.norm(m.normals, axis=1), 1.0, atol=1e-5)
    np.testing.assert_allclose(np.linalg.norm(m.tangents[:, :3], axis=1), 1.0, atol=1e-5)
    assert np.abs(np.sum(m.normals * m.tangents[:, :3], axis=1)).max() < 1e-4
    assert set(np.unique(m.tangents[:, 3])) <= {-1.0, 1.0}


@pytest.mark.parametrize("name", BUILTIN_MESHES)
def test_builtin_meshes(name):
    m = builtin_mesh(name)
    _check_frame(m)
    ext = np.ptp(m.positions, axis=0).max()
    assert 0.2 <= ext <= 1.0, "objects are 0.2-1 m"
    assert m.uv.shape == (len(m.positions), 2) and np.ptp(m.uv, axis=0).min() > 0.5
    if name == "highpoly":
        assert 95_000 <= len(m.faces) <= 110_000
    # outward/up-facing winding: face normals agree with the vertex normals
    p = m.positions[m.faces].astype(np.float64)
    fn = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    vn = m.normals[m.faces].mean(axis=1)
    assert np.mean(np.sum(fn * vn, axis=1) > 0) > 0.99


def test_builtin_tangents_follow_material_u():
    """On the plane (uv = xz / tile) the tangent is +x and the bitangent +z, i.e. w * (n x t)."""
    m = builtin_mesh("plane")
    np.testing.assert_allclose(
        m.tangents[:, :3], np.tile([1, 0, 0], (len(m.positions), 1)), atol=1e-6
    )
    b = m.tangents[:, 3:4] * np.cross(m.normals, m.tangents[:, :3])
    np.testing.assert_allclose(b, np.tile([0, 0, 1], (len(m.positions), 1)), atol=1e-6)
    with pytest.raises(VrnError, match="not allowed"):
        builtin_mesh("teapot")


def test_mirrored_uv_flips_the_bitangent_sign():
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    faces = np.array([[0, 1, 2]])
    n = np.tile([0.0, 0.0, 1.0], (3, 1))
    t = vertex_tangents(pos, faces, np.array([[0, 0], [1, 0], [0, 1]], float), n)
    assert np.all(t[:, 3] == 1) and np.allclose(t[:, :3], [1, 0, 0])
    t = vertex_tangents(pos, faces, np.array([[0, 0], [1, 0], [0, -1]], float), n)
    assert np.all(t[:, 3] == -1) and np.allclose(t[:, :3], [1, 0, 0])


def test_validation_errors_and_degenerate_warning():
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], float)
    with pytest.raises(VrnError, match="no faces"):
        make_mesh("m", pos, np.zeros((0, 3), int))
    bad = pos.copy()
    bad[2, 1] = np.nan
    with pytest.raises(
        VrnError,
        match=r"1 vertex has a NaN/Inf position \(the first is vertex index 2, counted from 0\)",
    ):
        make_mesh("m", bad, [[0, 1, 2]])
    bad[2, 1] = np.inf
    with pytest.raises(VrnError, match="NaN/Inf"):
        make_mesh("m", bad, [[0, 1, 2]])
    with pytest.raises(VrnError, match="out of range"):
        make_mesh("m", pos, [[0, 1, 7]])
    faces = [[0, 1, 2], [0, 0, 1], [0, 1, 3]]  # repeated index; collinear
    with pytest.warns(MeshWarning, match="skipped 2 degenerate triangles of 3"):
        m = make_mesh("m", pos, faces, uv=pos[:, :2])
    assert len(m.faces) == 1
    with (
        pytest.raises(VrnError, match="its only triangle is degenerate"),
        pytest.warns(MeshWarning),
    ):
        make_mesh("m", pos, [[0, 1, 3]])
    far = pos.copy()
    far[3] = [1e39, 0, 0]  # finite in float64, Inf once the mesh is float32
    with pytest.raises(VrnError, match=r"m: 1 vertex lies beyond 1e\+18 m .*vertex index 3"):
        make_mesh("m", far, [[0, 1, 3]])


def test_mesh_warning_prints_as_one_line(tmp_path):
    """vrneural's warnings print as ``warning: <message>`` on stderr, without Python's
    file:line prefix and source line; other warnings keep Python's format. A fresh process,
    as a user's script sees it (pytest records warnings instead of printing them)."""
    import subprocess
    import sys

    code = (
        "import warnings\n"
        "from vrneural.atlas import make_mesh\n"
        "make_mesh('m', [[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], [[0, 1, 2], [0, 1, 3]])\n"
        "warnings.warn('plain', UserWarning)\n"
    )
    r = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=tmp_path
    )
    assert r.returncode == 0, r.stderr
    lines = r.stderr.splitlines()
    assert lines[0] == "warning: m: skipped 1 degenerate triangle of 2"
    assert lines[1] == "<string>:4: UserWarning: plain"


def test_box_uv_splits_vertices_and_is_planar():
    box = trimesh.creation.box(extents=(0.4, 0.2, 0.1))
    src, faces, uv = box_uv(np.asarray(box.vertices), np.asarray(box.faces))
    pos = np.asarray(box.vertices)[src]
    assert len(pos) == 24  # 8 corners x 3 projections
    # each face keeps its 3D shape in UV (planar projection along its own axis): equal areas
    p = pos[faces]
    a3 = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    e1, e2 = uv[faces[:, 1]] - uv[faces[:, 0]], uv[faces[:, 2]] - uv[faces[:, 0]]
    a2 = np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    np.testing.assert_allclose(a2 * 0.4**2, a3, rtol=1e-9)


def test_load_obj_ply_glb_and_scenes(tmp_path):
    src = builtin_mesh("torus")
    tm = trimesh.Trimesh(
        src.positions, src.faces, process=False, visual=trimesh.visual.TextureVisuals(uv=src.uv)
    )
    tm.export(tmp_path / "t.obj")
    tm.export(tmp_path / "t.glb")
    trimesh.Trimesh(src.positions, src.faces, process=False).export(tmp_path / "t.ply")
    for ext in ("obj", "glb"):
        (m,) = load_mesh(tmp_path / f"t.{ext}")
        _check_frame(m)
        assert len(m.faces) == len(src.faces)
        # material UVs kept (OBJ may re-index vertices; compare per corner)
        np.testing.assert_allclose(m.uv[m.faces], src.uv[src.faces], atol=1e-5)
        np.testing.assert_allclose(m.positions[m.faces], src.positions[src.faces], atol=1e-6)
    (m,) = load_mesh(tmp_path / "t.ply")  # no UVs in the file: box projection
    _check_frame(m)
    assert len(m.faces) == len(src.faces) and len(m.positions) > len(src.positions)
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.box(extents=(0.2, 0.2, 0.2)), node_name="box")
    scene.add_geometry(
        trimesh.creation.icosphere(2, 0.1),
        node_name="ball",
        transform=trimesh.transformations.translation_matrix([1, 0, 0]),
    )
    scene.export(tmp_path / "s.glb")
    meshes = load_mesh(tmp_path / "s.glb")
    assert sorted(m.name for m in meshes) == ["s.glb:ball", "s.glb:box"]
    ball = next(m for m in meshes if m.name.endswith("ball"))
    np.testing.assert_allclose(ball.positions.mean(axis=0), [1, 0, 0], atol=1e-2)


def test_file_normals_are_kept(tmp_path):
    """A quad whose file normals are tilted (not the geometric +z): they survive loading."""
    n = np.array([0.0, 0.6, 0.8])
    text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
    text += "vn 0 0.6 0.8\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n"
    (tmp_path / "q.obj").write_text(text)
    (m,) = load_mesh(tmp_path / "q.obj")
    np.testing.assert_allclose(m.normals, np.tile(n, (len(m.normals), 1)), atol=1e-6)
    plain = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
    (tmp_path / "q2.obj").write_text(plain + "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")
    (m2,) = load_mesh(tmp_path / "q2.obj")
    np.testing.assert_allclose(m2.normals, np.tile([0, 0, 1.0], (len(m2.normals), 1)), atol=1e-6)


def _tilted_quad(normal):
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=np.float64)
    f = np.array([[0, 1, 2], [0, 2, 3]])
    uv = v[:, :2].copy()
    return trimesh.Trimesh(
        v,
        f,
        vertex_normals=np.tile(normal, (4, 1)),
        visual=trimesh.visual.TextureVisuals(uv=uv),
        process=False,
    )


def test_scene_nodes_keep_file_order_and_file_normals(tmp_path):
    """A glTF with three nodes: they come back in the file's order (``:0`` is the first), and
    each node's file normals are carried through its transform (a rotation, a mirror), with a
    mirrored node's triangles turned to keep facing their normals."""
    n = np.array([0.0, 0.6, 0.8])
    tf = trimesh.transformations
    rot = tf.rotation_matrix(np.pi / 2, [1, 0, 0])
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0])
    scene = trimesh.Scene()
    for name, m in (("first", np.eye(4)), ("second", rot), ("third", mirror)):
        scene.add_geometry(_tilted_quad(n), node_name=name, geom_name=f"q{name}", transform=m)
    (tmp_path / "s.glb").write_bytes(trimesh.exchange.gltf.export_glb(scene, include_normals=True))
    meshes = load_mesh(tmp_path / "s.glb")
    assert [m.name for m in meshes] == ["s.glb:first", "s.glb:second", "s.glb:third"]
    for m, matrix in zip(meshes, (np.eye(4), rot, mirror), strict=True):
        want = matrix[:3, :3] @ n  # rotation and this mirror: the inverse transpose is itself
        np.testing.assert_allclose(m.normals, np.tile(want, (len(m.normals), 1)), atol=1e-6)
        assert (np.sum(_face_normals(m) * want, axis=1) > 0.5).all(), m.name
    np.testing.assert_allclose(meshes[1].positions[:, 2].max(), 1.0, atol=1e-6)  # rotated up


def test_obj_objects_materials_and_latin1(tmp_path):
    """One mesh per ``o`` object in file order, named after it (Latin-1 bytes decoded); the
    materials inside an object do not split it."""
    quad = "v {x} 0 0\nv {x1} 0 0\nv {x1} 1 0\nv {x} 1 0\n"
    text = "# exportiert von M\xfcller\no Caf\xe9\n" + quad.format(x=0, x1=1)
    text += "usemtl red\nf 1 2 3\nusemtl blue\nf 1 3 4\n"
    text += "o Zebra\n" + quad.format(x=2, x1=3) + "f 5 6 7\nf 5 7 8\n"
    (tmp_path / "two.obj").write_bytes(text.encode("latin-1"))
    cafe, zebra = load_mesh(tmp_path / "two.obj")
    assert (cafe.name, zebra.name) == ("two.obj:Caf\xe9", "two.obj:Zebra")
    assert len(cafe.faces) == 2 and len(zebra.faces) == 2
    assert cafe.positions[:, 0].max() == 1.0 and zebra.positions[:, 0].min() == 2.0
    # faces before the first ``o`` line come first, then the objects in file order
    lead = quad.format(x=5, x1=6) + "f 1 2 3\no Zebra\n" + quad.format(x=2, x1=3) + "f 5 6 7\n"
    (tmp_path / "lead.obj").write_text(lead + "o Ant\n" + quad.format(x=8, x1=9) + "f 9 10 11\n")
    first, zebra, ant = load_mesh(tmp_path / "lead.obj")
    # a UTF-8 byte-order mark before a first v line: that vertex still counts
    (tmp_path / "bom.obj").write_bytes(
        b"\xef\xbb\xbf" + (quad.format(x=0, x1=1) + "f 1 2 4\n").encode()
    )
    (bom,) = load_mesh(tmp_path / "bom.obj")
    assert len(bom.faces) == 1 and bom.positions[:, 0].max() == 1.0
    assert (zebra.name, ant.name) == ("lead.obj:Zebra", "lead.obj:Ant")
    assert first.positions[:, 0].min() == 5.0 and ant.positions[:, 0].min() == 8.0
    # an ``o`` name repeated later adds to that object, which keeps its first place (it went
    # last, so ``file.obj:0`` was the second object)
    again = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\no first\nf 1 2 3\no second\nf 1 2 4\n"
    (tmp_path / "again.obj").write_text(again + "o first\nf 2 4 3\n")
    meshes = load_mesh(tmp_path / "again.obj")
    assert [(m.name, len(m.faces)) for m in meshes] == [
        ("again.obj:first", 2),
        ("again.obj:second", 1),
    ]


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("vt nan 0", "texture coordinate 1 is NaN/Inf"),
        ("vt u v", "texture coordinate 1 needs numbers u v"),
        ("vn 0 inf 1", "normal 1 is NaN/Inf"),
        ("vn 0 1", "normal 1 needs 3 numbers"),
    ],
)
def test_obj_bad_texture_coordinate_or_normal_names_the_line(tmp_path, line, message):
    text = f"v 0 0 0\nv 1 0 0\nv 0 1 0\n{line}\nf 1 2 3\n"
    (tmp_path / "b.obj").write_text(text)
    with pytest.raises(VrnError, match=f"b.obj:4: {message}"):
        load_mesh(tmp_path / "b.obj")


def test_load_errors(tmp_path):
    with pytest.raises(VrnError, match="no such file"):
        load_mesh(tmp_path / "missing.obj")
    (tmp_path / "x.xyz").write_text("1 2 3\n")
    with pytest.raises(VrnError, match="unsupported mesh type"):
        load_mesh(tmp_path / "x.xyz")
    (tmp_path / "pts.ply").write_text(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
    )
    with pytest.raises(VrnError, match="no triangle faces"):
        load_mesh(tmp_path / "pts.ply")
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n")
    with pytest.raises(VrnError, match="NaN/Inf"):
        load_mesh(tmp_path / "nan.obj")
    (tmp_path / "junk.glb").write_bytes(b"not a glb file at all")
    with pytest.raises(VrnError, match="cannot read mesh"):
        load_mesh(tmp_path / "junk.glb")


_CUBE = (
    "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
    "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
    "f 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n"
)


def _face_normals(m):
    p = m.positions.astype(np.float64)[m.faces.astype(np.int64)]
    fn = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return fn / np.linalg.norm(fn, axis=1, keepdims=True)


def test_cube_without_normals_has_flat_faces(tmp_path):
    """An 8-vertex cube with no normals in the file: its edges are creases (90 > 60 degrees),
    so every corner gets its face's normal, not the diagonal average over the three faces."""
    (tmp_path / "cube.obj").write_text(_CUBE)
    (m,) = load_mesh(tmp_path / "cube.obj")
    _check_frame(m)
    fn = _face_normals(m)
    for k in range(3):
        np.testing.assert_allclose(m.normals[m.faces[:, k]], fn, atol=1e-6)
    (smooth,) = load_mesh(tmp_path / "cube.obj", crease_deg=180)  # everything smoothed
    assert np.abs(smooth.normals).min() > 0.3  # blended over the three faces at each corner
    with_vn = _CUBE.split("f ")[0] + "vn 0 0 1\nf 1//1 2//1 3//1\n"
    (tmp_path / "cube_vn.obj").write_text(with_vn)
    with pytest.warns(MeshWarning, match="own normals; crease angle 30 not used"):
        load_mesh(tmp_path / "cube_vn.obj", crease_deg=30)


def test_smooth_mesh_keeps_its_vertices_and_zero_crease_is_flat():
    ico = trimesh.creation.icosphere(subdivisions=3)
    pos, faces = np.asarray(ico.vertices), np.asarray(ico.faces)
    uv = pos[:, :2] * 0.5 + 0.5  # any UV: normals do not depend on it
    m = make_mesh("ico", pos, faces, uv=uv)  # default 60: neighbours differ by ~10 degrees
    assert len(m.positions) == len(pos)
    np.testing.assert_array_equal(m.faces, faces)
    np.testing.assert_allclose(m.normals, pos / np.linalg.norm(pos, axis=1)[:, None], atol=2e-2)
    flat = make_mesh("ico", pos, faces, uv=uv, crease_deg=0)
    assert len(flat.positions) > len(pos)
    _check_frame(flat)
    fn = _face_normals(flat)
    for k in range(3):
        np.testing.assert_allclose(flat.normals[flat.faces[:, k]], fn, atol=1e-6)
    np.testing.assert_allclose(flat.positions[flat.faces], m.positions[m.faces])
    np.testing.assert_allclose(flat.uv[flat.faces], m.uv[m.faces])
    with pytest.raises(VrnError, match=r"ico: crease angle 200 is out of range \[0, 180\]"):
        make_mesh("ico", pos, faces, uv=uv, crease_deg=200)


def _creased_twin(pos, faces, crease_deg):
    """Per-corner normals by brute force: the loop the vectorized code replaces."""
    fn = np.cross(pos[faces[:, 1]] - pos[faces[:, 0]], pos[faces[:, 2]] - pos[faces[:, 0]])
    fu = fn / np.linalg.norm(fn, axis=1, keepdims=True)
    keyed = [tuple(p) for p in pos]
    out = np.zeros((len(faces), 3, 3))
    for f in range(len(faces)):
        for k in range(3):
            here = keyed[faces[f, k]]
            acc = np.zeros(3)
            for g in range(len(faces)):
                at = any(keyed[faces[g, j]] == here for j in range(3))
                if at and fu[f] @ fu[g] >= np.cos(np.radians(crease_deg)) - 1e-9:
                    acc += fn[g]
            out[f, k] = acc / np.linalg.norm(acc)
    return out


@pytest.mark.parametrize("crease", [0.0, 25.0, 60.0, 120.0])
def test_creased_normals_match_a_brute_force_twin(monkeypatch, crease):
    """A bumpy grid with a duplicated (UV-seam) column: the vectorized corners equal the loop,
    also when the pair buffer is cut into tiny chunks; seam copies share their normal."""
    from vrneural.atlas import geometry

    rng = np.random.default_rng(3)
    n = 6
    s, t = np.meshgrid(np.arange(n + 1.0), np.arange(n + 1.0), indexing="xy")
    pos = np.stack([s.ravel(), t.ravel(), rng.uniform(-0.8, 0.8, s.size)], 1)
    faces = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            faces += [[a, a + 1, a + n + 1], [a + 1, a + n + 2, a + n + 1]]
    faces = np.array(faces)
    seam = np.arange(3, len(pos), n + 1)  # column 3 duplicated: faces right of it use copies
    pos2 = np.concatenate([pos, pos[seam]])
    right = (pos[faces].min(axis=1)[:, 0] >= 3).nonzero()[0]
    remap = np.arange(len(pos))
    remap[seam] = len(pos) + np.arange(len(seam))
    faces[right] = remap[faces[right]]
    want = _creased_twin(pos2, faces, crease)
    for chunk in (geometry._PAIR_CHUNK, 5):
        monkeypatch.setattr(geometry, "_PAIR_CHUNK", chunk)
        src, f2, nrm = geometry.creased_normals(pos2, faces, crease)
        np.testing.assert_array_equal(src[f2], faces)  # same triangles, same positions
        np.testing.assert_allclose(nrm[f2], want, atol=1e-9)


def test_python_api_arguments_are_checked():
    """What a Python user gets wrong first: a list of meshes, a precision name, UV shapes."""
    from vrneural.atlas import build_atlas
    from vrneural.material import material_forward, random_material

    with pytest.raises(VrnError, match=r"expected a Mesh, got list .*pass one of its meshes"):
        build_atlas([builtin_mesh("plane")], 64)
    mat = random_material(0)
    d = np.tile([[0.0, 0.0, 1.0]], (2, 1))
    uv = np.zeros((2, 4, 2))
    assert material_forward(mat, d, d, uv).shape == (2, 4, 3)
    with pytest.raises(VrnError, match="precision = 'bf16' is not allowed; choose f32 or f16"):
        material_forward(mat, d, d, uv, precision="bf16")
    with pytest.raises(VrnError, match=r"uv has shape \[2, 2\], expected \[N, 4, 2\]"):
        material_forward(mat, d, d, np.zeros((2, 2)))
