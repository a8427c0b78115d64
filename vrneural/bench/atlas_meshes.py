"""The fixed mesh set of `vrneural bench atlas`, generated (deterministic), and a small GLB
writer for meshes with two UV sets.

======== ====================================================================== ===========
name     shape                                                                  triangles
======== ====================================================================== ===========
ico6     icosphere, subdivision 6, radius 0.25 m (xatlas crashes on it)         81 920
ico7     icosphere, subdivision 7                                               327 680
torus    the built-in torus                                                     9 216
knot     (2, 3) trefoil-knot tube, 320 x 32 segments, tube radius 3.5 cm        20 480
cloth    the built-in draped cloth                                              32 768
fan      a disc of 5 000 needle triangles around one centre vertex              5 000
field    a 1 x 1 m height field, 708 x 708 quads, smooth waves + fine ripples   1 002 528
lightmap a GLB torus (96 x 48) whose TEXCOORD_1 is an unwrap in three square    9 216
         islands (an asset with its own lightmap UVs); TEXCOORD_0 tiles
======== ====================================================================== ===========

``quick=True`` gives the CI-sized set: the same shapes, a few thousand triangles at most.
"""

from __future__ import annotations

import json
import struct
from pathlib import Path

import numpy as np

from vrneural.outputs import atomic_path

#: atlas resolution per mesh (full set; the quick set uses 128 or 256)
RESOLUTION = {"ico7": 2048, "field": 2048}


def _grid(nu: int, nv: int):
    from vrneural.atlas.builtin import grid_faces

    s, t = np.meshgrid(np.linspace(0, 1, nu + 1), np.linspace(0, 1, nv + 1), indexing="xy")
    return s.reshape(-1), t.reshape(-1), grid_faces(nu, nv)


def _welded(pos, faces):
    """Merge the seam duplicates of a closed grid (trimesh's exact-position merge)."""
    import trimesh

    m = trimesh.Trimesh(pos, faces, process=False)
    m.merge_vertices()
    return np.asarray(m.vertices), np.asarray(m.faces)


def icosphere(subdivisions: int):
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=0.25)
    return np.asarray(m.vertices), np.asarray(m.faces)


def knot(nu: int = 320, nv: int = 32, r: float = 0.035):
    s, t, faces = _grid(nu, nv)
    a = 2 * np.pi * s

    def curve(a):
        rad = 2.0 + np.cos(3 * a)
        return 0.1 * np.stack([rad * np.cos(2 * a), -np.sin(3 * a), rad * np.sin(2 * a)], -1)

    c = curve(a)
    tan = curve(a + 1e-4) - curve(a - 1e-4)
    tan /= np.linalg.norm(tan, axis=1, keepdims=True)
    nrm = np.cross(tan, [0.0, 1.0, 0.0])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    th = 2 * np.pi * t
    pos = c + (np.cos(th)[:, None] * nrm + np.sin(th)[:, None] * np.cross(tan, nrm)) * r
    return _welded(pos, faces)


def fan(n: int = 5000, radius: float = 0.5):
    ang = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = np.stack([radius * np.cos(ang), 0 * ang, radius * np.sin(ang)], 1)
    pos = np.concatenate([[[0.0, 0.0, 0.0]], ring])
    i = np.arange(n)
    return pos, np.stack([np.zeros(n, np.int64), 1 + (i + 1) % n, 1 + i], 1)


def field(n: int = 708):
    s, t, faces = _grid(n, n)
    h = 0.05 * np.sin(6 * s) * np.cos(5 * t) + 0.004 * np.sin(90 * s + 7 * t) * np.cos(80 * t)
    return np.stack([s - 0.5, h, t - 0.5], 1), faces


