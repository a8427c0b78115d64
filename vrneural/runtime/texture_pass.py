"""The texture-space compute pass (``shaders/texture_space.wgsl``) and its GPU entry point
:func:`shade_texture_space`, the twin of :func:`vrneural.runtime.reference.shade_texture_space`.

One :class:`TextureSpacePass` per (material, precision, light count, weight variant) holds the
pipeline; one :class:`TextureTarget` per (object, eye) holds its uniform regions, the radiance
texture and the bind groups. An update is one dispatch (``main``: facing test and shading
fused) over the candidate blocks of its row phase. Counters: 4 u32 per slot (blocks shaded,
back-facing blocks skipped, coarse and fine MLP evaluations), summed per subgroup or workgroup,
one slot per dispatch.
"""

from __future__ import annotations

import numpy as np

from vrneural.gpu.device import get_device, has_feature
from vrneural.gpu.pipelines import compute_pipeline
from vrneural.gpu.readback import read_buffer, read_texture, upload_buffer
from vrneural.gpu.uniforms import UniformArena
from vrneural.material import NeuralMaterial
from vrneural.runtime.codegen import material_spec, texture_space_wgsl
from vrneural.runtime.gpu_material import GpuAtlas, GpuMaterial, new_radiance_texture
from vrneural.runtime.interface import LIGHT, TEXTURE_PARAMS, texture_bindings
from vrneural.runtime.radiance_mips import MipChain, mip_count
from vrneural.runtime.reference import normal_matrix

PARAMS_BYTES = TEXTURE_PARAMS.size  # 192
WORKGROUP_SIZE = 64  # 1D workgroups of the shading kernels


def pack_params_into(
    p: np.ndarray, model, eye, tiling, offset=0, count=0, slot=0, margin=0.0, base=None,
    lod_scale=1.0
) -> None:  # fmt: skip
    """Write the ``Params`` uniform of texture_space.wgsl into the record ``p``
    (:data:`~vrneural.runtime.interface.TEXTURE_PARAMS`). ``model`` is taken relative to
    ``eye`` in float64 first (:func:`~vrneural.runtime.reference.camera_relative`: the shaded
    eye sits at the origin); ``offset, count``: this dispatch's span of the atlas's candidate
    block list; ``margin`` (m): blocks facing any point within it of ``eye`` are shaded (a
    radiance texture shared by both eyes); ``base``: :func:`params_base` of ``model`` when the
    caller keeps it; ``lod_scale``: the prefiltered neural textures' footprint in atlas texels
    (:func:`~vrneural.runtime.reference.block_lod`; above 1 where a pixel is the larger)."""
    b = params_base(model) if base is None else base
    p["model"] = b[:16].reshape(4, 4)
    p["normal_mat"] = b[16:32].reshape(4, 4)
    p["model"][3, :3] = np.asarray(model, np.float64)[:3, 3] - np.asarray(eye, np.float64)[:3]
    p["eye"] = (0.0, 0.0, 0.0, margin)
    p["tiling"] = tiling
    p["sched"] = (offset, count, slot, 0)
    p["lod"] = (lod_scale, 0.0, 0.0, 0.0)


def params_base(model) -> np.ndarray:
    """``[32]`` float32: ``model`` and its normal matrix, column-major, as the first words of
    ``Params`` (the translation is replaced per eye by :func:`pack_params_into`)."""
    m32 = np.asarray(model, np.float32)
    return np.concatenate([m32.T.ravel(), normal_matrix(m32).T.ravel()])


def pack_lights_into(a: np.ndarray, light_pos, light_rgb, origin=None) -> None:
    """Write ``array<Light, n>`` into the records ``a: [n]``
    (:data:`~vrneural.runtime.interface.LIGHT`): (pos.xyz - origin, 0), (colour * intensity,
    0) per light (positions shifted in float64); zero-padded (the w components are never
    written: ``a`` comes zeroed)."""
    k = len(light_pos)
    lp = np.asarray(light_pos, np.float64)
    a["pos"][:k, :3] = lp if origin is None else lp - np.asarray(origin, np.float64)[:3]
    a["radiance"][:k, :3] = light_rgb
    if k < len(a):
        a[k:] = np.zeros(1, a.dtype)


def light_words(lw: np.ndarray, light_pos, light_rgb, origin=None) -> None:
    """:func:`pack_lights_into` on the float32 words ``lw [8 n]`` of ``array<Light, n>``:
    (pos.xyz - origin, 0), (radiance, 0), zero-padded."""
    a = lw.reshape(-1, 8)
    lp = np.asarray(light_pos, np.float64)
    k = len(lp)
    a[:k, :3] = lp if origin is None else lp - origin
    a[:k, 3:] = 0.0
    a[:k, 4:7] = light_rgb
    a[k:] = 0.0


