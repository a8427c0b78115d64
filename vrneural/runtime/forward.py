"""Forward (raster) pass per eye, ``shaders/forward.wgsl``: meshes with a depth test, neural
objects bilinearly sampling their eye's radiance texture, plain objects shaded by
Lambert + Blinn-Phong under the same point lights (a loop over the light count, fixed per
pipeline). Also the visibility pass of the screen-space modes (plain colour + an rg32uint
``(object id + 1, triangle)`` target). Each eye's draws never change during a renderer's life:
they are recorded once into a render bundle (:func:`record_bundle`) that every frame replays.

Vertex buffers hold triangles expanded to 3 vertices each: ``position.xyz, normal.xyz,
atlas_uv.xy, triangle (u32)`` (36 bytes).
"""

from __future__ import annotations

import functools

import numpy as np

from vrneural.gpu.device import get_device
from vrneural.gpu.readback import upload_buffer
from vrneural.gpu.shaders import render_wgsl
from vrneural.gpu.uniforms import UniformArena
from vrneural.runtime import settings
from vrneural.runtime.interface import FRAME, LIGHT, OBJECT, forward_bindings, structs_wgsl
from vrneural.runtime.reference import normal_matrix
from vrneural.runtime.texture_pass import light_words

#: eye colour targets: ``hdr`` (linear radiance, for EXR and FLIP) or ``display`` (Reinhard
#: tonemapped, sRGB-encoded 8 bits: half the bytes where HDR output is not needed), and the
#: format each renders into (the display target's when its colour is cleared by the render pass;
#: see :func:`colour_format`)
TARGETS = dict(zip(settings.TARGETS, ("rgba16float", "rgba8unorm-srgb"), strict=True))
DEPTH_FORMAT = "depth32float"
VIS_FORMAT = "rg32uint"
FRAME_BYTES = FRAME.size  # 96


