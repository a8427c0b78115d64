"""On-disk cache of built atlases, in the versioned container format (no pickle).

Key: SHA-256 over the mesh content (positions, faces, normals, tangents, material UV and its
source, the lightmap UV set: dtype, shape and bytes), the resolution, the padding, the UV choice
(``auto``, ``mesh``, ``charts``, ``xatlas``) and :data:`ATLAS_CODE_VERSION` (bump it whenever
the unwrap or rasterization rules change, so stale entries are never reused). Any change to a
vertex, a face or a shading attribute changes the key.

Location: ``$VRNEURAL_CACHE/atlas`` when ``VRNEURAL_CACHE`` is set, else
``~/.cache/vrneural/atlas``. One file ``<key>.vrna`` per entry, written to a unique temporary
name and renamed into place (atomic; concurrent builders of one key are harmless). A corrupt,
truncated or inconsistent entry is reported with a warning, rebuilt and overwritten, never fatal.
"""

from __future__ import annotations

import hashlib
import os
import warnings
from pathlib import Path

import numpy as np

from vrneural.atlas.types import Atlas, Mesh
from vrneural.errors import VrnError
from vrneural.formats.container import read_container, write_container
from vrneural.outputs import atomic_path
from vrneural.warn import VrnWarning

ATLAS_CODE_VERSION = 6
MAGIC = b"VRNATLAS"
FORMAT_VERSION = 1


class CacheWarning(VrnWarning):
    """A cache entry could not be used (it is rebuilt), or could not be written; printed as one
    line, ``warning: <message>`` (:mod:`vrneural.warn`)."""


def cache_dir() -> Path:
    """The atlas cache directory (not created here)."""
    root = os.environ.get("VRNEURAL_CACHE")
    base = Path(root).expanduser() if root else Path.home() / ".cache" / "vrneural"
    return base / "atlas"


def cache_key(mesh: Mesh, resolution: int, padding: int, uv: str = "auto") -> str:
    """Hex SHA-256 of mesh content + resolution + padding + UV choice + code version."""
    h = hashlib.sha256()
    h.update(f"vrneural-atlas v{ATLAS_CODE_VERSION} R={resolution} pad={padding}\n".encode())
    if uv != "auto" or mesh.lightmap_uv is not None or mesh.uv_source != "file":
        h.update(f"atlas_uv={uv} uv_source={mesh.uv_source}\n".encode())
    for name in ("positions", "faces", "normals", "tangents", "uv", "lightmap_uv"):
        if getattr(mesh, name) is None:
            continue
        a = np.ascontiguousarray(getattr(mesh, name))
        h.update(f"{name} {a.dtype.str} {a.shape}\n".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def cache_path(key: str) -> Path:
    return cache_dir() / f"{key}.vrna"


def load_cached(mesh: Mesh, key: str, resolution: int, padding: int) -> Atlas | None:
    """The cached atlas for ``key``, or None when absent or unusable (warned, rebuilt)."""
    path = cache_path(key)
    if not path.exists():
        return None
    try:
        header, arrays, _ = read_container(
            path, MAGIC, (FORMAT_VERSION,), what="vrneural atlas cache"
        )
        vmap = np.asarray(arrays["vmap"], dtype=np.int64)
        faces = np.array(arrays["faces"])
        uv = np.array(arrays["uv_atlas"])
        ids = np.array(arrays["tri_ids"])
        ok = (
            header.get("key") == key
            and ids.shape == (resolution, resolution)
            and faces.shape == mesh.faces.shape
            and len(uv) == len(vmap)
            and (len(vmap) == 0 or (vmap.min() >= 0 and vmap.max() < len(mesh.positions)))
            and (faces.size == 0 or faces.max() < len(vmap))
        )
        if not ok:
            raise VrnError(f"{path}: cache entry does not match its key")
    except (VrnError, KeyError, ValueError, OSError) as e:
        warnings.warn(f"atlas cache: {e}; rebuilding", CacheWarning, stacklevel=3)
        return None
    # the key is the geometry, not the name: the same mesh under another name hits
    stats = dict(header.get("stats", {}), cache="hit", cache_file=str(path), mesh=mesh.name)
    return Atlas(
        mesh=split_mesh(mesh, vmap, faces),
        uv_atlas=uv,
        tri_ids=ids,
        resolution=resolution,
        padding=padding,
        stats=stats,
    )


def store(atlas: Atlas, vmap: np.ndarray, key: str) -> Path | None:
    """Write an entry atomically; where it cannot be written, warn and return None."""
    path = cache_path(key)
    try:
        with atomic_path(path) as tmp:
            write_container(
                tmp,
                MAGIC,
                FORMAT_VERSION,
                {"key": key, "code_version": ATLAS_CODE_VERSION, "stats": atlas.stats},
                {
                    "vmap": vmap.astype(np.int64),
                    "faces": atlas.mesh.faces,
                    "uv_atlas": atlas.uv_atlas,
                    "tri_ids": atlas.tri_ids,
                },
            )
    except (OSError, VrnError) as e:
        warnings.warn(f"atlas cache: cannot write {path} ({e})", CacheWarning, stacklevel=3)
        return None
    return path


def split_mesh(mesh: Mesh, vmap: np.ndarray, faces: np.ndarray) -> Mesh:
    """``mesh`` with vertex ``i`` copied from ``vmap[i]`` and faces re-indexed to ``faces``."""
    return Mesh(
        name=mesh.name,
        positions=mesh.positions[vmap],
        faces=np.asarray(faces, dtype=np.uint32),
        normals=mesh.normals[vmap],
        tangents=mesh.tangents[vmap],
        uv=mesh.uv[vmap],
        lightmap_uv=None if mesh.lightmap_uv is None else mesh.lightmap_uv[vmap],
        uv_source=mesh.uv_source,
    )
