"""Meshes, unique atlas UVs (the mesh's own lightmap UVs, or generated charts) and triangle-ID
textures with gutters.

Public API (used by the runtime): :func:`load_mesh`, :func:`builtin_mesh`,
:data:`BUILTIN_MESHES`, :func:`build_atlas`, :func:`texel_barycentrics`, and the contract types
:class:`Mesh`, :class:`Atlas`, :data:`EMPTY`. Conventions are in :mod:`vrneural.atlas.types`.
"""

from vrneural.atlas.build import MAX_RESOLUTION, AtlasConfig, build_atlas
from vrneural.atlas.builtin import BUILTIN_MESHES, builtin_mesh
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
