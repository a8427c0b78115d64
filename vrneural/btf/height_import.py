"""A measured height field for `vrneural btf import --height FILE` (issue #44).

Measured BTFs come with their tile's height field beside the images (the mobile-VR paper's
parallax relies on UBO2014's; btf-extractor, which reads the ``.btf`` files, does not expose
one), so the import takes it as a separate file: a ``.npy`` array ``[N, N]`` or a one-channel
image (EXR, PFM, TIFF, PNG: the first channel; integer images are read as values in [0, 1],
not sRGB). ``scale`` converts its values to UV units (fractions of the tile's width: for a map
in millimetres of a tile ``w`` mm wide, ``1 / w``); the mean is removed, as the reference plane
of rectified slices is the mean height (docs/conventions.md). A size that is not a whole
multiple of the texels is resampled bilinearly to the nearest one
(:func:`vrneural.btf.heightfield.texel_height`).
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path

import numpy as np

from vrneural.btf.heightfield import texel_height
from vrneural.errors import VrnError


def _read(path: Path) -> np.ndarray:
    if path.suffix.lower() == ".npy":
        try:
            a = np.load(path, allow_pickle=False)
        except (ValueError, OSError) as e:
            raise VrnError(f"{path}: cannot read it as a .npy array ({e})") from None
        if a.ndim == 3 and a.shape[2] == 1:
            a = a[..., 0]
        if a.ndim != 2 or a.dtype.kind not in "iuf":
            raise VrnError(f"{path}: a {a.dtype} array of shape {list(a.shape)}; expected [N, N]")
        return a.astype(np.float64)
    import OpenImageIO as oiio  # noqa: N813

    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        msg = oiio.geterror().strip().splitlines()
        raise VrnError(f"{path}: cannot read it as an image ({msg[0] if msg else 'unknown'})")
    spec = inp.spec()
    px = inp.read_image(0, 0, 0, 1, oiio.FLOAT)
    inp.close()
    if px is None:
        raise VrnError(f"{path}: cannot read its pixels ({oiio.geterror().strip()})")
    return np.asarray(px, np.float64).reshape(spec.height, spec.width)


def read_height(path, scale: float, size: tuple[int, int]) -> tuple[np.ndarray, dict]:
    """The height field in ``path`` for a BTF of ``size = (H, W)`` texels: ``([M, M]`` float32,
    UV units, mean 0, ``M`` a multiple of ``W``; the record the BTF's header keeps
    (source, SHA-256, scale)). One-line :class:`VrnError` for a missing or unreadable file,
    non-finite values, a shape that is not square or texels that are not, a bad scale."""
    path = Path(path)
    if not (isinstance(scale, (int, float)) and math.isfinite(scale) and scale > 0):
        raise VrnError(f"--height-scale = {scale!r}; allowed: a finite number > 0 (UV units)")
    if not path.is_file():
        raise VrnError(f"--height: {path} does not exist or is not a file")
    h = _read(path)
    if h.shape[0] != h.shape[1] or h.shape[0] < 2:
        raise VrnError(
            f"{path}: height field {h.shape[0]}x{h.shape[1]}; expected a square [N, N], N >= 2 "
            "(the tile, as the BTF's texels)"
        )
    if size[0] != size[1]:
        raise VrnError(
            f"--height: the BTF's texels are {size[0]}x{size[1]}; a height field needs square "
            "texels (crop the images)"
        )
    if not np.isfinite(h).all():
        raise VrnError(f"{path}: the height field contains {int((~np.isfinite(h)).sum())} NaN/Inf")
    h = (h - h.mean()) * float(scale)
    rec = {
        "source": str(path),
        "sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
        "scale": float(scale),
    }
    return texel_height(h.astype(np.float32), size[1]), rec
