"""The GPU interface of the shading passes, declared once: their uniform structs and bind
groups (:mod:`vrneural.gpu.bindings`). The WGSL declarations are generated from these tables
and included by the templates (``texture_space.wgsl``, ``screen_space.wgsl``,
``forward.wgsl``); the host writes the same structs by field name and binds resources by
binding name, so a binding number or a uniform offset is written here and nowhere else.
"""

from __future__ import annotations

from vrneural.gpu.bindings import ArrayOf, Binding, Bindings, Struct

#: one point light (texture, screen and forward passes)
LIGHT = Struct(
    "Light",
    [("pos", "vec4<f32>", "world position, metres (relative to the shaded eye where noted)"),
     ("radiance", "vec4<f32>", "colour * intensity, W/sr")],
)  # fmt: skip

#: the texture-space pass's per-dispatch uniform
TEXTURE_PARAMS = Struct(
    "Params",
    [
        ("model", "mat4x4<f32>", "object -> world (camera-relative: the eye at the origin)"),
        ("normal_mat", "mat4x4<f32>", "inverse transpose of the model's 3x3 (upper-left)"),
        ("eye", "vec4<f32>", "eye position (camera-relative: 0); w: facing margin, metres"),
        ("tiling", "vec4<f32>", "material uv = uv * tiling.xy + tiling.zw"),
        ("sched", "vec4<u32>", "(candidate list offset, candidate count, counter slot, unused)"),
        ("lod", "vec4<f32>", "x: the neural-texture footprint's scale (1: one atlas texel; "
         "Settings.lod_footprint), yzw unused"),
    ],
)  # fmt: skip

#: the screen-space pass's per-dispatch uniform
SCREEN_PARAMS = Struct(
    "Params",
    [
        ("model", "mat4x4<f32>"),
        ("normal_mat", "mat4x4<f32>"),
        ("eye", "vec4<f32>"),
        ("tiling", "vec4<f32>"),
        ("inv_view_proj", "mat4x4<f32>"),
        ("screen", "vec4<u32>", "(width, height, counter slot, object id)"),
        ("rect", "vec4<u32>", "dispatch origin (x0, y0) and size (w, h): the object's bounds"),
    ],
)

#: the forward pass's per-eye uniform (group 0) and per-object uniform (group 1)
FRAME = Struct(
    "Frame",
    [("view_proj", "mat4x4<f32>"),
     ("eye", "vec4<f32>", "world eye position"),
     ("info", "vec4<u32>", "(light count, unused...): the loops use n_active, fixed per pipeline")],
)  # fmt: skip
OBJECT = Struct(
    "Object",
    [("model", "mat4x4<f32>"),
     ("normal_mat", "mat4x4<f32>"),
     ("albedo", "vec4<f32>", "plain: diffuse albedo rgb"),
     ("spec", "vec4<f32>", "plain: (specular albedo, shininess, object id, unused)")],
)  # fmt: skip

#: the neural material's bindings start here (textures, then a storage weight buffer)
MATERIAL_BINDING = 7
#: binding of the height field of a parallax material (both passes)
HEIGHT_BINDING = 18
#: binding of the offset texture of a neural-offset material (both passes)
OFFSET_BINDING = 19
#: binding of the neural textures' sampler (filtering "hardware", both passes)
NEURAL_SAMPLER_BINDING = 11
#: first binding of the uniform weight buffers (one per layer, then the biases)
UNIFORM_WEIGHTS_BINDING = 20


def lights_binding(n_lights: int, slot: int = 1) -> Binding:
    """The lights uniform: ``array<Light, n_lights>`` (WGSL arrays are never empty)."""
    return Binding(slot, "lights", "uniform", ArrayOf(LIGHT, max(1, n_lights)))