def torus_with_lightmap(nu: int = 96, nv: int = 48, ring: float = 0.3, tube: float = 0.1):
    """``(pos, faces, normals, uv0, uv1)``: a torus cut into three segments along the ring,
    each a square island of TEXCOORD_1 (side 0.47, 0.02 apart); TEXCOORD_0 = arc length /
    0.25 m (tiles the material)."""
    k = nu // 3
    parts = []
    for seg, (ox, oy) in enumerate(((0.02, 0.02), (0.51, 0.02), (0.02, 0.51))):
        s, t = np.meshgrid(
            np.linspace(seg / 3, (seg + 1) / 3, k + 1), np.linspace(0, 1, nv + 1), indexing="xy"
        )
        s, t = s.reshape(-1), t.reshape(-1)
        phi, th = 2 * np.pi * s, 2 * np.pi * t
        rad = ring + tube * np.cos(th)
        pos = np.stack([rad * np.cos(phi), tube * np.sin(th), -rad * np.sin(phi)], 1)
        nrm = np.stack([np.cos(th) * np.cos(phi), np.sin(th), -np.cos(th) * np.sin(phi)], 1)
        uv0 = np.stack([s * 2 * np.pi * ring, t * 2 * np.pi * tube], 1) / 0.25
        uv1 = np.stack([ox + 0.47 * (s * 3 - seg), oy + 0.47 * t], 1)
        from vrneural.atlas.builtin import grid_faces

        f = grid_faces(k, nv)
        f = f[:, [0, 2, 1]]  # outward
        parts.append((pos, f, nrm, uv0, uv1))
    off = np.cumsum([0] + [len(p[0]) for p in parts[:-1]])
    cat = [np.concatenate([p[j] for p in parts]) for j in range(5)]
    cat[1] = np.concatenate([p[1] + o for p, o in zip(parts, off, strict=True)])
    return tuple(cat)


def write_glb(path, pos, faces, normals=None, uv0=None, uv1=None) -> Path:
    """A one-mesh, one-node GLB: POSITION, NORMAL, TEXCOORD_0, TEXCOORD_1 (float32, each
    optional but the positions) and uint32 indices, written atomically."""
    arrays = [("POSITION", pos, "VEC3"), ("NORMAL", normals, "VEC3")]
    arrays += [("TEXCOORD_0", uv0, "VEC2"), ("TEXCOORD_1", uv1, "VEC2")]
    blob, views, accessors, attributes = b"", [], [], {}
    for name, a, kind in [*arrays, ("indices", faces, "SCALAR")]:
        if a is None:
            continue
        a = np.ascontiguousarray(a, np.uint32 if name == "indices" else np.float32)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": a.nbytes})
        acc = {
            "bufferView": len(views) - 1,
            "componentType": 5125 if name == "indices" else 5126,
            "count": a.size if name == "indices" else len(a),
            "type": kind,
        }
        if name == "POSITION":
            acc |= {"min": a.min(0).tolist(), "max": a.max(0).tolist()}
        accessors.append(acc)
        blob += a.tobytes()
        if name != "indices":
            attributes[name] = len(accessors) - 1
    doc = {
        "asset": {"version": "2.0", "generator": "vrneural bench atlas"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": Path(path).stem}],
        "meshes": [{"primitives": [{"attributes": attributes, "indices": len(accessors) - 1}]}],
        "buffers": [{"byteLength": len(blob)}],
        "bufferViews": views,
        "accessors": accessors,
    }
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    body = struct.pack("<I4s", len(text), b"JSON") + text
    body += struct.pack("<I4s", len(blob), b"BIN\0") + blob
    with atomic_path(Path(path)) as tmp:
        Path(tmp).write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)
    return Path(path)


def write_mesh(name: str, folder: Path, quick: bool) -> Path:
    """Generate bench mesh ``name`` (:data:`~vrneural.bench.configs.NAMES`) into ``folder``
    (PLY, or GLB for the one with lightmap UVs, whose normals and UV sets a PLY cannot hold);
    returns the file."""
    import trimesh

    from vrneural.atlas import builtin

    folder.mkdir(parents=True, exist_ok=True)
    if name == "lightmap":
        pos, faces, nrm, uv0, uv1 = torus_with_lightmap(*((24, 12) if quick else ()))
        return write_glb(folder / "lightmap.glb", pos, faces, nrm, uv0, uv1)
    if name in ("ico6", "ico7"):
        pos, faces = icosphere(int(name[-1]) - (3 if quick else 0))
    elif name == "torus":
        pos, faces, _ = builtin._torus(nu=24, nv=12) if quick else builtin._torus()
        pos, faces = _welded(pos, faces)
    elif name == "cloth":
        pos, faces, _ = builtin._cloth(n=24) if quick else builtin._cloth()
    else:
        small = {"knot": (64, 8), "fan": (300,), "field": (40,)}[name]
        pos, faces = {"knot": knot, "fan": fan, "field": field}[name](*(small if quick else ()))
    out = folder / f"{name}.ply"
    trimesh.Trimesh(pos, faces, process=False).export(out)
    return out
