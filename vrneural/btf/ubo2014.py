"""UBO2014 ``.btf`` import through the ``btf-extractor`` package.

The UBO2014 files are read by btf-extractor's ``Ubo2014`` (a Cython wrapper around Zdravko
Velinov's ``btf.hh``), which returns BGR float32 images ``[H, W, 3]`` per (light, view) angle
tuple ``(theta_l, phi_l, theta_v, phi_v)`` in degrees (rounded to 0.1). We convert BGR -> RGB,
angles -> unit vectors, and stream every slice into our format.

``btf.hh``'s loader returns NULL on a malformed file and the wrapper then dereferences it
(a segfault), so :func:`parse_header` validates the file in Python first: magic, header, the
direction tables and the exact file length of the factorised data ("DFMF" and "FMF0/1").

Files in the "!DFMF08FC" layout for the tests are written by ``write_dfmf`` of
``tests/btf_helpers.py``.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from vrneural.btf.dirs import spherical
from vrneural.btf.format import BtfWriter
from vrneural.errors import VrnError, input_file

INSTALL_HINT = "pip install 'vrneural[ubo]' (or: pip install btf-extractor)"
_COMMON = struct.Struct("<II80s80s80sf3f")  # BTFCommonHeader, 264 bytes


def load_extractor():
    """btf-extractor's ``Ubo2014`` class, or a one-line :class:`VrnError` saying how to install.

    btf-extractor 1.7.0's package ``__init__`` also imports its UBO2003 reader, which needs
    ``nptyping`` and ``simplejpeg``; the UBO2014 reader itself is the compiled module
    ``ubo2014_cy`` that the package ships, so we fall back to importing it directly.
    """
    try:
        from btf_extractor import Ubo2014

        return Ubo2014
    except ImportError:
        pass
    try:
        from ubo2014_cy import Ubo2014

        return Ubo2014
    except ImportError:
        raise VrnError(f"btf-extractor is not installed; install it with: {INSTALL_HINT}") from None


class _Reader:
    def __init__(self, path: Path, data: bytes):
        self.path, self.data, self.pos = path, data, 0

    def take(self, n: int) -> bytes:
        if self.pos + n > len(self.data):
            raise VrnError(f"{self.path}: truncated UBO2014 file ({len(self.data)} bytes)")
        b = self.data[self.pos : self.pos + n]
        self.pos += n
        return b

    def u32(self) -> int:
        return struct.unpack("<I", self.take(4))[0]

    def skip(self, n: int) -> None:
        self.take(n)


def parse_header(path) -> dict:
    """Validate a UBO2014 file the way btf.hh's ``LoadBTF`` does, without loading the data.

    Returns ``{"format", "width", "height", "light_angles" [L, 2], "view_angles" [V, 2]}``
    (angles in radians, as stored). Raises :class:`VrnError` on anything LoadBTF would reject.
    """
    p = input_file(path, "a UBO2014 .btf file")
    size = p.stat().st_size
    with open(p, "rb") as f:
        head = f.read(min(size, 1 << 24))  # direction tables and headers are small
    r = _Reader(p, head)
    sig = head[:9]
    known = sig[1:9] in (b"DFMF08FC", b"FMF12FCE") or sig[1:8] == b"FMF06FC"
    if sig[:1] != b"!" or not known:
        raise VrnError(f"{p}: not a UBO2014 BTF file (magic {head[:9]!r}; expected b'!DFMF08FC')")
    fmt = sig[1:5].decode()
    r.skip(9 if sig[1:9] in (b"DFMF08FC", b"FMF12FCE") else 8)
    if head[r.pos : r.pos + 1] == b"R":
        raise VrnError(f"{p}: UBO2014 files with rotation tables are not supported")
    start = r.pos
    hsize, version = struct.unpack("<II", r.take(8))
    r.skip(_COMMON.size - 8)
    channels = 3
    if version > 1:
        r.skip(4)  # cosine flag
    if version > 2:
        r.skip(r.u32())  # XML
    if version > 3:
        channels = r.u32()
        for _ in range(channels):
            r.skip(r.u32())
    if r.pos - start != hsize or channels != 3:
        raise VrnError(f"{p}: unsupported UBO2014 header (size {hsize}, {channels} channels)")
    n_views = r.u32()
    views, lights = [], None
    for _ in range(n_views):
        views.append(struct.unpack("<2f", r.take(8)))
        n_l = r.u32()
        if lights is None:
            lights = [struct.unpack("<2f", r.take(8)) for _ in range(n_l)]
        elif n_l != len(lights):
            raise VrnError(f"{p}: inconsistent light counts ({n_l} vs {len(lights)})")
        else:
            r.skip(8 * n_l)
    width, height = r.u32(), r.u32()
    if not views or not lights or width == 0 or height == 0:
        raise VrnError(f"{p}: empty UBO2014 file ({n_views} views, {width}x{height} texels)")
    end = _data_end(p, fmt, r, size, len(lights), width * height)
    if end != size:
        raise VrnError(f"{p}: UBO2014 data ends at byte {end} but the file has {size} bytes")
    _check_directions(p, "light", lights)
    _check_directions(p, "view", views)
    return {
        "format": fmt,
        "width": width,
        "height": height,
        "light_angles": np.array(lights, np.float32),
        "view_angles": np.array(views, np.float32),
    }


def _check_directions(p: Path, kind: str, angles: list) -> None:
    """Refuse non-finite angles, directions below the horizon (theta > 90 degrees) and pairs of
    directions btf-extractor cannot tell apart, naming the indices and angles.

    btf.hh turns the stored angles (radians) into unit vectors; btf-extractor turns those back
    into ``(degrees(arccos z), degrees(atan2(y, x)) % 360)`` rounded to 0.1 degree and keys its
    slices by them, so two directions whose theta and phi both differ by less than 0.1 degree
    may share a key (one of them then cannot be read). Which way a value on a rounding boundary
    goes depends on float32 details, so every such pair is refused; so is a pair less than 0.01
    degree apart (the same direction, e.g. theta 0 with two phis).
    """
    a = np.asarray(angles, np.float64).reshape(-1, 2)
    deg = np.degrees(a)

    def shown(i: int) -> str:
        return f"{kind} direction {i} (theta {deg[i, 0]:.2f} deg, phi {deg[i, 1]:.2f} deg)"

    for i in range(len(a)):
        if not np.isfinite(a[i]).all():
            raise VrnError(
                f"{p}: {kind} direction {i} has a non-finite angle (theta {a[i, 0]}, phi "
                f"{a[i, 1]} rad); UBO2014 angles must be finite numbers"
            )
        if abs(a[i, 0]) > 2 * np.pi:  # no radian value: degrees, most likely
            raise VrnError(
                f"{p}: {kind} direction {i} has theta {a[i, 0]:g}, not an angle in radians "
                "(UBO2014 stores radians; were degrees written?)"
            )
        if np.cos(a[i, 0]) < -1e-6:  # z < 0 (the margin lets float32 pi/2 through)
            raise VrnError(
                f"{p}: {shown(i)} is below the horizon; directions must have theta <= 90 deg "
                "(pointing away from the surface)"
            )
    d = spherical(a[:, 0], a[:, 1])
    theta = np.degrees(np.arccos(np.clip(d[:, 2], -1, 1)))
    phi = np.degrees(np.arctan2(d[:, 1], d[:, 0])) % 360
    for i in range(1, len(a)):
        dphi = np.abs(phi[:i] - phi[i])
        close = (np.abs(theta[:i] - theta[i]) < 0.1) & (np.minimum(dphi, 360 - dphi) < 0.1)
        sep = np.degrees(np.arctan2(np.linalg.norm(np.cross(d[:i], d[i]), axis=1), d[:i] @ d[i]))
        hit = np.flatnonzero(close | (sep < 0.01))
        if hit.size:
            raise VrnError(
                f"{p}: {shown(int(hit[0]))} and {shown(i)} are the same direction to "
                "btf-extractor (it rounds theta and phi to 0.1 deg); every two directions must "
                "differ by at least 0.1 deg in theta or phi"
            )


def _data_end(p: Path, fmt: str, r: _Reader, size: int, n_lights: int, n_texels: int) -> int:
    """Byte offset where the factorised data ends (the header part is read through ``r``)."""
    if fmt == "DFMF":
        r.skip(4 + 4 + 12 + 36)  # components, colour model, colour mean, colour transform
        pos = r.pos
        for _ in range(3):
            if pos + 13 > size:
                raise VrnError(f"{p}: truncated UBO2014 file ({size} bytes)")
            with open(p, "rb") as f:
                f.seek(pos)
                b = f.read(13)
            dsize = b[0]
            ncomp, rows, cols = struct.unpack("<III", b[1:13])
            if rows != n_lights * n_lights or cols != n_texels or dsize not in (2, 4, 8):
                raise VrnError(
                    f"{p}: UBO2014 matrix {rows}x{cols} (data size {dsize}) does not "
                    f"match {n_lights} directions and {n_texels} texels"
                )
            pos += 13 + (ncomp + rows * ncomp + cols * ncomp) * dsize
        return pos
    hv = r.take(1)[0] if fmt == "FMF1" else 0
    if hv >= 1:
        r.skip(4)
    if hv >= 2:
        hw, hh = struct.unpack("<II", r.take(8))
        r.skip(2 * hw * hh)
    if hv >= 3:
        raise VrnError(f"{p}: unsupported UBO2014 extended header version {hv}")
    c0 = r.u32()
    dsize = r.take(1)[0]
    c1 = r.u32()
    rows, cols = r.u32(), r.u32()
    ncomp = max(1, min(c0, c1))
    if rows != n_lights * n_lights * 3 or cols != n_texels:
        raise VrnError(f"{p}: UBO2014 matrix {rows}x{cols} does not match the directions")
    return r.pos + (ncomp + rows * ncomp + cols * ncomp) * dsize


def _degrees_to_dirs(angles) -> np.ndarray:
    a = np.radians(np.asarray(angles, np.float64))
    return spherical(a[:, 0], a[:, 1])


def import_ubo(src, out, resume: bool = False, progress: bool = True, height=None) -> Path:
    """Convert a UBO2014 ``.btf`` into our format at ``out`` (streaming, one slice at a time).
    ``height``: the tile's height field and its record
    (:func:`vrneural.btf.height_import.read_height`), or None."""

    Ubo2014 = load_extractor()
    src = Path(src)
    hdr = parse_header(src)
    btf = Ubo2014(str(src))
    lights: dict[int, tuple] = {}
    views: dict[int, tuple] = {}
    for (tl, pl, tv, pv), (li, vi) in btf.angles_vs_index_dict.items():
        lights[li] = (tl, pl)
        views[vi] = (tv, pv)
    L, V = len(hdr["light_angles"]), len(hdr["view_angles"])
    for kind, got, n in (("light", lights, L), ("view", views, V)):
        if sorted(got) != list(range(n)):  # parse_header's check should have caught it
            raise VrnError(
                f"{src}: btf-extractor tells apart only {len(got)} of the {n} {kind} directions "
                "(it rounds angles to 0.1 deg); every direction must be distinct"
            )
    light_ang = [lights[i] for i in range(L)]
    view_ang = [views[i] for i in range(V)]
    w_img, h_img, _ = btf.img_shape  # btf-extractor reports (Width, Height, 3)
    meta = {
        "name": src.stem,
        "generator": {
            "tool": "btf-extractor Ubo2014",
            "source": str(src),
            "format": hdr["format"],
            "source_bytes": src.stat().st_size,
        },
        "seed": None,
    }
    if height is not None:
        meta["generator"]["height"] = height[1]
    w = BtfWriter(
        out,
        _degrees_to_dirs(light_ang),
        _degrees_to_dirs(view_ang),
        (h_img, w_img),
        meta,
        resume=resume,
        height=None if height is None else height[0],
    )

    def read(li, v):
        img = np.asarray(btf.angles_to_image(*light_ang[li], *view_ang[v]), np.float32)
        return img[..., ::-1]  # BGR -> RGB

    def nonfinite(li, v, rgb):
        return f"{src}: non-finite values at light {li}, view {v}"

    return w.import_views(read, nonfinite, src, "it", progress)