def material_bindings(spec) -> list[Binding]:
    """A material's resources (:class:`~vrneural.runtime.codegen.MaterialSpec`): neural
    textures (and their sampler, for filtering "hardware"), the height field of parallax or the
    offset texture of a neural offset, buffer weights; read by neural_material.wgsl and
    bound from :meth:`~vrneural.runtime.gpu_material.GpuMaterial.resources`."""
    first = MATERIAL_BINDING
    hw = spec.filtering == "hardware"
    tex = "texture_2d_array<f32>" if hw else "texture_2d_array<u32>"
    out = [Binding(first, "tex_a", "texture", tex, "coarse / features")]
    if hw:
        out.append(Binding(NEURAL_SAMPLER_BINDING, "neural_samp", "sampler", "sampler",
                           "repeat, linear, linear mipmaps"))  # fmt: skip
    if spec.parallax_steps > 0:
        out.append(Binding(HEIGHT_BINDING, "height_tex", "texture", "texture_2d<f32>",
                           "r16float, UV units" if hw else "r32float, UV units",
                           sample_type=None if hw else "unfilterable-float"))  # fmt: skip
    if spec.offset_net:
        out.append(Binding(OFFSET_BINDING, "off_tex", "texture", tex, "neural offset texture"))
    if spec.arch == "coarse_fine":
        out.append(Binding(first + 1, "tex_b", "texture", tex, "fine"))
    if spec.weights in ("storage", "streamed"):
        out.append(Binding(first + 2, "weights", "storage", "array<f32>"))
    elif spec.weights == "uniform":
        dims = list(zip(spec.buf_dims_in, spec.buf_dims_out, strict=True))
        out += [
            Binding(UNIFORM_WEIGHTS_BINDING + li, f"wl{li}", "uniform",
                    f"array<vec4<f32>, {(n_in * n_out + 3) // 4}>")
            for li, (n_in, n_out) in enumerate(dims)
        ]  # fmt: skip
        out.append(Binding(UNIFORM_WEIGHTS_BINDING + len(dims), "wbias", "uniform",
                           f"array<vec4<f32>, {(sum(spec.buf_dims_out) + 3) // 4}>"))  # fmt: skip
    return out


#: work compaction (compact.wgsl; host side texture_pass.CompactionBuffers)
COMPACT = [
    Binding(13, "todo", "storage_rw", "array<u32>"),
    Binding(14, "todo_n", "storage_rw", "array<atomic<u32>>"),
    Binding(15, "ind", "storage_rw", "array<u32>", "(x, y, z) workgroups"),
]


def texture_bindings(spec, n_lights: int, fmt: str = "rgba16float") -> Bindings:
    """The texture-space pass (texture_space.wgsl). The geometry atlas: one vec4 per non-empty
    block in each array (gpu_material.GpuAtlas.geometry); ``cand``: indices into it of the
    non-empty blocks, grouped by block row phase (GpuAtlas.block_list)."""
    geo = "array<vec4<f32>>"
    return Bindings([
        Binding(0, "P", "uniform", TEXTURE_PARAMS),
        lights_binding(n_lights),
        Binding(2, "geo_pos", "storage", geo, "object pos, bitcast(by << 16 | bx)"),
        Binding(3, "geo_nrm", "storage", geo, "object normal, tangent sign"),
        Binding(4, "geo_tan", "storage", geo, "object tangent, texel foot"),
        Binding(16, "geo_uv01", "storage", geo, "untiled uv of texels 0, 1"),
        Binding(17, "geo_uv23", "storage", geo, "untiled uv of texels 2, 3"),
        Binding(5, "out_tex", "storage_texture", f"texture_storage_2d<{fmt}, write>"),
        Binding(6, "counters", "storage_rw", "array<atomic<u32>>", "4 per slot"),
        *material_bindings(spec),
        Binding(12, "cand", "storage", "array<u32>", "candidate blocks"),
        *COMPACT,
    ])  # fmt: skip


def screen_bindings(spec, n_lights: int) -> Bindings:
    """The screen-space pass (screen_space.wgsl); compaction lists the object's pixels of its
    rectangle, packed ``y << 16 | x``."""
    return Bindings([
        Binding(0, "P", "uniform", SCREEN_PARAMS),
        lights_binding(n_lights),
        Binding(2, "verts", "storage", "array<vec4<f32>>"),
        Binding(3, "faces", "storage", "array<u32>"),
        Binding(4, "vis", "texture", "texture_2d<u32>"),
        Binding(5, "out_tex", "storage_texture", "texture_storage_2d<rgba16float, write>"),
        Binding(6, "counters", "storage_rw", "array<atomic<u32>>"),
        *material_bindings(spec),
        *COMPACT,
    ])  # fmt: skip


def forward_bindings(n_lights: int) -> tuple[Bindings, Bindings]:
    """The forward pass (forward.wgsl): group 0 per eye (frame, lights), group 1 per object
    (its uniform; neural objects also their radiance texture and its sampler)."""
    frame = Bindings([Binding(0, "F", "uniform", FRAME), lights_binding(n_lights)], group=0)
    obj = Bindings([
        Binding(0, "O", "uniform", OBJECT),
        Binding(1, "radiance", "texture", "texture_2d<f32>"),
        Binding(2, "samp", "sampler", "sampler"),
    ], group=1)  # fmt: skip
    return frame, obj


#: a radiance texture's mip chain (radiance_mips.wgsl): the level read and the level written
MIP_BINDINGS = Bindings([
    Binding(0, "src", "texture", "texture_2d<f32>"),
    Binding(1, "dst", "storage_texture", "texture_storage_2d<rgba16float, write>"),
])  # fmt: skip


def structs_wgsl(*structs: Struct) -> str:
    """The WGSL declarations of ``structs``."""
    return "\n".join(s.wgsl() for s in structs)