class CounterBuffer:
    """``slots x 4`` u32 atomic counters (zeroed on creation and by :meth:`clear`)."""

    def __init__(self, slots: int):
        import wgpu

        self.slots = slots
        self.buf = upload_buffer(
            np.zeros(slots * 4, np.uint32),
            wgpu.BufferUsage.STORAGE | wgpu.BufferUsage.COPY_SRC | wgpu.BufferUsage.COPY_DST,
            "counters",
        )

    def clear(self, encoder=None) -> None:
        """Zero the counters: in ``encoder`` (on the GPU, in order with the frame's passes) or,
        without one, through the queue."""
        if encoder is not None:
            encoder.clear_buffer(self.buf)
        else:
            get_device().queue.write_buffer(self.buf, 0, np.zeros(self.slots * 4, np.uint32))

    def read(self) -> np.ndarray:
        return read_buffer(self.buf, np.uint32, self.slots * 4).reshape(self.slots, 4)


class TextureSpacePass:
    """Compiled texture-space kernel for one material and its GPU resources."""

    def __init__(
        self,
        mat: NeuralMaterial,
        precision: str = "f32",
        n_lights: int = 1,
        weights: str = "constants",
        radiance_format: str = "rgba16float",
        subgroups: bool | None = None,
        filtering: str = "exact",
        taps: int = 1,
    ):
        self.mat = mat
        self.taps = taps  # footprint taps per axis at most (Settings.lod_taps)
        self.radiance_format = radiance_format  # rgba32float: no f16 clamp, 2x memory
        self.n_lights = max(1, n_lights)  # size of the lights uniform (0 lights: one unused)
        self.subgroups = has_feature("subgroup") if subgroups is None else subgroups
        self.code = texture_space_wgsl(
            mat, precision, n_lights, weights, radiance_format, self.subgroups, filtering, taps
        )
        self.gmat = GpuMaterial(mat, weights, filtering)
        spec = material_spec(mat, weights, filtering)
        self.bindings = texture_bindings(spec, n_lights, radiance_format)

    def pipeline(self, entry: str = "main"):
        """The compiled entry point (one for every texture side: the kernel takes its texels
        from the geometry atlas, so no side is compiled in)."""
        return compute_pipeline(self.code, entry, label=f"texture_space/{entry}")


