"""The texture-space compute pass (``shaders/texture_space.wgsl``) and its GPU entry point
:func:`shade_texture_space`, the twin of :func:`vrneural.runtime.reference.shade_texture_space`.

One :class:`TextureSpacePass` per (material, precision, light count, weight variant) holds the
pipeline; one :class:`TextureTarget` per (object, eye) holds the uniforms, the radiance texture
and the bind group. Counters: 4 u32 per slot (blocks shaded, back-facing blocks skipped, coarse
and fine MLP evaluations), accumulated with workgroup atomics, one slot per dispatch.
"""

from __future__ import annotations


import numpy as np

from vrneural.gpu.device import get_device, has_feature
from vrneural.gpu.pipelines import compute_pipeline
from vrneural.gpu.readback import read_buffer, read_texture, upload_buffer
from vrneural.material import NeuralMaterial
from vrneural.runtime.codegen import texture_space_wgsl
from vrneural.runtime.gpu_material import GpuAtlas, GpuMaterial, new_radiance_texture
from vrneural.runtime.reference import camera_relative, normal_matrix

PARAMS_BYTES = 176  # mat4 model, mat4 normal_mat, vec4 eye, vec4 tiling, vec4<u32> sched
WORKGROUP_SIZE = 64  # 1D workgroups of the cull and shade kernels


def pack_params(model, eye, tiling, offset=0, count=0, slot=0, margin=0.0) -> bytes:
    """The ``Params`` uniform of texture_space.wgsl (matrices column-major); ``offset, count``:
    this dispatch's span of the atlas's candidate block list; ``margin`` (m): blocks facing any
    point within it of ``eye`` are shaded (a radiance texture shared by both eyes)."""
    f = np.zeros(40, np.float32)
    f[0:16] = np.asarray(model, np.float32).T.ravel()
    f[16:32] = normal_matrix(np.asarray(model, np.float32)).T.ravel()
    f[32:35] = np.asarray(eye, np.float32)[:3]
    f[35] = margin
    f[36:40] = np.asarray(tiling, np.float32)
    u = np.array([offset, count, slot, 0], np.uint32)
    return f.tobytes() + u.tobytes()


def pack_lights(light_pos: np.ndarray, light_rgb: np.ndarray, n: int) -> bytes:
    """``array<Light, n>``: (pos.xyz, 0), (colour * intensity, 0) per light; zero-padded."""
    a = np.zeros((max(n, 1), 2, 4), np.float32)
    k = len(light_pos)
    a[:k, 0, :3] = light_pos
    a[:k, 1, :3] = light_rgb
    return a.tobytes()


