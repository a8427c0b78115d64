"""A pass's GPU interface, declared once in Python: its bindings and its uniform structs.

A :class:`Struct` is a WGSL struct whose host mirror is a structured numpy dtype with the WGSL
layout (the alignment and size rules of the uniform address space: ``vec3`` aligned to 16,
matrix columns padded to ``vec4``, array strides and struct alignment multiples of 16), as
pygfx does with its ``array_from_shadertype``: host code writes fields by name and the WGSL
declaration is generated from the same table. A :class:`Bindings` is one bind group's list of
:class:`Binding` (slot, WGSL name, kind, WGSL type): it writes the WGSL ``var`` declarations
that the templates include, and the wgpu bind-group entries (by name) and bind-group-layout
entries, so a binding number is written in exactly one place.

Host layout of the WGSL types (``[...]`` = numpy shape of the field, float32 unless noted):
``f32`` / ``u32`` / ``i32`` scalars; ``vecN`` ``[N]``; ``matCxR`` ``[C, 4 if R == 3 else R]``
(column-major: ``field[c, r]``, write ``M.T`` for a numpy row-major matrix); ``array<E, N>``
``[N, ...]`` (elements padded to the stride); a struct field a nested record.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

_SCALARS = {"f32": "<f4", "u32": "<u4", "i32": "<i4"}


def _round(n: int, k: int) -> int:
    return -(-n // k) * k


@dataclass(frozen=True)
class _Layout:
    align: int
    size: int
    dtype: np.dtype


class Struct:
    """A WGSL struct for the uniform address space. ``fields``: ``(name, wgsl type or Struct)``
    or ``(name, type, comment)``; :attr:`dtype` is its host mirror (``itemsize`` = WGSL size)."""

    def __init__(self, name: str, fields: list[tuple]):
        self.name = name
        self.fields = [(f[0], f[1], f[2] if len(f) > 2 else "") for f in fields]
        names, formats, offsets, off, align = [], [], [], 0, 16
        for fname, ftype, _ in self.fields:
            lay = layout_of(ftype)
            off = _round(off, lay.align)
            names.append(fname)
            formats.append(lay.dtype)
            offsets.append(off)
            off += lay.size
            align = max(align, lay.align)
        self.align = align
        self.size = _round(off, align)
        self.dtype = np.dtype(
            {"names": names, "formats": formats, "offsets": offsets, "itemsize": self.size}
        )

    def wgsl(self) -> str:
        """The WGSL declaration (field comments kept)."""
        lines = [f"struct {self.name} {{"]
        for fname, ftype, comment in self.fields:
            t = ftype.name if isinstance(ftype, (Struct, ArrayOf)) else ftype
            lines.append(f"    {fname}: {t},{'  // ' + comment if comment else ''}")
        return "\n".join([*lines, "}"])

    def zeros(self, n: int | None = None) -> np.ndarray:
        """A zeroed record (``n``: an array of them)."""
        return np.zeros(() if n is None else n, self.dtype)

    def view(self, raw: np.ndarray) -> np.ndarray:
        """The records in the bytes ``raw`` (e.g. a uniform arena's region), writable in place:
        ``s.view(buf)[0]["eye"] = ...``; ``[n]`` records for ``n * size`` bytes."""
        return raw.view(np.uint8).view(self.dtype)


@dataclass(frozen=True)
class ArrayOf:
    """``array<Struct, n>`` (a WGSL array of a :class:`Struct`, e.g. a uniform's lights)."""

    struct: Struct
    n: int

    @property
    def name(self) -> str:
        return f"array<{self.struct.name}, {self.n}>"


def layout_of(t) -> _Layout:
    """Alignment, size and host dtype of WGSL type ``t`` (a string, a :class:`Struct` or an
    :class:`ArrayOf`) in the uniform address space."""
    if isinstance(t, Struct):
        return _Layout(t.align, t.size, t.dtype)
    if isinstance(t, ArrayOf):  # struct sizes are multiples of 16: the stride is the size
        return _Layout(t.struct.align, t.n * t.struct.size, np.dtype((t.struct.dtype, (t.n,))))
    t = t.replace(" ", "")
    if t in _SCALARS:
        return _Layout(4, 4, np.dtype(_SCALARS[t]))
    m = re.fullmatch(r"vec([234])<(f32|u32|i32)>", t)
    if m:
        n = int(m[1])
        return _Layout(8 if n == 2 else 16, 4 * n, np.dtype((_SCALARS[m[2]], (n,))))
    m = re.fullmatch(r"mat([234])x([234])<f32>", t)
    if m:
        c, r = int(m[1]), int(m[2])
        col = 8 if r == 2 else 16  # a column is a vecR: its alignment is its stride
        return _Layout(col, c * col, np.dtype(("<f4", (c, col // 4))))
    m = re.fullmatch(r"array<(.+),(\d+)>", t)
    if m:
        el, n = layout_of(m[1]), int(m[2])
        stride = _round(_round(el.size, el.align), 16)  # uniform arrays: 16-byte strides
        if stride == el.size:  # structs (sizes are multiples of 16), vec4, mat4x4, ...
            dt = np.dtype((el.dtype, (n,)))
        elif el.dtype.names is None and len(el.dtype.shape) <= 1:  # a scalar / vector, padded
            base = el.dtype.subdtype[0] if el.dtype.subdtype else el.dtype
            dt = np.dtype((base, (n, stride // 4)))
        else:
            raise ValueError(f"WGSL type {t!r}: no host layout for this array's padding")
        return _Layout(max(16, el.align), n * stride, dt)
    raise ValueError(f"WGSL type {t!r} has no host layout here")


#: binding kinds -> the address space of their WGSL ``var`` (resources have none)
KINDS = {
    "uniform": "<uniform>",
    "storage": "<storage, read>",
    "storage_rw": "<storage, read_write>",
    "texture": "",
    "storage_texture": "",
    "sampler": "",
}


@dataclass(frozen=True)
class Binding:
    """One resource of a bind group: ``slot`` (binding number), WGSL ``name``, ``kind`` (one of
    :data:`KINDS`), WGSL ``type`` (a string or a :class:`Struct`) and a comment for the WGSL.
    ``sample_type``: a sampled texture's wgpu sample type when not the type's default
    (``"unfilterable-float"`` for an r32float texture). ``dynamic``: a buffer bound with a
    dynamic offset (one bind group serving many draws' uniforms)."""

    slot: int
    name: str
    kind: str
    type: object
    comment: str = ""
    sample_type: str | None = None
    dynamic: bool = False

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"binding kind {self.kind!r} not in {tuple(KINDS)}")

    @property
    def type_name(self) -> str:
        return self.type.name if isinstance(self.type, (Struct, ArrayOf)) else str(self.type)

    def wgsl(self, group: int = 0) -> str:
        decl = f"@group({group}) @binding({self.slot}) var{KINDS[self.kind]} {self.name}: "
        return decl + self.type_name + ";" + (f"  // {self.comment}" if self.comment else "")

    def layout_entry(self, visibility, sized: bool = False) -> dict:
        """The wgpu bind-group-layout entry; ``sized``: a uniform's ``min_binding_size`` from
        its host layout (wgpu then checks it against the shader's size of the type)."""
        t = self.type_name.replace(" ", "")
        if self.kind == "uniform":
            res = {"buffer": {"type": "uniform"}}
            if sized:
                res["buffer"]["min_binding_size"] = layout_of(self.type).size
        elif self.kind in ("storage", "storage_rw"):
            ty = "read-only-storage" if self.kind == "storage" else "storage"
            res = {"buffer": {"type": ty}}
        elif self.kind == "texture":
            m = re.fullmatch(r"texture_(2d|2d_array|3d|cube)<(f32|u32|i32)>", t)
            st = {"f32": "float", "u32": "uint", "i32": "sint"}[m[2]]
            res = {"texture": {"sample_type": self.sample_type or st,
                               "view_dimension": m[1].replace("_", "-")}}  # fmt: skip
        elif self.kind == "storage_texture":
            m = re.fullmatch(r"texture_storage_(2d|2d_array|3d)<(\w+),(write|read|read_write)>", t)
            access = {"write": "write-only", "read": "read-only", "read_write": "read-write"}[m[3]]
            res = {"storage_texture": {"access": access, "format": m[2],
                                       "view_dimension": m[1].replace("_", "-")}}  # fmt: skip
        else:
            res = {"sampler": {"type": self.sample_type or "filtering"}}
        if self.dynamic:
            res["buffer"]["has_dynamic_offset"] = True
        return {"binding": self.slot, "visibility": visibility, **res}


class Bindings:
    """One bind group's bindings, by name; slots must be unique."""

    def __init__(self, bindings, group: int = 0):
        self.group = group
        self.items = [b for b in bindings if b is not None]
        self.by_name = {b.name: b for b in self.items}
        slots = [b.slot for b in self.items]
        if len(set(slots)) != len(slots) or len(self.by_name) != len(self.items):
            raise ValueError(f"bind group {group}: a slot or name twice in {self.items}")

    def wgsl(self, names=None) -> str:
        """The WGSL declarations (of ``names`` only, in list order, when given)."""
        keep = self.items if names is None else [b for b in self.items if b.name in names]
        return "\n".join(b.wgsl(self.group) for b in keep)

    def entries(self, resources: dict, names=None) -> list[dict]:
        """Bind-group entries for ``resources`` (name -> wgpu resource): those named in
        ``names`` (all by default; an entry point's auto layout holds only the bindings it
        uses), in declaration order."""
        names = list(resources) if names is None else names
        missing = [n for n in names if n not in self.by_name]
        if missing:
            raise KeyError(f"no binding named {missing} in bind group {self.group}")
        want = set(names)
        return [
            {"binding": b.slot, "resource": resources[b.name]} for b in self.items if b.name in want
        ]

    def layout_entries(self, visibility, names=None, sized: bool = False) -> list[dict]:
        """Bind-group-layout entries (all bindings, or ``names``) with ``visibility`` (shader
        stage flags, or a dict of them by binding name); ``sized``: see
        :meth:`Binding.layout_entry`."""
        keep = self.items if names is None else [b for b in self.items if b.name in names]
        vis = visibility if isinstance(visibility, dict) else {b.name: visibility for b in keep}
        return [b.layout_entry(vis[b.name], sized) for b in keep]