def grid(n: int, size: int = WORKGROUP_SIZE) -> tuple[int, int]:
    """Workgroups ``(x, y)`` covering ``n`` invocations, each dimension within the 65535 limit
    (the kernels index them as ``(wid.y * nwg.x + wid.x) * size + lid``)."""
    wg = -(-n // size)
    y = max(1, -(-wg // 65535))
    return -(-wg // y), y


class CompactionBuffers:
    """The buffers of compact.wgsl (todo, todo_n, ind) for up to ``n`` items: the list of items to
    shade (padded to whole workgroups), its count (zero at creation; ``args`` re-zeroes it) and
    the indirect workgroup counts."""

    def __init__(self, n: int):
        import wgpu

        dev = get_device()
        st = wgpu.BufferUsage.STORAGE
        x, y = grid(n)
        self.todo = dev.create_buffer(size=4 * max(1, x * y * WORKGROUP_SIZE), usage=st)
        self.todo_n = dev.create_buffer(size=16, usage=st)
        self.ind = dev.create_buffer(size=16, usage=st | wgpu.BufferUsage.INDIRECT)

    def resources(self) -> dict:
        """By binding name (runtime/interface.py:COMPACT)."""
        return {"todo": {"buffer": self.todo}, "todo_n": {"buffer": self.todo_n},
                "ind": {"buffer": self.ind}}  # fmt: skip


#: bindings of the ``args`` entry point (compact.wgsl)
ARGS_BINDINGS = ("todo", "todo_n", "ind")


def dispatch_compacted(cp, pipes: dict, binds: dict, cull_grid, ind) -> None:
    """Record ``cull`` over ``cull_grid`` workgroups, then ``args``, then ``main`` over the
    items ``cull`` kept (indirect) into the open compute pass ``cp``."""
    cp.set_pipeline(pipes["cull"])
    cp.set_bind_group(0, binds["cull"])
    cp.dispatch_workgroups(*cull_grid, 1)
    cp.set_pipeline(pipes["args"])
    cp.set_bind_group(0, binds["args"])
    cp.dispatch_workgroups(1, 1, 1)
    main = "main_compacted" if "main_compacted" in pipes else "main"
    cp.set_pipeline(pipes[main])
    cp.set_bind_group(0, binds[main])
    cp.dispatch_workgroups_indirect(ind, 0)


#: candidate blocks per dispatch from which an update compacts its front-facing blocks first
#: (cull, args, main_compacted) instead of testing and shading in one dispatch (main): measured
#: on lavapipe, the one dispatch is 1.3-2.3x faster up to ~20 k candidates (a staggered update at
#: 128-256^2), the compacted three 7-16% faster from ~40 k (full updates at 512-800^2)
COMPACT_MIN = 32768


class TextureTarget:
    """One (object, eye) radiance texture with its uniform regions and bind groups.

    ``arena``: the :class:`~vrneural.gpu.uniforms.UniformArena` holding its ``Params`` and
    lights (the renderer's, written once per frame); by default one of its own, written at
    every :meth:`update`."""

    def __init__(
        self,
        tpass: TextureSpacePass,
        gatlas: GpuAtlas,
        counters: CounterBuffer,
        arena: UniformArena | None = None,
        mips: bool = False,
    ):
        self.tpass = tpass
        self.gatlas = gatlas
        self.R = gatlas.resolution
        self.pipes = {"main": tpass.pipeline()}
        self.arena = arena or UniformArena("texture target", auto_flush=True)
        self.p_off = self.arena.alloc(PARAMS_BYTES)
        self.l_off = self.arena.alloc(LIGHT.size * tpass.n_lights)
        levels = mip_count(self.R) if mips else 1
        self.texture = new_radiance_texture(self.R, fmt=tpass.radiance_format, mips=levels)
        self.view = self.texture.create_view(base_mip_level=0, mip_level_count=1)  # written
        self.sample_view = self.texture.create_view()  # every level: the forward pass's
        #: rebuilds levels 1.. after an update (None: a single level)
        self.mips = MipChain(self.texture, levels) if levels > 1 else None
        self.compact: CompactionBuffers | None = None  # made for the first long span
        self.counters = counters
        self.binds: dict = {}
        self._base: tuple | None = None  # (model bytes, params_base(model), translation)
        self._words: tuple | None = None  # its arena regions as words (update)

    def _bind(self, entry: str, period: int):
        """Bind group of one entry point and row period (auto layouts differ per entry)."""
        key = (entry, period if entry not in ("args", "main_compacted") else 0)
        if key not in self.binds:
            if entry not in self.pipes:
                self.pipes[entry] = self.tpass.pipeline(entry)
            g, tp, ar = self.gatlas, self.tpass, self.arena
            geo = g.geometry()
            res = {
                "P": ar.binding(self.p_off, PARAMS_BYTES),
                "lights": ar.binding(self.l_off, LIGHT.size * tp.n_lights),
                "geo_pos": {"buffer": geo["pos"]},
                "geo_nrm": {"buffer": geo["nrm"]},
                "geo_tan": {"buffer": geo["tan"]},
                "geo_uv01": {"buffer": geo["uv01"]},
                "geo_uv23": {"buffer": geo["uv23"]},
                "out_tex": self.view,
                "counters": {"buffer": self.counters.buf},
                "cand": {"buffer": g.block_list(period)[0]},
                **tp.gmat.resources(),
            }
            if entry in ("cull", "args", "main_compacted"):
                if self.compact is None:
                    self.compact = CompactionBuffers(g.non_empty_blocks)
                res.update(self.compact.resources())
            # an entry point's auto layout holds the bindings it uses, and only those
            bare = ("P", "geo_pos", "geo_nrm", "geo_tan", "geo_uv01", "geo_uv23", "out_tex", "cand")
            used = {
                "bare": bare,
                "bare_loads": (*bare, *(k for k in ("tex_a", "tex_b", "neural_samp") if k in res)),
                "cull": ("P", "geo_pos", "geo_nrm", "counters", "cand", "todo", "todo_n"),
                "args": ARGS_BINDINGS,
                "main_compacted": tuple(k for k in res if k not in ("cand", "todo_n", "ind")),
            }.get(entry)  # fmt: skip
            self.binds[key] = get_device().create_bind_group(
                layout=self.pipes[entry].get_bind_group_layout(0),
                entries=tp.bindings.entries(res, used),
            )
        return self.binds[key]

    def update(
        self, model, eye, tiling, light_pos, light_rgb, phase=0, period=1, slot=0, margin=0.0,
        lod_scale=1.0
    ):  # fmt: skip
        """Write this dispatch's uniforms (before encoding it; the renderer's arena sends them
        with the frame). World quantities are made relative to ``eye`` in float64 first
        (:func:`~vrneural.runtime.reference.camera_relative`). ``margin``,
        ``lod_scale``: see :func:`pack_params_into`."""
        key = model.tobytes() if isinstance(model, np.ndarray) else repr(model)
        if self._base is None or self._base[0] != key:  # computed again when the model changes
            self._base = (key, params_base(model), np.asarray(model, np.float64)[:3, 3].copy())
        offset, count = self.gatlas.block_list(period)[1][phase]
        ar = self.arena
        if self._words is None:  # word views of its two regions, kept (called every frame)
            nl = self.tpass.n_lights
            w = ar.words(self.p_off, PARAMS_BYTES)
            self._words = (w, w.view(np.uint32), ar.words(self.l_off, LIGHT.size * nl))
        # the words of pack_params_into and pack_lights_into (the same values: tested), with
        # plain slices instead of record fields: a few microseconds less per target and frame
        w, wu, lw = self._words
        e = np.asarray(eye, np.float64)[:3]
        w[:32] = self._base[1]  # model and normal matrix, column-major
        w[12:15] = self._base[2] - e  # the translation, camera-relative in float64 first
        w[32:36] = (0.0, 0.0, 0.0, margin)
        w[36:40] = tiling
        wu[40:44] = (offset, count, slot, 0)
        w[44:48] = (lod_scale, 0.0, 0.0, 0.0)
        light_words(lw, light_pos, light_rgb, e)
        ar.mark(self.p_off, PARAMS_BYTES)
        ar.mark(self.l_off, lw.nbytes)
        ar.written()

    def encode(self, encoder, phase=0, period=1, timestamp_writes=None, entry="main") -> None:
        """Dispatch the block rows ``phase, phase + period, ...`` in a compute pass of its own."""
        cp = encoder.begin_compute_pass(timestamp_writes=timestamp_writes)
        self.dispatch(cp, phase, period, entry)
        cp.end()

    def dispatch(self, cp, phase=0, period=1, entry="main", bound=None):
        """Record this target's update into an open compute pass ``cp`` (after :meth:`update`
        with the same ``phase, period``): one dispatch, or from :data:`COMPACT_MIN` candidates
        three (cull, args, main_compacted). ``bound``: the pipeline the pass has set (returned:
        the other eye's target shares it). ``entry="bare"``: the pass's floor kernel (the same
        facing test, geometry records read and texels stored; no shading); ``"bare_loads"``:
        with the neural-texture lookups at the block's texels too."""
        n = self.gatlas.block_list(period)[1][phase][1]
        if not n:
            return bound
        if entry == "main" and n >= COMPACT_MIN:
            ents = ("cull", "args", "main_compacted")
            binds = {e: self._bind(e, period) for e in ents}
            dispatch_compacted(cp, self.pipes, binds, grid(n), self.compact.ind)
            bound = None
        else:
            bind = self._bind(entry, period)
            pipe = self.pipes[entry]
            if pipe is not bound:
                cp.set_pipeline(pipe)
            cp.set_bind_group(0, bind)
            cp.dispatch_workgroups(*grid(n), 1)
            bound = pipe
        if self.mips is not None and not entry.startswith("bare"):  # after the texels it averages
            self.mips.dispatch(cp)
            bound = None
        return bound


def shade_texture_space(
    atlas,
    mat: NeuralMaterial,
    model: np.ndarray,
    eye: np.ndarray,
    light_pos: np.ndarray,
    light_rgb: np.ndarray,
    tiling=(1.0, 1.0, 0.0, 0.0),
    precision: str = "f32",
    phase: int = 0,
    period: int = 1,
    weights: str = "constants",
    radiance_format: str = "rgba16float",
    subgroups: bool | None = None,
    margin: float = 0.0,
    filtering: str = "exact",
    lod_scale: float = 1.0,
    taps: int = 1,
):
    """GPU texture-space pass on a fresh (zeroed) texture; returns ``(radiance [R, R, 4]
    float32, counters [4])`` like the numpy twin of the same name. ``subgroups``: None = use
    them where the device has the feature; ``margin``, ``lod_scale``: see
    :func:`pack_params_into`;
    ``filtering``: of the neural textures (codegen_sample.FILTERS); ``taps``: footprint taps
    per axis at most (``Settings.lod_taps``)."""
    lp = np.asarray(light_pos, np.float64).reshape(-1, 3)
    tp = TextureSpacePass(
        mat,
        precision,
        len(lp),
        weights,
        radiance_format=radiance_format,
        subgroups=subgroups,
        filtering=filtering,
        taps=taps,
    )
    counters = CounterBuffer(1)
    tgt = TextureTarget(tp, GpuAtlas(atlas), counters)
    tgt.update(model, eye, tiling, lp, light_rgb, phase, period, 0, margin, lod_scale)
    enc = get_device().create_command_encoder()
    tgt.encode(enc, phase, period)
    get_device().queue.submit([enc.finish()])
    rad = read_texture(tgt.texture).astype(np.float32)
    return rad, counters.read()[0].astype(np.int64)
