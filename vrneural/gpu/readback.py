"""Uploads and read-backs between numpy arrays and GPU buffers/textures."""

from __future__ import annotations

import numpy as np

from vrneural.gpu.device import get_device

# texture format -> (numpy dtype, channels)
_FORMATS = {
    "rgba16float": (np.float16, 4),
    "rgba32float": (np.float32, 4),
    "r32uint": (np.uint32, 1),
    "r32float": (np.float32, 1),
    "rg32float": (np.float32, 2),
    "rgba8unorm": (np.uint8, 4),
    "rgba8unorm-srgb": (np.uint8, 4),
    "bgra8unorm": (np.uint8, 4),
    "bgra8unorm-srgb": (np.uint8, 4),
    "r16float": (np.float16, 1),
    "rg16float": (np.float16, 2),
    "depth32float": (np.float32, 1),
}


def upload_buffer(data: np.ndarray, usage, label: str = ""):
    """A new buffer holding ``data`` (usage flags as for ``create_buffer``)."""
    import wgpu

    dev = get_device()
    arr = np.ascontiguousarray(data)
    size = max(16, (arr.nbytes + 3) // 4 * 4)
    buf = dev.create_buffer(size=size, usage=usage | wgpu.BufferUsage.COPY_DST, label=label)
    if arr.nbytes:
        dev.queue.write_buffer(
            buf, 0, arr.tobytes() + b"\0" * (size - arr.nbytes) if arr.nbytes % 4 else arr
        )
    return buf


def read_buffer(buf, dtype=np.float32, count: int | None = None) -> np.ndarray:
    """Copy a GPU buffer (needs ``COPY_SRC``) into a numpy array."""
    mem = get_device().queue.read_buffer(buf)
    a = np.frombuffer(mem, dtype=dtype)
    return a[:count].copy() if count is not None else a.copy()


def upload_texture(data: np.ndarray, fmt: str, usage, label: str = ""):
    """A 2D texture ``[H, W, C]`` (or ``[H, W]``) in format ``fmt`` holding ``data``."""
    import wgpu

    dtype, ch = _FORMATS[fmt]
    arr = np.ascontiguousarray(data, dtype=dtype)
    h, w = arr.shape[:2]
    if (arr.shape[2] if arr.ndim == 3 else 1) != ch:
        raise ValueError(f"{fmt} needs {ch} channels, got array {arr.shape}")
    dev = get_device()
    tex = dev.create_texture(
        size=(w, h, 1), format=fmt, usage=usage | wgpu.TextureUsage.COPY_DST, label=label
    )
    dev.queue.write_texture(
        {"texture": tex},
        arr,
        {"bytes_per_row": w * ch * arr.itemsize, "rows_per_image": h},
        (w, h, 1),
    )
    return tex


def read_texture(tex, mip_level: int = 0) -> np.ndarray:
    """Copy a 2D texture's level ``mip_level`` (needs ``COPY_SRC``) to numpy ``[H, W, C]``
    (``[H, W]`` if 1 channel)."""
    fmt = str(tex.format)
    dtype, ch = _FORMATS[fmt]
    w, h = max(1, tex.size[0] >> mip_level), max(1, tex.size[1] >> mip_level)
    bpr = w * ch * np.dtype(dtype).itemsize
    mem = get_device().queue.read_texture(
        {"texture": tex, "origin": (0, 0, 0), "mip_level": mip_level},
        {"offset": 0, "bytes_per_row": bpr, "rows_per_image": h},
        (w, h, 1),
    )
    a = np.frombuffer(mem, dtype=dtype).reshape(h, w, ch)
    return (a[..., 0] if ch == 1 else a).copy()