class CounterBuffer:
    """``slots x 4`` u32 atomic counters (zeroed on creation and by :meth:`clear`)."""

    def __init__(self, slots: int):
        import wgpu

        self.slots = slots
        self.buf = upload_buffer(
            np.zeros(slots * 4, np.uint32),
            wgpu.BufferUsage.STORAGE | wgpu.BufferUsage.COPY_SRC,
            "counters",
        )

    def clear(self) -> None:
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
        gmat: GpuMaterial | None = None,
        radiance_format: str = "rgba16float",
        subgroups: bool | None = None,
    ):
        self.mat = mat
        self.radiance_format = radiance_format  # rgba32float: no f16 clamp, 2x memory
        self.n_lights = max(1, n_lights)  # size of the lights uniform (0 lights: one unused)
        self.subgroups = has_feature("subgroup") if subgroups is None else subgroups
        self.code = texture_space_wgsl(
            mat, precision, n_lights, weights, radiance_format, self.subgroups
        )
        self.gmat = gmat or GpuMaterial(mat, weights)

    def pipeline(self, resolution: int | None = None, entry: str = "main"):
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
    """The buffers of compact.wgsl (bindings 13-15) for up to ``n`` items: the list of items to
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
        return {13: {"buffer": self.todo}, 14: {"buffer": self.todo_n}, 15: {"buffer": self.ind}}


#: bindings of the ``args`` entry point (compact.wgsl)
ARGS_BINDINGS = (13, 14, 15)


def dispatch_compacted(cp, pipes: dict, binds: dict, cull_grid, ind) -> None:
    """Record ``cull`` over ``cull_grid`` workgroups, then ``args``, then ``main`` over the
    items ``cull`` kept (indirect) into the open compute pass ``cp``."""
    cp.set_pipeline(pipes["cull"])
    cp.set_bind_group(0, binds["cull"])
    cp.dispatch_workgroups(*cull_grid, 1)
    cp.set_pipeline(pipes["args"])
    cp.set_bind_group(0, binds["args"])
    cp.dispatch_workgroups(1, 1, 1)
    cp.set_pipeline(pipes["main"])
    cp.set_bind_group(0, binds["main"])
    cp.dispatch_workgroups_indirect(ind, 0)


class TextureTarget:
    """One (object, eye) radiance texture with its uniforms, compaction buffers and bind groups.

    An update is three dispatches (texture_space.wgsl): ``cull`` keeps the front-facing blocks of
    the candidate list, ``args`` turns their count into indirect workgroup counts, ``main``
    shades only those blocks."""

    def __init__(
        self, tpass: TextureSpacePass, gatlas: GpuAtlas, counters: CounterBuffer, mips: bool = False
    ):
        import wgpu

        from vrneural.runtime.radiance_mips import MipChain, mip_count

        dev = get_device()
        self.tpass = tpass
        self.gatlas = gatlas
        self.R = gatlas.resolution
        self.pipes = {e: tpass.pipeline(self.R, e) for e in ("cull", "args", "main")}
        self.pipe = self.pipes["main"]
        u = wgpu.BufferUsage.UNIFORM | wgpu.BufferUsage.COPY_DST
        self.params = dev.create_buffer(size=PARAMS_BYTES, usage=u)
        self.lights = dev.create_buffer(size=32 * tpass.n_lights, usage=u)
        levels = mip_count(self.R) if mips else 1
        self.texture = new_radiance_texture(self.R, fmt=tpass.radiance_format, mips=levels)
        self.view = self.texture.create_view(base_mip_level=0, mip_level_count=1)  # written
        self.sample_view = self.texture.create_view()  # every level: the forward pass's
        #: rebuilds levels 1.. after an update (None: a single level)
        self.mips = MipChain(self.texture, levels) if levels > 1 else None
        self.compact = CompactionBuffers(gatlas.non_empty_blocks)
        self.counters = counters
        self.binds: dict = {}

    def _bind(self, entry: str, period: int):
        """Bind group of one entry point (auto layouts differ per entry point)."""
        key = (entry, period if entry == "cull" else 0)
        if key not in self.binds:
            g, tp = self.gatlas, self.tpass
            geo = g.geometry()
            res = {
                0: {"buffer": self.params},
                1: {"buffer": self.lights},
                2: {"buffer": geo["pos"]},
                3: {"buffer": geo["nrm"]},
                4: {"buffer": geo["tan"]},
                16: {"buffer": geo["uv01"]},
                17: {"buffer": geo["uv23"]},
                5: self.view,
                6: {"buffer": self.counters.buf},
                12: {"buffer": g.block_list(period)[0]},
                **self.compact.resources(),
            }
            res.update({e["binding"]: e["resource"] for e in tp.gmat.entries(7)})
            used = {"cull": (0, 2, 3, 6, 12, 13, 14), "args": ARGS_BINDINGS}
            keys = used.get(entry, tuple(k for k in res if k not in (12, 14, 15)))
            self.binds[key] = get_device().create_bind_group(
                layout=self.pipes[entry].get_bind_group_layout(0),
                entries=[{"binding": k, "resource": res[k]} for k in keys],
            )
        return self.binds[key]

    def update(
        self, model, eye, tiling, light_pos, light_rgb, phase=0, period=1, slot=0, margin=0.0
    ):
        """Write this dispatch's uniforms (call before encoding it). World quantities are made
        camera-relative in float64 first (:func:`~vrneural.runtime.reference.camera_relative`).
        ``margin``: see :func:`pack_params`."""
        model, eye, light_pos = camera_relative(model, eye, light_pos)
        span = self.gatlas.block_list(period)[1][phase]
        q = get_device().queue
        q.write_buffer(self.params, 0, pack_params(model, eye, tiling, *span, slot, margin))
        q.write_buffer(self.lights, 0, pack_lights(light_pos, light_rgb, self.tpass.n_lights))

    def encode(self, encoder, phase=0, period=1, timestamp_writes=None) -> None:
        """Dispatch the block rows ``phase, phase + period, ...`` in a compute pass of its own."""
        cp = encoder.begin_compute_pass(timestamp_writes=timestamp_writes)
        self.dispatch(cp, phase, period)
        cp.end()

    def dispatch(self, cp, phase=0, period=1) -> None:
        """Record this target's three dispatches into an open compute pass ``cp`` (after
        :meth:`update` with the same ``phase, period``)."""
        n = self.gatlas.block_list(period)[1][phase][1]
        if n:
            binds = {e: self._bind(e, period) for e in self.pipes}
            dispatch_compacted(cp, self.pipes, binds, grid(n), self.compact.ind)
            if self.mips is not None:  # after the texels it averages (dispatches are ordered)
                self.mips.dispatch(cp)


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
):
    """GPU texture-space pass on a fresh (zeroed) texture; returns ``(radiance [R, R, 4]
    float32, counters [4])`` like the numpy twin of the same name. ``subgroups``: None = use
    them where the device has the feature; ``margin``: see :func:`pack_params`."""
    lp = np.asarray(light_pos, np.float64).reshape(-1, 3)
    tp = TextureSpacePass(
        mat,
        precision,
        len(lp),
        weights,
        radiance_format=radiance_format,
        subgroups=subgroups,
    )
    counters = CounterBuffer(1)
    tgt = TextureTarget(tp, GpuAtlas(atlas), counters)
    tgt.update(model, eye, tiling, lp, light_rgb, phase, period, 0, margin)
    enc = get_device().create_command_encoder()
    tgt.encode(enc, phase, period)
    get_device().queue.submit([enc.finish()])
    rad = read_texture(tgt.texture).astype(np.float32)
    return rad, counters.read()[0].astype(np.int64)
