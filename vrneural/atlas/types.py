"""The data the atlas stage hands to the runtime. Conventions (shared with the runtime shaders):

- positions in metres, object space; normals unit; directions follow docs/conventions.md section 1.
- ``tangents[:, :3]`` is the unit tangent along increasing *material* u, orthogonalised against
  the normal; ``tangents[:, 3]`` is +-1 and the bitangent is ``w * cross(n, t)``.
- Atlas UVs are in [0, 1]; radiance texel ``(x, y)`` (column x, row y, row 0 first in memory)
  has its centre at atlas UV ``((x + 0.5) / R, (y + 0.5) / R)``. No v flip anywhere: the forward
  pass samples the radiance texture at the interpolated atlas UV directly.
- A mesh's own UVs become the atlas when they serve (``build_atlas(uv="auto")``, see
  :mod:`vrneural.atlas.meshuv`): ``lightmap_uv``, else ``uv`` when ``uv_source == "file"``.
- ``tri_ids[y, x]`` is the index of a row of ``mesh.faces`` (uint32), ``EMPTY`` where no
  triangle covers the texel or its gutter.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

EMPTY = np.uint32(0xFFFFFFFF)


@dataclass
class Mesh:
    """A triangle mesh with material UVs and a shading frame per vertex."""

    name: str
    positions: np.ndarray  # [V, 3] float32, metres
    faces: np.ndarray  # [F, 3] uint32
    normals: np.ndarray  # [V, 3] float32, unit
    tangents: np.ndarray  # [V, 4] float32: unit tangent (+u of material UV), bitangent sign
    uv: np.ndarray  # [V, 2] float32, material UV (one BTF tile per unit, before tiling scale)
    #: [V, 2] float32: the asset's own lightmap UV set (glTF ``TEXCOORD_1``), or None
    lightmap_uv: np.ndarray | None = None
    #: where ``uv`` came from: "file" (the asset's, e.g. glTF ``TEXCOORD_0`` or OBJ ``vt``),
    #: "builtin" (a built-in mesh's arc-length UVs) or "box" (box projection)
    uv_source: str = "file"


@dataclass
class Atlas:
    """A mesh re-indexed for its atlas (vertices split at chart seams) plus its triangle IDs."""

    mesh: Mesh  # vertices duplicated where charts split; faces keep the input order
    uv_atlas: np.ndarray  # [V, 2] float32 in [0, 1], one per vertex of ``mesh``
    tri_ids: np.ndarray  # [R, R] uint32, EMPTY outside triangles and their gutter
    resolution: int
    padding: int
    stats: dict = field(default_factory=dict)
