"""Meshes for the runtime (from :mod:`vrneural.atlas`), and the warnings `run` and `atlas` give
about an atlas's triangles."""

from __future__ import annotations

from pathlib import Path

from vrneural.atlas.types import Mesh
from vrneural.errors import VrnError

#: Fraction of a mesh's triangles that may own no atlas texel before `run` and `atlas` warn
LOST_TRIANGLES = 0.5


def lost_triangles(stats: dict, res: int, shown_as: str) -> str | None:
    """The warning for an atlas (its ``stats``) in which more than :data:`LOST_TRIANGLES` of
    the triangles own no texel at ``res``^2, else None; ``shown_as`` says what those triangles
    show instead."""
    lost, n_tri = int(stats.get("triangles_without_texels", 0)), int(stats.get("triangles", 0))
    if not n_tri or lost <= LOST_TRIANGLES * n_tri:
        return None
    return (
        f"{lost} of {n_tri} triangles own no texel at {res}^2 (too small in the atlas; {shown_as})"
    )


def collapsed_triangles(stats: dict) -> str | None:
    """The warning for an atlas (its ``stats``) in which xatlas gave triangles no area (each
    far smaller than the mesh, or degenerate), else None. Unlike texel-less triangles this is
    not a matter of resolution: every such triangle shows the one texel its uvs fall on."""
    n, n_tri = int(stats.get("zero_area_triangles", 0)), int(stats.get("triangles", 0))
    if not n:
        return None
    return (
        f"{n} of {n_tri} triangles have no area in the atlas (far smaller than the rest of the "
        "mesh, so xatlas flattened them; each shows one texel's shading at any resolution): "
        "make such small parts separate objects or meshes"
    )


def get_mesh(
    spec: str, base: Path | None = None, field: str = "mesh", crease_deg: float | None = None
) -> Mesh:
    """A built-in mesh by name, or a mesh file (relative to ``base``).

    ``crease_deg``: the crease angle for computed normals (None: smooth built-ins, 60 degrees
    for files without normals; see :mod:`vrneural.atlas.geometry`).

    A file holding several meshes (a glTF scene, say) needs the one to use named after a
    colon, ``"room.glb:chair"`` (the names ``vrneural atlas`` prints), or its index,
    ``"room.glb:0"``.
    """
    from vrneural.atlas import BUILTIN_MESHES, builtin_mesh, load_mesh

    if spec in BUILTIN_MESHES:
        return builtin_mesh(spec, crease_deg)

    def where(s: str) -> Path:
        p = Path(s)
        return base / p if base is not None and not p.is_absolute() else p

    p, part = where(spec), None
    if not p.is_file() and ":" in spec:
        head, tail = spec.rsplit(":", 1)
        if where(head).is_file():
            p, part = where(head), tail
    if not p.is_file():
        looked = f"no such file ({p})" if base is not None and str(p) != spec else "no such file"
        raise VrnError(
            f"{field} = {spec!r}: {looked} and not a built-in mesh ({', '.join(BUILTIN_MESHES)})"
        )
    meshes = load_mesh(p, crease_deg)
    names = [m.name.split(":", 1)[1] if ":" in m.name else str(i) for i, m in enumerate(meshes)]
    if part is None:
        if len(meshes) == 1:
            return meshes[0]
        raise VrnError(
            f"{field} = {spec!r} holds {len(meshes)} meshes ({', '.join(names[:6])}"
            f"{', ...' if len(names) > 6 else ''}); name one, e.g. "
            f"{spec + ':' + names[0]!r}, one object each"
        )
    if len(meshes) == 1 and part != "0" and part not in names:
        raise VrnError(
            f"{field} = {spec!r}: {p.name} holds one mesh (its objects are merged on loading); "
            f"write {spec.rsplit(':', 1)[0]!r}"
        )
    if part in names:
        return meshes[names.index(part)]
    if part.isdigit() and int(part) < len(meshes):
        return meshes[int(part)]
    raise VrnError(
        f"{field} = {spec!r}: {p.name} has no mesh {part!r}; it has {', '.join(names[:6])}"
        f"{', ...' if len(names) > 6 else ''} (or an index 0-{len(meshes) - 1})"
    )
