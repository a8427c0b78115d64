"""GPU resources of a neural material and of an atlased mesh.

- Neural textures ``[H, W, C]`` float16 become ``rgba32uint`` 2D array textures with
  ``ceil(C / 8)`` layers: 8 float16 channels per texel and layer, two per u32 (channel 2k in the
  low half, 2k + 1 in the high half; zero-padded), read by ``textureLoad`` and
  ``unpack2x16float``. One 128-bit load brings 8 channels: half the loads of 4-channel
  ``rgba16float`` layers (measured on llvmpipe: see docs/runtime.md), same values.
- Weights: constants in the generated code; or one float32 storage buffer in
  :func:`vrneural.runtime.codegen.packed_weights` layout (``"storage"``, ``"streamed"``); or uniform
  buffers in :func:`vrneural.runtime.codegen.uniform_weights` layout (``"uniform"``).
- An atlas becomes two storage buffers: ``verts`` (4 vec4 per vertex: ``pos.xyz, atlas_u``;
  ``normal.xyz, atlas_v``; ``tangent.xyzw``; ``material_uv.xy, 0, 0``) and ``faces`` ``[F*3]``
  u32 (the screen pass), plus, built once on first use by
  the texture-space pass, the *geometry atlas* (``GpuAtlas.geometry``): per non-empty 2x2
  block, five ``vec4<f32>`` arrays (struct of arrays: each at most ``R * R / 4 * 16`` bytes, the
  size of an ``R * R`` u32 image) holding what ``reference.block_geometry`` computes.
"""

from __future__ import annotations

import numpy as np

from vrneural.atlas.types import Atlas
from vrneural.gpu.device import get_device
from vrneural.gpu.readback import upload_buffer, upload_texture
from vrneural.material import ARCHS, NeuralMaterial
from vrneural.runtime.codegen import packed_weights, uniform_weights
from vrneural.runtime.reference import block_geometry