def expanded_vertices(mesh, uv_atlas: np.ndarray | None) -> np.ndarray:
    """``[3F, 9]`` 32-bit rows (8 float32 + 1 uint32 triangle index), as raw float32 view."""
    f = mesh.faces.astype(np.int64).ravel()
    n = len(f)
    rows = np.zeros((n, 9), np.float32)
    rows[:, 0:3] = mesh.positions[f]
    rows[:, 3:6] = mesh.normals[f]
    if uv_atlas is not None:
        rows[:, 6:8] = uv_atlas[f]
    rows.view(np.uint32)[:, 8] = np.repeat(np.arange(n // 3, dtype=np.uint32), 3)
    return rows


def colour_format(target: str, compute_clear: bool) -> str:
    """The eyes' colour format for ``target``: :data:`TARGETS`'s, but the display target
    cleared by :func:`clear_colour` is ``rgba8unorm`` (an ``-srgb`` format cannot be a storage
    texture), its sRGB encoding done by the fragment shader instead of the target."""
    return "rgba8unorm" if target == "display" and compute_clear else TARGETS[target]


@functools.cache
def _module(n_lights: int, n_active: int, fmt: str, mips: bool = False):
    frame, obj = forward_bindings(n_lights)
    code = render_wgsl(
        "forward",
        structs=structs_wgsl(FRAME, LIGHT, OBJECT),
        bindings=frame.wgsl() + "\n" + obj.wgsl(),
        n_active=n_active,
        display=fmt != TARGETS["hdr"],  # Reinhard-tonemapped
        encode_srgb=fmt == "rgba8unorm",  # not by the target
        mips=mips,
    )
    return get_device().create_shader_module(code=code, label="forward")


@functools.cache
def _layouts():
    """Explicit bind-group layouts: (frame group, neural object group, plain object group)."""
    import wgpu

    dev = get_device()
    vf = wgpu.ShaderStage.VERTEX | wgpu.ShaderStage.FRAGMENT
    fr = wgpu.ShaderStage.FRAGMENT
    frame, obj = forward_bindings(1)  # the layouts leave the lights' size open
    vis = {"F": vf, "lights": fr, "O": vf, "radiance": fr, "samp": fr}
    return (
        dev.create_bind_group_layout(entries=frame.layout_entries(vis)),
        dev.create_bind_group_layout(entries=obj.layout_entries(vis)),
        dev.create_bind_group_layout(entries=obj.layout_entries(vis, ["O"])),
    )


#: the vertex buffer of :func:`expanded_vertices`: position, normal, atlas uv, triangle
VERTEX_BUFFER = {
    "array_stride": 36,
    "attributes": [
        {"format": f, "offset": off, "shader_location": k}
        for k, (f, off) in enumerate(
            (("float32x3", 0), ("float32x3", 12), ("float32x2", 24), ("uint32", 32))
        )
    ],
}
#: fragment entry points whose object group holds a radiance texture
SAMPLING = ("fs_neural", "fs_floor_sample", "fs_floor_constant")


def _raster_state() -> dict:
    """Primitive and depth state of every forward-pass pipeline: triangle lists, no culling,
    depth less-tested and written."""
    return {
        "primitive": {"topology": "triangle-list", "cull_mode": "none"},
        "depth_stencil": {
            "format": DEPTH_FORMAT,
            "depth_write_enabled": True,
            "depth_compare": "less",
        },
    }


@functools.cache
def render_pipeline(
    n_lights: int,
    fragment: str,
    vis: bool,
    n_active: int | None = None,
    fmt: str = TARGETS["hdr"],
    mips: bool = False,
    samples: int = 1,
):
    """Cached render pipeline for entry point ``fragment`` (``vis``: colour + visibility):
    a lights array of ``n_lights``, ``n_active`` of them shaded (default all), colour format
    ``fmt`` (``EyeTargets.format``); ``mips``: neural objects sample their radiance textures'
    mip chains; ``samples``: the targets' samples per pixel (``EyeTargets.samples``)."""
    mips = mips and fragment in ("fs_neural", "fs_floor_sample")
    mod = _module(n_lights, n_lights if n_active is None else n_active, fmt, mips)
    frame_l, neural_l, plain_l = _layouts()
    obj_l = neural_l if fragment in SAMPLING else plain_l
    layout = get_device().create_pipeline_layout(bind_group_layouts=[frame_l, obj_l])
    targets = [{"format": fmt}]
    if vis:
        targets.append({"format": VIS_FORMAT})
    return get_device().create_render_pipeline(
        layout=layout,
        vertex={"module": mod, "entry_point": "vs_main", "buffers": [VERTEX_BUFFER]},
        **_raster_state(),
        fragment={"module": mod, "entry_point": fragment, "targets": targets},
        multisample={"count": samples},
        label=fragment,
    )


@functools.cache
def screen_floor_pipeline(n_lights: int, fmt: str = TARGETS["hdr"], samples: int = 1):
    """The raster floor (`bench frame`): a triangle covering the viewport in a constant colour,
    depth-tested and written as the forward pass's draws are, into a colour target of format
    ``fmt`` alone (no visibility target), ``samples`` per pixel; no vertex buffer, no
    bindings."""
    mod = _module(n_lights, n_lights, fmt)
    return get_device().create_render_pipeline(
        layout="auto",
        vertex={"module": mod, "entry_point": "vs_screen", "buffers": []},
        **_raster_state(),
        fragment={
            "module": mod,
            "entry_point": "fs_floor_constant",
            "targets": [{"format": fmt}],
        },
        multisample={"count": samples},
        label="screen floor",
    )


class EyeTargets:
    """Per-eye colour (``target``: :data:`TARGETS`), depth and (screen modes) visibility
    textures, their views, and the frame uniforms (regions of ``arena``, the renderer's
    :class:`~vrneural.gpu.uniforms.UniformArena`; by default one of its own).

    ``share``: draw into the textures of another ``EyeTargets`` instead, in the ``width``
    columns from ``x0`` (:meth:`side_by_side`); ``columns``: textures that many eyes wide;
    ``depth_slices``: render passes one depth clear serves (:func:`begin_pass`); ``samples``:
    samples per pixel (4: multisampled colour and depth, resolved into the colour texture at
    the end of each pass; the fragment shader still runs once per pixel and triangle, so a
    pixel covered by one triangle keeps its value, and one that a silhouette or a triangle's
    edge crosses becomes the coverage-weighted mean of the triangles covering it)."""

    def __init__(
        self, width: int, height: int, n_lights: int, vis: bool = False, arena=None,
        target: str = "hdr", share: EyeTargets | None = None, x0: int = 0, columns: int = 1,
        compute_clear: bool = True, depth_slices: int = 1, samples: int = 1,
    ):  # fmt: skip
        import wgpu

        dev = get_device()
        tu = wgpu.TextureUsage
        self.size = (width, height)  # this eye's image
        if samples not in settings.MSAA:
            raise ValueError(f"EyeTargets: samples = {samples} is not one of {settings.MSAA}")
        #: samples per pixel of the colour and depth attachments
        self.samples = samples if share is None else share.samples
        #: begin_pass clears the colour with clear_colour (else in the render pass; with
        #: samples the resolve writes every pixel: nothing to clear there)
        own = compute_clear and self.samples == 1
        self.compute_clear = own if share is None else share.compute_clear
        self.x0 = x0  # its first column in the textures
        #: the eyes' targets that own the textures (itself unless ``share``): the depth's state
        self.owner = self if share is None else share
        if share is None:
            if not 1 <= depth_slices <= 64:
                raise ValueError(f"EyeTargets: depth_slices = {depth_slices} is not in [1, 64]")
            self.depth_slices = depth_slices
            self.passes = 0  # render passes begun on these targets (begin_pass)
            #: the depth range of the pass in progress (viewport's min and max depth)
            self.depth_range = (0.0, 1.0)
        self.target = target
        #: the colour texture's format (:func:`colour_format`)
        self.format = colour_format(target, self.compute_clear)

        def texture(fmt: str, usage, samples: int = 1):
            return dev.create_texture(size=(width * columns, height, 1), format=fmt, usage=usage,
                                      sample_count=samples)  # fmt: skip

        rt = tu.RENDER_ATTACHMENT
        if share is not None:
            self.colour, self.depth, self.vis = share.colour, share.depth, share.vis
            self.colour_view, self.depth_view = share.colour_view, share.depth_view
            self.vis_view, self._clear = share.vis_view, share._clear
            self.ms_view = share.ms_view
        else:
            # storage: cleared by a compute pass (clear_colour); the screen pass writes HDR
            storable = not self.format.endswith("-srgb")
            usage = rt | tu.COPY_SRC | tu.TEXTURE_BINDING | (tu.STORAGE_BINDING * storable)
            self.colour = texture(self.format, usage)
            self.depth = texture(DEPTH_FORMAT, rt, self.samples)
            #: the multisampled colour the pass draws into (None: the colour texture itself)
            self.ms_view = None
            if self.samples > 1:
                if vis:
                    raise ValueError("EyeTargets: no visibility target with samples above 1")
                self.ms_view = texture(self.format, rt, self.samples).create_view()
            self.vis = texture(VIS_FORMAT, rt | tu.TEXTURE_BINDING) if vis else None
            self.colour_view = self.colour.create_view()
            self._clear = _clear_group(self.colour, self.format) if storable else None
            self.depth_view = self.depth.create_view()
            self.vis_view = self.vis.create_view() if vis else None
        self.n_lights = max(1, n_lights)
        self.arena = arena or UniformArena("eye", auto_flush=True)
        self.f_off = self.arena.alloc(FRAME_BYTES)
        self.l_off = self.arena.alloc(LIGHT.size * self.n_lights)
        self._bind = None
        self._words: tuple | None = None  # its arena regions as words (update)

    @classmethod
    def side_by_side(
        cls, n: int, width: int, height: int, n_lights: int, arena=None, target: str = "hdr",
        compute_clear: bool = True, depth_slices: int = 1, samples: int = 1,
    ) -> list[EyeTargets]:  # fmt: skip
        """``n`` eyes' targets in one set of textures ``n * width`` wide, eye ``e`` in the
        columns from ``e * width``: one render pass draws every eye (a viewport each,
        :func:`viewport`), each with its own frame uniforms. Single-pass stereo: one pass
        begun, cleared and ended per frame instead of one per eye."""
        first = cls(width, height, n_lights, False, arena, target, columns=n,
                    compute_clear=compute_clear, depth_slices=depth_slices,
                    samples=samples)  # fmt: skip
        rest = [
            cls(width, height, n_lights, False, arena, target, share=first, x0=e * width)
            for e in range(1, n)
        ]
        return [first, *rest]

    def update(self, view_proj, eye_pos, light_pos, light_rgb) -> None:
        """Frame uniforms: ``view_proj [4, 4]``, ``eye_pos [3]``, lights (positions as given,
        in the same frame as ``view_proj``)."""
        ar = self.arena
        if self._words is None:  # word views of the Frame uniform and the lights, kept
            w = ar.words(self.f_off, FRAME_BYTES)
            self._words = (w, w.view(np.uint32), ar.words(self.l_off, LIGHT.size * self.n_lights))
        w, wu, lw = self._words  # the FRAME record's words: view_proj (column-major), eye, info
        w[:16] = np.asarray(view_proj, np.float64).T.ravel()
        w[16:19] = eye_pos
        w[19] = 0.0
        wu[20:24] = (len(light_pos), 0, 0, 0)
        light_words(lw, light_pos, light_rgb)
        ar.mark(self.f_off, FRAME_BYTES)
        ar.mark(self.l_off, lw.nbytes)
        ar.written()

    def formats(self) -> list[str]:
        """Colour attachment formats of its render passes (bundles must match them)."""
        return [self.format] + ([VIS_FORMAT] if self.vis is not None else [])


class DrawObject:
    """One object's vertex buffer and object uniform (shared by eyes)."""

    def __init__(self, mesh, uv_atlas, model, obj_id: int, plain=None):
        import wgpu

        self.n_vertices = 3 * len(mesh.faces)
        self.vbuf = upload_buffer(expanded_vertices(mesh, uv_atlas), wgpu.BufferUsage.VERTEX)
        albedo, spec, shin = plain if plain is not None else ((0, 0, 0), 0.0, 1.0)
        o = OBJECT.zeros()  # the Object uniform
        m32 = np.asarray(model, np.float32)
        o["model"] = m32.T
        o["normal_mat"] = normal_matrix(m32).T
        o["albedo"][:3] = albedo
        o["spec"][:3] = (spec, shin, obj_id)
        self.ubuf = upload_buffer(np.frombuffer(o.tobytes(), np.uint8), wgpu.BufferUsage.UNIFORM)
        self.binds: dict = {}

    def bind_group(self, radiance_view=None, key=None, mips: bool = False):
        """Group 1 (object uniform, radiance texture + sampler when given: ``mips``, the
        trilinear and anisotropic one), cached per ``key``."""
        if key in self.binds:
            return self.binds[key]
        layout = _layouts()[1 if radiance_view is not None else 2]
        res = {"O": {"buffer": self.ubuf}}
        if radiance_view is not None:
            res |= {"radiance": radiance_view, "samp": _sampler(bool(mips))}
        entries = forward_bindings(1)[1].entries(res)
        bg = get_device().create_bind_group(layout=layout, entries=entries)
        self.binds[key] = bg
        return bg


#: the anisotropy the mip sampler asks for (WebGPU clamps it to the adapter's)
MAX_ANISOTROPY = 8


@functools.cache
def _sampler(mips: bool = False):
    """Bilinear, clamped; ``mips``: trilinear and anisotropic over a radiance mip chain."""
    trilinear = {"mipmap_filter": "linear", "max_anisotropy": MAX_ANISOTROPY} if mips else {}
    return get_device().create_sampler(
        mag_filter="linear",
        min_filter="linear",
        address_mode_u="clamp-to-edge",
        address_mode_v="clamp-to-edge",
        **trilinear,
    )


def record_bundle(eye: EyeTargets, draws: list):
    """A render bundle of ``eye``'s draws, ``[(pipeline, object bind group, DrawObject)]``
    in order: replayed by every frame's forward pass (one call instead of four per draw)."""
    enc = bundle_encoder(eye)
    if eye._bind is None:  # group 0 (frame uniforms + lights), shared by every pipeline
        ar = eye.arena
        res = {
            "F": ar.binding(eye.f_off, FRAME_BYTES),
            "lights": ar.binding(eye.l_off, LIGHT.size * eye.n_lights),
        }
        entries = forward_bindings(eye.n_lights)[0].entries(res)
        eye._bind = get_device().create_bind_group(layout=_layouts()[0], entries=entries)
    enc.set_bind_group(0, eye._bind)
    for pipe, bg, d in draws:
        enc.set_pipeline(pipe)
        enc.set_bind_group(1, bg)
        enc.set_vertex_buffer(0, d.vbuf)
        enc.draw(d.n_vertices)
    return enc.finish()


def bundle_encoder(eye: EyeTargets):
    """A render bundle encoder for ``eye``'s passes (its formats and samples)."""
    return get_device().create_render_bundle_encoder(
        color_formats=eye.formats(), depth_stencil_format=DEPTH_FORMAT, sample_count=eye.samples
    )


def viewport(rp, eye: EyeTargets) -> None:
    """Draw into ``eye``'s columns of its (shared) targets, at the pass's depth range."""
    rp.set_viewport(eye.x0, 0, eye.size[0], eye.size[1], *eye.owner.depth_range)


def depth_slice(n: int, slices: int) -> tuple[bool, float, float]:
    """Render pass ``n``'s depth with ``slices`` passes per clear: (cleared?, the viewport's
    min and max depth). Pass ``n`` draws into slice ``k = n % slices``, the range
    ``[1 - (k + 1) / slices, 1 - k / slices]``: nearer than every slice drawn since the last
    clear (pass ``n - k``), so a depth left there by an earlier pass, drawn or not since,
    never hides the pass's own (its fragments pass the less test against it), and the pass's
    own surfaces are ordered among themselves as before, at ``log2(slices)`` bits less
    precision. ``slices`` 1: cleared every pass, the whole range."""
    k = n % slices
    return k == 0, 1.0 - (k + 1) / slices, 1.0 - k / slices


@functools.cache
def _clear_pipeline(fmt: str):
    """A compute pipeline storing black in every texel of a ``fmt`` storage texture."""
    code = f"""
@group(0) @binding(0) var dst: texture_storage_2d<{fmt}, write>;
@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) g: vec3<u32>) {{
    if (any(g.xy >= textureDimensions(dst))) {{ return; }}
    textureStore(dst, g.xy, vec4<f32>(0.0));
}}"""
    dev = get_device()
    mod = dev.create_shader_module(code=code, label=f"clear {fmt}")
    return dev.create_compute_pipeline(
        layout="auto", compute={"module": mod, "entry_point": "main"}, label=f"clear {fmt}"
    )


def _clear_group(tex, fmt: str):
    """(pipeline, bind group, workgroups) of :func:`clear_colour` for ``tex``."""
    pipe = _clear_pipeline(fmt)
    bg = get_device().create_bind_group(
        layout=pipe.get_bind_group_layout(0),
        entries=[{"binding": 0, "resource": tex.create_view()}],
    )
    return pipe, bg, ((tex.size[0] + 7) // 8, (tex.size[1] + 7) // 8)


def clear_colour(encoder, eye: EyeTargets, timestamp_writes=None) -> None:
    """Clear ``eye``'s colour texture (all of it: every eye drawn into it) to black in a
    compute pass. A render pass's clear goes through the raster back end, which some GPUs
    have little of: on an NVIDIA H200 (graphics on a few of its multiprocessors) clearing
    both Quest 3 eyes' rgba16float target took 1.3 ms in a render pass, 0.09 ms in compute
    (docs/results/h200/raster_floor.py), and the main job's frame fell from 4.4 to 3.2 ms. On
    lavapipe the compute pass is the slower (the main job's forward pass 130 -> 150-180 ms),
    so CPU adapters keep the render pass's clear (``Settings.colour_clear``), as a tiling GPU
    would want (a render pass's clear costs it nothing)."""
    if eye._clear is None:
        raise ValueError(f"clear_colour: the eyes' colour ({eye.format}) is no storage texture")
    pipe, bg, groups = eye._clear
    cp = encoder.begin_compute_pass(timestamp_writes=timestamp_writes)
    cp.set_pipeline(pipe)
    cp.set_bind_group(0, bg)
    cp.dispatch_workgroups(*groups)
    cp.end()


def begin_pass(encoder, eye: EyeTargets, timestamp_writes=None, clear_writes=None):
    """A render pass over ``eye``'s targets: colour black (with ``eye.compute_clear``
    cleared first by :func:`clear_colour`, timed by ``clear_writes``, then loaded; else
    cleared by the pass), depth cleared to 1 (and visibility to 0); the viewport the whole
    target (:func:`viewport` narrows it to an eye).

    With ``depth_slices`` above 1 the depth is cleared by one pass in that many and loaded by
    the others, each drawing into its own slice of the depth range (:func:`depth_slice`). A
    render pass's depth clear goes through the raster back end: on an NVIDIA H200, clearing
    both Quest 3 eyes' depth32float took 0.65 ms, a fifth of the main job's frame
    (docs/results/h200/raster_floor.py); a loaded depth costs nothing to set up there."""
    clear = {"load_op": "clear", "store_op": "store", "clear_value": (0, 0, 0, 0)}
    att = [{"view": eye.colour_view, **clear}]
    if eye.ms_view is not None:  # drawn multisampled, resolved into the colour texture
        att = [{"view": eye.ms_view, "resolve_target": eye.colour_view, **clear,
                "store_op": "discard"}]  # fmt: skip
    elif eye.compute_clear:
        clear_colour(encoder, eye, clear_writes)
        att = [{"view": eye.colour_view, "load_op": "load", "store_op": "store"}]
    if eye.vis is not None:
        att.append({"view": eye.vis_view, **clear})
    o = eye.owner
    cleared, lo, hi = depth_slice(o.passes, o.depth_slices)
    o.passes += 1
    o.depth_range = (lo, hi)
    rp = encoder.begin_render_pass(
        color_attachments=att,
        depth_stencil_attachment={
            "view": eye.depth_view,
            "depth_load_op": "clear" if cleared else "load",
            "depth_store_op": "store",
            "depth_clear_value": 1.0,
        },
        timestamp_writes=timestamp_writes,
    )
    if o.depth_slices > 1:
        rp.set_viewport(0, 0, o.depth.size[0], o.depth.size[1], lo, hi)
    return rp
