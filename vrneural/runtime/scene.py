"""Scene files (TOML) and the built-in scene. Every error names the file and field path::

    scene.toml: objects[2].material.scale = -1 is out of range (0, inf)

Format (all lengths in metres, angles in degrees)::

    profile = "quest3"            # optional; CLI flags override the profile
    ipd = 0.063                   # optional, metres
    [head]                        # optional: "orbit" (built-in smooth path) or a CSV pose log
    path = "orbit"                # or path = "poses.csv" (rows t, x, y, z, qx, qy, qz, qw)
    [[objects]]
    mesh = "sphere"               # built-in name or a mesh file (relative to the scene file)
    position = [0, 1, 0]
    rotation = [0, 30, 0]         # XYZ Euler angles
    scale = 1.0                   # uniform
    texture_res = 1200            # optional, overrides the profile / --texture-res
    min_texture_res = 256         # optional floor under the profile's / --texture-res
    crease_angle = 60             # optional, degrees: computed normals (a mesh without its own)
                                  # are smooth across gentler bends, hard at sharper ones;
                                  # default 60 for mesh files, 180 (smooth) for built-ins
    atlas_uv = "auto"             # optional: auto (the mesh's own lightmap/UVs when they
                                  # serve), mesh (insist on them), charts or xatlas (unwrap)
    [objects.material]            # neural: pack = "x.vrnm" | procedural = "random" | "lambertian"
    pack = "leather.vrnm"         # relative to the scene file, else a bundled pack of that name
    reference = "leather.teacher.vrnm"  # optional teacher pack for --mode reference (same rule)
    scale = 4.0                   # material tiling (BTF tiles per material-UV unit)
    # ordinary: kind = "plain", albedo = [r, g, b], specular = 0.04, shininess = 32
    [[lights]]
    position = [1, 2, 1]
    colour = [1, 1, 1]
    intensity = 2.0               # W/sr
    motion = "circle"             # optional: radius, period (s), phase (rad)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from importlib.resources import files
from pathlib import Path

import numpy as np
import tomllib

from vrneural.atlas.config import MAX_RESOLUTION, MIN_RESOLUTION, MODES
from vrneural.errors import SEED_MAX, VrnError, check_choice, check_int, check_range
from vrneural.formats.vrnm import read_vrnm
from vrneural.material import NeuralMaterial, lambertian_material, random_material
from vrneural.runtime.lights import (
    MAX_INTENSITY,
    MOTIONS,
    PointLight,
    default_lights,
)
from vrneural.runtime.profiles import PROFILES
from vrneural.runtime.settings import LIGHTS_MAX


@dataclass
class MaterialDesc:
    kind: str  # "neural" | "plain"
    neural: NeuralMaterial | None = None
    source: str = ""  # pack path or procedural name
    tiling: float = 1.0
    albedo: tuple = (0.5, 0.5, 0.5)
    specular: float = 0.04
    shininess: float = 32.0
    reference: NeuralMaterial | None = None  # teacher pack used by ``--mode reference``
    reference_source: str = ""  # the teacher pack's path, when there is one
    reference_hint: str = ""  # where a missing reference was looked for (``--pack``)


@dataclass
class ObjectDesc:
    name: str
    mesh: str
    model: np.ndarray  # [4, 4] object -> world
    material: MaterialDesc
    texture_res: int | None = None
    min_texture_res: int | None = None  # floor under the profile's (dense meshes need texels)
    crease_angle: float | None = None  # degrees, for computed normals (None: the mesh's default)
    atlas_uv: str = "auto"  # the atlas's UVs: vrneural.atlas.config.MODES


@dataclass
class Scene:
    name: str
    objects: list[ObjectDesc]
    lights: list[PointLight]
    profile: str | None = None
    ipd: float | None = None
    head: str = "orbit"  # "orbit" or a pose-log path
    base: Path = field(default_factory=Path.cwd)
    src: str = "built-in scene"  # what errors name: the scene file, or the built-in scene


#: Largest |coordinate| of an object or light position and the largest object scale (metres):
#: far beyond any VR scene, and far inside float32 (what the GPU gets, after the floating origin)
MAX_COORD = 1e7
MAX_SCALE = 1e6
#: Smallest object scale: a nanometre per mesh unit. Far smaller ones vanish in float32 (below
#: about 1e-45 the model matrix became 0 and its normal matrix a singular-matrix traceback)
MIN_SCALE = 1e-9


def model_matrix(position=(0, 0, 0), rotation=(0, 0, 0), scale=1.0) -> np.ndarray:
    """Object -> world ``[4, 4]``: uniform ``scale``, XYZ Euler angles ``rotation`` in degrees
    (applied x, then y, then z), then ``position``."""
    x, y, z = np.radians(np.asarray(rotation, np.float64))
    rx = np.array([[1, 0, 0], [0, np.cos(x), -np.sin(x)], [0, np.sin(x), np.cos(x)]])
    ry = np.array([[np.cos(y), 0, np.sin(y)], [0, 1, 0], [-np.sin(y), 0, np.cos(y)]])
    rz = np.array([[np.cos(z), -np.sin(z), 0], [np.sin(z), np.cos(z), 0], [0, 0, 1]])
    m = np.eye(4)
    m[:3, :3] = rz @ ry @ rx * scale
    m[:3, 3] = position
    return m


class _Fields:
    """Typed access to one TOML table with errors naming ``file: path``."""

    def __init__(self, src: str, path: str, table: dict):
        self.src, self.path, self.t = src, path, table
        if not isinstance(table, dict):
            raise VrnError(f"{src}: {path} must be a table")

    def name(self, key: str) -> str:
        """``file: path.key``, as messages name a field."""
        return f"{self.src}: {self.path}.{key}" if self.path else f"{self.src}: {key}"

    def err(self, key: str, msg: str) -> VrnError:
        return VrnError(f"{self.name(key)} {msg}")

    def num(self, key, default=None, lo=None, hi=None, lo_open=False, integer=False):
        v = self.t.get(key, default)
        if v is None:
            raise self.err(key, "is missing")
        if isinstance(v, bool) or not isinstance(v, (int, float)) or (integer and v != int(v)):
            raise self.err(key, f"= {v!r} must be {'an integer' if integer else 'a number'}")
        check_range(self.name(key), v, lo, hi, lo_open, open_inf=True)
        return int(v) if integer else float(v)

    def vec(self, key, default=None, n=3, lo=None, bound=None):
        v = self.t.get(key, default)
        if v is None:
            raise self.err(key, "is missing")
        ok = isinstance(v, (list, tuple)) and len(v) == n
        ok = ok and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)
        if not ok or not all(math.isfinite(x) for x in v):
            raise self.err(key, f"= {v!r} must be a list of {n} finite numbers")
        if lo is not None and min(v) < lo:
            raise self.err(key, f"= {v!r} has a value below {lo:g}")
        if bound is not None and max(abs(x) for x in v) > bound:
            raise self.err(key, f"= {v!r} is out of range; each value in [-{bound:g}, {bound:g}]")
        return tuple(float(x) for x in v)

    def one_of(self, *keys) -> None:
        """At most one of ``keys`` (synonyms or exclusive choices) may be given."""
        given = [k for k in keys if k in self.t]
        if len(given) > 1:
            raise self.err(given[1], f"and {given[0]} are both given; keep one")

    def pack(self, key: str, base: Path) -> Path:
        """A .vrnm path: relative to the scene file, else a bundled pack of that name."""
        name = self.str(key)
        p = Path(name)
        here = base / p  # an absolute path stays as it is
        if not here.is_file() and p.parent == Path(".") and bundled_path(name).is_file():
            return bundled_path(name)
        if not here.is_file():
            raise self.err(key, f"= {name!r}: file not found ({here}, nor a bundled pack)")
        return here

    def str(self, key, default=None, choices=None):
        v = self.t.get(key, default)
        if v is None:
            raise self.err(key, "is missing")
        if not isinstance(v, str):
            raise self.err(key, f"= {v!r} must be a string")
        if choices is not None:
            check_choice(self.name(key), v, choices, ordered=True)
        return v

    def unknown(self, allowed) -> None:
        extra = sorted(set(self.t) - set(allowed))
        if extra:
            raise self.err(extra[0], f"is not a known field (known: {', '.join(sorted(allowed))})")


def _material(src: str, path: str, t: dict, base: Path) -> MaterialDesc:
    f = _Fields(src, path, t)
    kind = f.str("kind", "neural", ("neural", "plain"))
    if kind == "plain":
        f.unknown(("kind", "albedo", "specular", "shininess"))
        return MaterialDesc(
            "plain",
            albedo=f.vec("albedo", (0.5, 0.5, 0.5), lo=0.0),
            specular=f.num("specular", 0.04, 0.0, 1.0),
            shininess=f.num("shininess", 32.0, 0.0, 1e4, lo_open=True),
        )
    f.unknown(("kind", "pack", "procedural", "seed", "albedo", "scale", "reference"))
    f.one_of("pack", "procedural")
    tiling = f.num("scale", 1.0, 0.0, lo_open=True)

    ref, ref_src = None, ""
    if "reference" in t:
        ref_path = f.pack("reference", base)
        ref, ref_src = read_vrnm(ref_path), str(ref_path)
    if "pack" not in t and "procedural" not in t:  # never an untrained network by default
        raise VrnError(
            f'{src}: {path} needs pack = "X.vrnm" (a distilled material), procedural = '
            '"random" | "lambertian" (test materials), or kind = "plain"'
        )
    if "pack" in t:
        for k in ("seed", "albedo"):
            if k in t:
                raise f.err(k, "only applies to procedural materials, not to a pack")
        p = f.pack("pack", base)
        return MaterialDesc(
            "neural", read_vrnm(p), str(p), tiling, reference=ref, reference_source=ref_src
        )
    proc = f.str("procedural", "random", ("random", "lambertian"))
    if proc == "random":
        if "albedo" in t:
            raise f.err("albedo", 'only applies to procedural = "lambertian"')
        mat = random_material(f.num("seed", 0, 0, SEED_MAX, integer=True))  # the CLI's seeds
    else:
        if "seed" in t:
            raise f.err("seed", 'only applies to procedural = "random"')
        mat = lambertian_material(f.vec("albedo", (0.8, 0.5, 0.2), lo=0.0))
    return MaterialDesc("neural", mat, proc, tiling, reference=ref, reference_source=ref_src)


#: the fields of an [[objects]] table: ObjectDesc's, its model as position, rotation and scale
OBJECT_KEYS = {f.name for f in fields(ObjectDesc)} - {"model"} | {"position", "rotation", "scale"}
#: the fields of a [[lights]] table: PointLight's, "color" as well as "colour"
LIGHT_KEYS = {f.name for f in fields(PointLight)} | {"color"}


def parse_scene(data: dict, src: str, base: Path) -> Scene:
    top = _Fields(src, "", data)
    top.unknown(("name", "profile", "ipd", "head", "objects", "lights"))

    profile = top.str("profile", None, tuple(PROFILES)) if "profile" in data else None
    ipd = top.num("ipd", 0.063, 0.0, 0.2) if "ipd" in data else None
    head = "orbit"
    if "head" in data:
        h = _Fields(src, "head", data["head"])
        h.unknown(("path",))
        head = h.str("path", "orbit")
        if head != "orbit":
            p = base / head  # an absolute path stays as it is
            if not p.is_file():
                raise h.err(
                    "path", f"= {head!r}: pose log not found ({p}); the built-in path is orbit"
                )
            head = str(p)
    objs_raw = data.get("objects", [])
    if not isinstance(objs_raw, list) or not objs_raw:
        raise VrnError(f"{src}: objects must be a non-empty array of tables ([[objects]])")
    objects, taken = [], set()  # taken: the object names given so far
    for i, o in enumerate(objs_raw):
        f = _Fields(src, f"objects[{i}]", o)
        f.unknown(OBJECT_KEYS)
        mesh = f.str("mesh")
        atlas_uv = f.str("atlas_uv", "auto", MODES)
        crease = f.num("crease_angle", 0.0, 0.0, 180.0) if "crease_angle" in o else None
        model = model_matrix(
            f.vec("position", (0, 0, 0), bound=MAX_COORD),
            f.vec("rotation", (0, 0, 0), bound=1e6),
            f.num("scale", 1.0, MIN_SCALE, MAX_SCALE),
        )
        mat = _material(src, f"objects[{i}].material", o.get("material", {}), base)
        tres, floor = (_texture_res(f, k) for k in ("texture_res", "min_texture_res"))
        if mat.kind == "plain" and (tres or floor):
            key = "texture_res" if tres else "min_texture_res"
            raise f.err(key, "is set on a plain object; only neural ones have a radiance texture")
        if tres is not None and floor is not None and floor > tres:
            raise f.err(
                "min_texture_res",
                f"= {floor} is above texture_res = {tres}: texture_res sets this object's "
                "size, min_texture_res is a floor under the profile's; keep one",
            )
        if "name" in o:
            name = f.str("name")
            if name in taken:
                raise f.err("name", f"= {name!r} is already another object's; names are unique")
        else:  # the mesh's stem (and part: "room:chair"), numbered where several objects
            # show one mesh: "sphere 2"
            file, colon, part = Path(mesh).name.partition(":")
            name = stem = Path(file).stem + colon + part
            k = 1
            while name in taken:
                k += 1
                name = f"{stem} {k}"
        taken.add(name)
        if atlas_uv != "auto" and mat.kind == "plain":
            raise f.err("atlas_uv", "is set on a plain object; only neural ones have an atlas")
        objects.append(ObjectDesc(name, mesh, model, mat, tres, floor, crease, atlas_uv))
    lights = []
    if not isinstance(data.get("lights", []), list):
        raise VrnError(f"{src}: lights must be an array of tables ([[lights]])")
    for i, lt in enumerate(data.get("lights", [])):
        f = _Fields(src, f"lights[{i}]", lt)
        f.unknown(LIGHT_KEYS)
        f.one_of("colour", "color")
        colour = f.vec("colour" if "colour" in lt else "color", (1, 1, 1), lo=0.0)
        intensity = f.num("intensity", 1.0, 0.0, MAX_INTENSITY)
        if max(colour) * intensity > MAX_INTENSITY:  # docs/extremes.md
            raise f.err("intensity", f"* colour = {max(colour) * intensity:g} W/sr is above 1e6")
        motion = f.str("motion", "none", MOTIONS)
        idle = [k for k in ("radius", "period", "phase") if k in lt]
        if motion == "none" and idle:
            raise f.err(
                idle[0],
                f'is given but the light does not move; add motion = "circle" or drop '
                f"{', '.join(idle)}",
            )
        lights.append(
            PointLight(
                f.vec("position", bound=MAX_COORD),
                colour,
                intensity,
                motion,
                f.num("radius", 0.0, 0.0, MAX_COORD),
                f.num("period", 8.0, 0.0, lo_open=True),
                f.num("phase", 0.0),
            )
        )
    name = top.str("name", Path(src).stem)
    return Scene(name, objects, lights, profile, ipd, head, base, src)


def _texture_res(f: _Fields, key: str) -> int | None:
    """An object's ``texture_res`` / ``min_texture_res``: even, in the atlas stage's range."""
    if key not in f.t:
        return None
    v = f.num(key, None, MIN_RESOLUTION, MAX_RESOLUTION, integer=True)
    if v % 2:
        raise f.err(key, f"= {v} must be even (2x2 blocks)")
    return v


def load_scene(path: str | Path) -> Scene:
    p = Path(path)
    if p.is_dir():
        raise VrnError(f"{p}: is a directory, expected a scene file (TOML)")
    if not p.is_file():
        raise VrnError(f"{p}: scene file not found")
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8-sig"))  # a BOM (Windows editors) too
    except tomllib.TOMLDecodeError as e:
        raise VrnError(f"{p}: invalid TOML ({e})") from None
    except UnicodeDecodeError:
        from vrneural.atlas.io import MESH_SUFFIXES

        hint = ""
        if p.suffix.lower() == ".vrnm":
            hint = "; a runtime pack goes to --pack (the built-in scene with that material)"
        elif p.suffix.lower() in MESH_SUFFIXES:
            hint = "; a mesh goes into a scene file's [[objects]] mesh = ..."
        raise VrnError(f"{p}: not a text file (a scene is TOML){hint}") from None
    return parse_scene(data, str(p), p.parent.resolve())  # messages name it as given


#: Materials of the built-in scene: packs bundled in ``vrneural/data/materials`` (trained by
#: ``demo/make_assets.py``; ``<name>.teacher.vrnm`` is the per-pixel reference of ``--mode
#: reference``), ``scale`` = BTF tiles per material-UV unit (mesh UVs are in metres).
BUILTIN_MATERIALS = {
    "leather": {"pack": "leather.vrnm", "scale": 2.5},
    "fabric": {"pack": "fabric.vrnm", "scale": 2.0},
    "wood": {"pack": "wood.vrnm", "scale": 1.5},
}


def bundled_path(name: str) -> Path:
    """Where the bundled pack ``name`` (like ``"leather.vrnm"``) lives, present or not."""
    return Path(str(files("vrneural") / "data" / "materials" / name))


def builtin_pack(name: str) -> Path:
    """Path of a bundled pack (``name`` like ``"leather.vrnm"``); one-line error if missing."""
    p = bundled_path(name)
    if not p.is_file():
        raise VrnError(
            f"built-in scene: material pack {p} is missing; rebuild the bundled packs with "
            "`.venv/bin/python demo/make_assets.py` (about 15 min) or reinstall vrneural"
        )
    return p


def builtin_material(key: str) -> MaterialDesc:
    """The bundled student pack ``key`` with its teacher attached as ``.reference``."""
    spec = BUILTIN_MATERIALS[key]
    stem = spec["pack"].removesuffix(".vrnm")
    pack = Path(str(builtin_pack(spec["pack"])))
    # sources by path, as for a scene's or --pack's packs (summary.json had bare names here)
    desc = MaterialDesc("neural", read_vrnm(pack), str(pack), spec["scale"])
    teacher = pack.with_name(f"{stem}.teacher.vrnm")
    if teacher.is_file():
        desc.reference, desc.reference_source = read_vrnm(teacher), str(teacher)
    return desc


def builtin_lights() -> list[PointLight]:
    """Key (warm, front left), fill (cool, right) and a slowly circling back light (12 s)."""
    return [
        PointLight((-1.0, 2.0, 1.3), (1.0, 0.93, 0.85), 4.5),
        PointLight((1.4, 1.5, 0.9), (0.85, 0.9, 1.0), 2.2),
        PointLight((0.0, 1.9, -0.4), (1.0, 0.85, 0.7), 3.0, "circle", 0.9, 12.0, 0.0),
    ]


def builtin_scene(n_lights: int = 3) -> Scene:
    """The demo: a leather sphere, a draped fabric cloth and a wood torus (bundled neural packs)
    on a plain floor; the first ``n_lights`` of three point lights (one circling slowly), the
    quest3 profile and the built-in head orbit. Same as ``demo/scene.toml``."""
    from vrneural.runtime.assets import get_mesh

    check_int("builtin_scene: n_lights", n_lights, 0, LIGHTS_MAX)  # `run --lights`' range

    def fit(name: str, size: float) -> float:  # scale so the mesh's largest extent is ``size``
        p = get_mesh(name).positions
        return size / float((p.max(0) - p.min(0)).max())

    floor = MaterialDesc("plain", albedo=(0.32, 0.32, 0.34), specular=0.03, shininess=24.0)
    m = builtin_material
    objects = [
        ObjectDesc(
            "leather sphere",
            "sphere",
            model_matrix((-0.55, 0.78, -0.15), (0, 0, 0), 1.4),
            m("leather"),
        ),
        ObjectDesc(
            "fabric cloth",
            "cloth",
            model_matrix((0.0, 0.34, -0.2), (0, 20, 0), 1.7),
            m("fabric"),
            min_texture_res=256,  # its 32768 triangles need texels: at 128^2 most would own none
        ),
        ObjectDesc(
            "wood torus", "torus", model_matrix((0.55, 0.85, -0.1), (60, 0, 0), 0.8), m("wood")
        ),
        ObjectDesc("floor", "plane", model_matrix((0, 0, 0), (0, 0, 0), fit("plane", 6.0)), floor),
    ]
    lights = builtin_lights()
    if n_lights > len(lights):
        lights += default_lights(n_lights)[len(lights) :]
    return Scene(
        "builtin", objects, lights[: max(n_lights, 0)], "quest3", None, "orbit", Path.cwd()
    )
