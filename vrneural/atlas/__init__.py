"""Meshes, unique atlas UVs (the mesh's own lightmap UVs, or generated charts) and triangle-ID
textures with gutters.

Public API (used by the runtime): :func:`load_mesh`, :func:`builtin_mesh`,
:data:`BUILTIN_MESHES`, :func:`build_atlas`, :func:`texel_barycentrics`, and the contract types
:class:`Mesh`, :class:`Atlas`, :data:`EMPTY`. Conventions are in :mod:`vrneural.atlas.types`.
"""

from vrneural.atlas.builtin import BUILTIN_MESHES, builtin_mesh
from vrneural.atlas.config import MAX_RESOLUTION, AtlasConfig
from vrneural.atlas.geometry import MeshWarning, make_mesh
from vrneural.atlas.io import load_mesh
from vrneural.atlas.raster import texel_barycentrics
from vrneural.atlas.types import EMPTY, Atlas, Mesh

__all__ = [
    "BUILTIN_MESHES",
    "EMPTY",
    "MAX_RESOLUTION",
    "Atlas",
    "AtlasConfig",
    "Mesh",
    "MeshWarning",
    "build_atlas",
    "builtin_mesh",
    "load_mesh",
    "make_mesh",
    "texel_barycentrics",
]


def __getattr__(name: str):  # build_atlas loads scipy: on first use, not with the package
    if name == "build_atlas":
        from vrneural.atlas.build import build_atlas

        return build_atlas
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
