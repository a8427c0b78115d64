"""Meshes, unique atlas UVs (the mesh's own lightmap UVs, or generated charts) and triangle-ID
textures with gutters.

Public API (used by the runtime): :func:`load_mesh`, :func:`builtin_mesh`,
:data:`BUILTIN_MESHES`, :func:`build_atlas`, :func:`texel_barycentrics`, and the contract types
:class:`Mesh`, :class:`Atlas`, :data:`EMPTY`. Conventions are in :mod:`vrneural.atlas.types`.
"""

from vrneural import lazy_exports
from vrneural.atlas.config import MAX_RESOLUTION, AtlasConfig

_FROM = {
    "BUILTIN_MESHES": "builtin",
    "EMPTY": "types",
    "Atlas": "types",
    "Mesh": "types",
    "MeshWarning": "geometry",
    "build_atlas": "build",
    "builtin_mesh": "builtin",
    "load_mesh": "io",
    "make_mesh": "geometry",
    "texel_barycentrics": "raster",
}
__all__ = ["MAX_RESOLUTION", "AtlasConfig", *_FROM]
__getattr__ = lazy_exports(__name__, _FROM)  # numpy (build_atlas: scipy) on first use
