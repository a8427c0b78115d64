"""GPU resources of a neural material and of an atlased mesh.

- Neural textures ``[H, W, C]`` float16 become ``rgba32uint`` 2D array textures with
  ``ceil(C / 8)`` layers: 8 float16 channels per texel and layer, two per u32 (channel 2k in the
  low half, 2k + 1 in the high half; zero-padded), read by ``textureLoad`` and
  ``unpack2x16float``. One 128-bit load brings 8 channels: half the loads of 4-channel
  ``rgba16float`` layers (measured on llvmpipe: see README, Runtime), same values.
- Weights: constants in the generated code, or (buffer variant) one float32 storage buffer in
  :func:`vrneural.runtime.codegen.packed_weights` layout.
- An atlas becomes three storage buffers: ``verts`` (4 vec4 per vertex: ``pos.xyz, atlas_u``;
  ``normal.xyz, atlas_v``; ``tangent.xyzw``; ``material_uv.xy, 0, 0``), ``faces`` ``[F*3]`` u32
  and ``tri_ids`` ``[R*R]`` u32.
"""

from __future__ import annotations

import numpy as np

from vrneural.atlas.types import Atlas, Mesh
from vrneural.gpu.device import get_device
from vrneural.gpu.readback import upload_buffer
from vrneural.material import ARCHS, NeuralMaterial
from vrneural.runtime.codegen import packed_weights
from vrneural.runtime.reference import count_non_empty_blocks, non_empty_blocks


def upload_feature_texture(tex: np.ndarray, label: str = ""):
    """``tex: [H, W, C]`` float16 -> a ``texture_2d_array`` (rgba32uint, 8 float16 channels
    per texel and layer, ceil(C/8) layers)."""
    import wgpu

    h, w, c = tex.shape
    layers = (c + 7) // 8
    data = np.zeros((layers, h, w, 8), np.float16)
    for i in range(layers):
        part = np.asarray(tex[:, :, 8 * i : 8 * i + 8], np.float16)
        data[i, :, :, : part.shape[2]] = part
    words = np.ascontiguousarray(data).view("<u4")  # [layers, h, w, 4]: (lo, hi) half pairs
    dev = get_device()
    t = dev.create_texture(
        size=(w, h, layers),
        format="rgba32uint",
        usage=wgpu.TextureUsage.TEXTURE_BINDING | wgpu.TextureUsage.COPY_DST,
        label=label,
    )
    dev.queue.write_texture(
        {"texture": t},
        np.ascontiguousarray(words),
        {"bytes_per_row": w * 16, "rows_per_image": h},
        (w, h, layers),
    )
    return t


class GpuMaterial:
    """Textures (and optionally the weight buffer) of one material on the device."""

    def __init__(self, mat: NeuralMaterial, buffer_weights: bool = False):
        import wgpu

        self.mat = mat
        self.buffer_weights = buffer_weights
        names = ARCHS[mat.arch][1]
        self.textures = [upload_feature_texture(mat.textures[n], f"neural.{n}") for n in names]
        self.views = [t.create_view(dimension="2d-array") for t in self.textures]
        self.weights = (
            upload_buffer(packed_weights(mat), wgpu.BufferUsage.STORAGE, "weights")
            if buffer_weights
            else None
        )

    def entries(self, first_binding: int) -> list[dict]:
        """Bind-group entries matching ``neural_material.wgsl:bindings(mat, first_binding)``."""
        out = [{"binding": first_binding + i, "resource": v} for i, v in enumerate(self.views)]
        if self.weights is not None:
            out.append({"binding": first_binding + 2, "resource": {"buffer": self.weights}})
        return out


def vertex_table(mesh: Mesh, uv_atlas: np.ndarray) -> np.ndarray:
    """The ``verts`` storage layout: ``[V, 4, 4]`` float32 (see module docstring)."""
    v = mesh.positions.shape[0]
    t = np.zeros((v, 4, 4), np.float32)
    t[:, 0, :3] = mesh.positions
    t[:, 0, 3] = uv_atlas[:, 0]
    t[:, 1, :3] = mesh.normals
    t[:, 1, 3] = uv_atlas[:, 1]
    t[:, 2, :] = mesh.tangents
    t[:, 3, :2] = mesh.uv
    return t


class GpuAtlas:
    """Storage buffers of one atlas (shared by both eyes)."""

    def __init__(self, atlas: Atlas):
        import wgpu

        if atlas.resolution % 2:
            raise ValueError(f"atlas resolution {atlas.resolution} must be even (2x2 blocks)")
        self.atlas = atlas
        self.resolution = atlas.resolution
        s = wgpu.BufferUsage.STORAGE
        self.verts = upload_buffer(vertex_table(atlas.mesh, atlas.uv_atlas), s, "verts")
        self.faces = upload_buffer(np.asarray(atlas.mesh.faces, np.uint32).ravel(), s, "faces")
        self.tri_ids = upload_buffer(np.asarray(atlas.tri_ids, np.uint32).ravel(), s, "tri_ids")
        self.non_empty_blocks = int(count_non_empty_blocks(atlas.tri_ids))
        self._lists: dict[int, tuple] = {}

    def block_list(self, period: int):
        """The candidate blocks of the texture-space pass for a row period: a storage buffer of
        the non-empty 2x2 blocks (packed ``by << 16 | bx``, row-major), grouped by phase
        (``by % period``), and ``[(offset, count)]`` per phase. Built once per period."""
        import wgpu

        if period not in self._lists:
            if self.resolution // 2 > 0xFFFF:
                raise ValueError(
                    f"atlas resolution {self.resolution} exceeds the packed block index "
                    "(max 131070)"
                )
            by, bx = non_empty_blocks(self.atlas.tri_ids)
            packed, spans, off = [], [], 0
            for ph in range(period):
                sel = by % period == ph
                packed.append((by[sel].astype(np.uint32) << 16) | bx[sel].astype(np.uint32))
                spans.append((off, int(sel.sum())))
                off += int(sel.sum())
            data = np.concatenate([*packed, np.zeros(1, np.uint32)])  # never an empty buffer
            buf = upload_buffer(
                data, wgpu.BufferUsage.STORAGE | wgpu.BufferUsage.COPY_SRC, f"blocks/{period}"
            )
            self._lists[period] = (buf, spans)
        return self._lists[period]


def new_radiance_texture(resolution: int, label: str = "radiance", fmt: str = "rgba16float"):
    """A radiance texture (storage-written, sampled, copyable), zeroed: ``rgba16float`` (the
    runtime's) or ``rgba32float`` (the wider option: no f16 clamp, twice the memory; sampling it
    bilinearly needs the float32-filterable feature)."""
    import wgpu

    return get_device().create_texture(
        size=(resolution, resolution, 1),
        format=fmt,
        usage=wgpu.TextureUsage.STORAGE_BINDING
        | wgpu.TextureUsage.TEXTURE_BINDING
        | wgpu.TextureUsage.COPY_SRC,
        label=label,
    )