def _words(tex: np.ndarray) -> np.ndarray:
    """``[H, W, C]`` float16 -> ``[layers, H, W, 4]`` u32: 8 channels per texel and layer."""
    h, w, c = tex.shape
    data = np.zeros((h, w, -(-c // 8) * 8), np.float16)
    data[..., :c] = tex
    data = data.reshape(h, w, -1, 8).transpose(2, 0, 1, 3)
    return np.ascontiguousarray(np.ascontiguousarray(data).view("<u4"))  # (lo, hi) half pairs


def _halves(tex: np.ndarray) -> np.ndarray:
    """``[H, W, C]`` float16 -> ``[layers, H, W, 4]`` float16: 4 channels per texel and layer."""
    h, w, c = tex.shape
    data = np.zeros((h, w, -(-c // 4) * 4), np.float16)
    data[..., :c] = tex
    return np.ascontiguousarray(data.reshape(h, w, -1, 4).transpose(2, 0, 1, 3))


def upload_feature_texture(tex: np.ndarray, label: str = "", levels=(), filtering: str = "exact"):
    """``tex: [H, W, C]`` float16 -> a ``texture_2d_array``, with ``levels`` (the pyramid's
    levels 1.., each ``[H >> k, W >> k, C]``) as its mip levels: for ``filtering`` "exact"
    rgba32uint (8 float16 channels per texel and layer, ceil(C/8) layers), for "hardware"
    rgba16float (4 channels per layer, ceil(C/4) layers; the same values, filterable)."""
    import wgpu

    h, w, c = tex.shape
    hw = filtering == "hardware"
    layers = (c + 3) // 4 if hw else (c + 7) // 8
    dev = get_device()
    t = dev.create_texture(
        size=(w, h, layers),
        mip_level_count=1 + len(levels),
        format="rgba16float" if hw else "rgba32uint",
        usage=wgpu.TextureUsage.TEXTURE_BINDING | wgpu.TextureUsage.COPY_DST,
        label=label,
    )
    for k, a in enumerate([tex, *levels]):
        lh, lw = a.shape[:2]
        dev.queue.write_texture(
            {"texture": t, "mip_level": k},
            _halves(a) if hw else _words(a),
            {"bytes_per_row": lw * (8 if hw else 16), "rows_per_image": lh},
            (lw, lh, layers),
        )
    return t


def neural_sampler():
    """The sampler of filtering "hardware": wrap (repeat), bilinear, linear between levels."""
    return get_device().create_sampler(
        address_mode_u="repeat",
        address_mode_v="repeat",
        mag_filter="linear",
        min_filter="linear",
        mipmap_filter="linear",
        label="neural",
    )


class GpuMaterial:
    """Textures (and the weight buffers, for buffer weights) of one material on the device."""

    def __init__(self, mat: NeuralMaterial, weights: str = "constants", filtering: str = "exact"):
        import wgpu

        self.mat = mat
        names = ARCHS[mat.arch][1]
        self.textures = [
            upload_feature_texture(mat.textures[n], f"neural.{n}", mat.levels.get(n, ()), filtering)
            for n in names
        ]
        self.views = [t.create_view(dimension="2d-array") for t in self.textures]
        #: the sampler of filtering "hardware" (neural textures and height field), else None
        self.sampler = neural_sampler() if filtering == "hardware" else None
        #: the height field of a parallax material (``[H, W]``: the float16 values exactly;
        #: r32float read with ``textureLoad``, or r16float through the sampler for filtering
        #: "hardware"; see neural_material.wgsl), else None
        self.height = None
        if mat.parallax_steps:
            fmt = "r32float" if self.sampler is None else "r16float"  # casts the heights
            tb = wgpu.TextureUsage.TEXTURE_BINDING
            self.height = upload_texture(mat.height, fmt, tb, "neural.height")
        #: the offset texture of a neural-offset material (as the neural textures), else None
        self.offset = None
        if mat.parallax_kind == "neural":
            self.offset = upload_feature_texture(
                mat.offset_tex, "neural.offset", filtering=filtering
            )
        self.weights, self.uniforms = None, []
        if weights in ("storage", "streamed"):
            self.weights = upload_buffer(packed_weights(mat), wgpu.BufferUsage.STORAGE, "weights")
        elif weights == "uniform":
            u = wgpu.BufferUsage.UNIFORM
            self.uniforms = [
                upload_buffer(w, u, f"weights.{i}") for i, w in enumerate(uniform_weights(mat))
            ]

    def resources(self) -> dict:
        """Its resources by binding name (runtime/interface.py:material_bindings)."""
        out = dict(zip(("tex_a", "tex_b"), self.views, strict=False))
        if self.sampler is not None:
            out["neural_samp"] = self.sampler
        if self.weights is not None:
            out["weights"] = {"buffer": self.weights}
        for i, b in enumerate(self.uniforms):
            last = i == len(self.uniforms) - 1
            out["wbias" if last else f"wl{i}"] = {"buffer": b}
        if self.height is not None:
            out["height_tex"] = self.height.create_view()
        if self.offset is not None:
            out["off_tex"] = self.offset.create_view(dimension="2d-array")
        return out


class GpuAtlas:
    """Storage buffers of one atlas (shared by both eyes)."""

    def __init__(self, atlas: Atlas):
        import wgpu

        if atlas.resolution % 2:
            raise ValueError(f"atlas resolution {atlas.resolution} must be even (2x2 blocks)")
        self.atlas = atlas
        self.resolution = atlas.resolution
        s = wgpu.BufferUsage.STORAGE
        mesh, uv = atlas.mesh, atlas.uv_atlas
        t = np.zeros((len(mesh.positions), 4, 4), np.float32)  # verts: see the module docstring
        t[:, 0, :3] = mesh.positions
        t[:, 0, 3] = uv[:, 0]
        t[:, 1, :3] = mesh.normals
        t[:, 1, 3] = uv[:, 1]
        t[:, 2, :] = mesh.tangents
        t[:, 3, :2] = mesh.uv
        self.verts = upload_buffer(t, s, "verts")
        self.faces = upload_buffer(np.asarray(atlas.mesh.faces, np.uint32).ravel(), s, "faces")
        self._lists: dict[int, tuple] = {}
        self._geometry: dict | None = None

    @property
    def non_empty_blocks(self) -> int:
        """Blocks of the geometry atlas (the texture-space pass's candidates)."""
        return len(self.geometry()["by"])

    def geometry(self) -> dict:
        """The geometry atlas, built on first use and kept: ``by, bx`` of the non-empty blocks
        (numpy) and its storage buffers, each ``[N]`` ``vec4<f32>``: ``pos`` (object position,
        ``bitcast<f32>(by << 16 | bx)``), ``nrm`` (object normal, tangent handedness),
        ``tan`` (object tangent; w: one atlas texel's untiled material-UV length, the LOD
        footprint), ``uv01`` and ``uv23`` (untiled material UVs of texels
        0, 1 and 2, 3). The texture-space kernels read these instead of the mesh: no triangle
        fetch or barycentrics per update (docs/runtime.md)."""
        if self._geometry is None:
            import wgpu

            if self.resolution // 2 > 0xFFFF:
                raise ValueError(
                    f"atlas resolution {self.resolution} exceeds the packed block index "
                    "(max 131070)"
                )
            g = block_geometry(self.atlas)
            n = len(g["by"])
            arr = np.zeros((5, max(n, 1), 4), np.float32)
            packed = (g["by"].astype(np.uint32) << 16) | g["bx"].astype(np.uint32)
            arr[0, :n, :3] = g["pos"]
            arr[0, :n, 3] = packed.view(np.float32)
            arr[1, :n, :3] = g["nrm"]
            arr[1, :n, 3] = np.where(g["tan"][:, 3] >= 0, 1.0, -1.0)
            arr[2, :n, :3] = g["tan"][:, :3]
            arr[2, :n, 3] = g["foot"]  # one atlas texel's material-uv length (LOD)
            arr[3, :n] = g["uv"][:, :2].reshape(n, 4)
            arr[4, :n] = g["uv"][:, 2:].reshape(n, 4)
            s = wgpu.BufferUsage.STORAGE | wgpu.BufferUsage.COPY_SRC
            names = ("pos", "nrm", "tan", "uv01", "uv23")
            self._geometry = {
                k: upload_buffer(arr[i], s, f"geometry/{k}") for i, k in enumerate(names)
            }
            self._geometry.update(by=g["by"], bx=g["bx"])
        return self._geometry

    def block_list(self, period: int):
        """The candidate blocks of the texture-space pass for a row period: a storage buffer of
        indices into :meth:`geometry` (the non-empty 2x2 blocks, row-major), grouped by phase
        (``by % period``), and ``[(offset, count)]`` per phase. Built once per period."""
        import wgpu

        if period not in self._lists:
            phase = self.geometry()["by"] % period
            idx = np.argsort(phase, kind="stable").astype(np.uint32)  # row-major in each phase
            n = np.bincount(phase, minlength=period)
            spans = [(int(o), int(k)) for o, k in zip(np.cumsum(n) - n, n, strict=True)]
            data = np.concatenate([idx, np.zeros(1, np.uint32)])  # never an empty buffer
            buf = upload_buffer(
                data, wgpu.BufferUsage.STORAGE | wgpu.BufferUsage.COPY_SRC, f"blocks/{period}"
            )
            self._lists[period] = (buf, spans)
        return self._lists[period]


def new_radiance_texture(
    resolution: int, label: str = "radiance", fmt: str = "rgba16float", mips: int = 1
):
    """A radiance texture (storage-written, sampled, copyable), zeroed: ``rgba16float`` (the
    runtime's) or ``rgba32float`` (the wider option: no f16 clamp, twice the memory; sampling it
    bilinearly needs the float32-filterable feature); ``mips`` levels (runtime/radiance_mips.py)."""
    import wgpu

    return get_device().create_texture(
        size=(resolution, resolution, 1),
        mip_level_count=mips,
        format=fmt,
        usage=wgpu.TextureUsage.STORAGE_BINDING
        | wgpu.TextureUsage.TEXTURE_BINDING
        | wgpu.TextureUsage.COPY_SRC,
        label=label,
    )
