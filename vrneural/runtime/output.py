"""Run outputs: tonemapped PNGs, HDR EXRs, a side-by-side stereo video, summary.json.

Tonemap: exposure, Reinhard ``x / (1 + x)`` per channel, sRGB encoding, 8 bits.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

from vrneural.errors import VrnError
from vrneural.outputs import atomic_path, make_parent


def tonemap(hdr: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """``hdr: [H, W, >=3]`` linear radiance -> ``[H, W, 3]`` uint8 sRGB."""
    x = np.maximum(np.nan_to_num(hdr[..., :3].astype(np.float32)) * exposure, 0)
    x = x / (1 + x)
    s = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.clip(np.round(s * 255), 0, 255).astype(np.uint8)


def write_png(path: Path, img: np.ndarray) -> Path:
    import imageio.v3 as iio

    with atomic_path(path) as tmp:
        iio.imwrite(tmp, img, extension=".png")
    return path


def write_exr(path: Path, hdr: np.ndarray) -> Path:
    """``hdr: [H, W, 3|4]`` float -> half-float EXR (OpenImageIO)."""
    from OpenImageIO import ImageOutput, ImageSpec, geterror

    a = np.ascontiguousarray(hdr[..., :3], np.float32)
    h, w, c = a.shape
    with atomic_path(path) as tmp:
        tmp_exr = tmp.with_suffix(".exr")
        try:  # OpenImageIO takes UTF-8 names only: a path with other bytes goes via /tmp
            str(tmp_exr).encode("utf-8")
        except UnicodeEncodeError:
            fd, name = tempfile.mkstemp(suffix=".exr", prefix=".vrneural-")
            os.close(fd)
            tmp_exr = Path(name)
        try:
            out = ImageOutput.create(str(tmp_exr))
            if out is None:
                raise VrnError(f"{path}: OpenImageIO cannot write EXR ({geterror()})")
            spec = ImageSpec(w, h, c, "half")
            if not out.open(str(tmp_exr), spec) or not out.write_image(a) or not out.close():
                raise VrnError(f"{path}: OpenImageIO cannot write EXR ({geterror()})")
            shutil.move(tmp_exr, tmp)
        finally:
            tmp_exr.unlink(missing_ok=True)
    return path


def downscale(img: np.ndarray, factor: int) -> np.ndarray:
    """Box-filter ``img: [H, W, C]`` by an integer ``factor`` (crops the remainder)."""
    if factor <= 1:
        return img
    h, w = img.shape[0] // factor * factor, img.shape[1] // factor * factor
    a = img[:h, :w].astype(np.float32).reshape(h // factor, factor, w // factor, factor, -1)
    return a.mean(axis=(1, 3))


def check_video() -> None:
    """Raise :class:`VrnError` unless imageio-ffmpeg is installed."""
    try:
        import imageio_ffmpeg  # noqa: F401
    except ImportError:
        raise VrnError(
            "--video needs the imageio-ffmpeg package: pip install imageio-ffmpeg"
        ) from None


class VideoWriter:
    """Side-by-side stereo H.264 video (imageio + imageio-ffmpeg), written atomically."""

    def __init__(self, path: Path, fps: float):
        check_video()
        import imageio.v2 as iio2

        self.path = make_parent(path)
        self.tmp = self.path.with_name(f".{self.path.stem}.tmp.mp4")
        self.w = iio2.get_writer(
            str(self.tmp), fps=fps, codec="libx264", quality=7, macro_block_size=2
        )

    def add(self, eyes_ldr: list[np.ndarray]) -> None:
        frame = np.concatenate(eyes_ldr, axis=1)
        h, w = frame.shape[0] // 2 * 2, frame.shape[1] // 2 * 2
        self.w.append_data(np.ascontiguousarray(frame[:h, :w]))

    def close(self) -> Path:
        self.w.close()
        self.tmp.replace(self.path)
        return self.path

    def abort(self) -> None:
        """Stop encoding and remove the partial video (the run failed; nothing to keep)."""
        try:
            self.w.close()
        except Exception:  # ffmpeg on a full disk: any error; there is nothing to save
            pass
        self.tmp.unlink(missing_ok=True)
