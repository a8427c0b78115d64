"""Import a BTF given as a folder of images plus a direction table (`vrneural btf import DIR`).

The folder holds one image per (light, view) pair (EXR, HDR, PNG, TIFF, PFM; read with
OpenImageIO) and a direction table, ``directions.csv`` or ``directions.json`` (or ``--table``),
one row per image:

- CSV: a header row naming the columns ``file, theta_i, phi_i, theta_v, phi_v`` (degrees; i =
  light, v = view) or ``file, wi_x, wi_y, wi_z, wo_x, wo_y, wo_z`` (unit vectors);
- JSON: a list of objects with those keys (or ``{"images": [...]}``); ``"wi": [x, y, z]`` and
  ``"wo": [x, y, z]`` may stand for the six vector keys.

Directions point away from the surface in the local frame (docs/conventions.md section 1):
theta in [0, 90] degrees, phi in [-360, 360]. The distinct light and view directions (in the
order they first appear) must form a full grid: every light with every view, exactly once.
Pixel row r, column c of an image is texel (x = c, y = r). Values are BTF values
(docs/conventions.md section 2: cos(theta_i) inside). Images stored as 8- or 16-bit integers
(PNG, most TIFFs) are taken as sRGB-encoded and linearised (``png_linear`` keeps them as they
are); float images (EXR, HDR, PFM, float TIFF) are linear. Grey images become grey RGB, and an
alpha channel is dropped.

Everything the table and the image headers can tell is checked before any output is written:
missing, unreadable or duplicate images, images in the folder that the table does not name,
sizes that differ, angles out of range or not numbers, directions below the horizon, a grid
with a pair missing or given twice. Non-finite pixel values are found while converting: the
unfinished file is then removed (a ``--resume`` would only stop there again).
"""

from __future__ import annotations

import hashlib
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vrneural.btf.format import BtfWriter
from vrneural.btf.imagetable import TABLE_NAMES, Entry, find_table, read_table
from vrneural.errors import VrnError

IMAGE_EXTS = (".exr", ".hdr", ".png", ".tif", ".tiff", ".pfm")
GENERATOR = "vrneural.btf.imageset v1 (OpenImageIO)"

__all__ = ["IMAGE_EXTS", "TABLE_NAMES", "Plan", "import_images", "plan_import"]


@dataclass
class Plan:
    """What an import will do: the grid of files ``files[light][view]``, the directions
    ``[L, 3]`` / ``[V, 3]`` float32, the image size ``(H, W)``, how many images are sRGB
    integer images, and the table's path."""

    folder: Path
    table: Path
    files: list[list[Path]]
    light_dirs: np.ndarray
    view_dirs: np.ndarray
    size: tuple[int, int]
    n_srgb: int


def _distinct(dirs: list[np.ndarray]) -> tuple[np.ndarray, list[int]]:
    """Distinct directions in order of first appearance (within 1e-5) and each row's index."""
    out: list[np.ndarray] = []
    idx = []
    for d in dirs:
        for k, o in enumerate(out):
            if np.abs(o - d).max() < 1e-5:
                idx.append(k)
                break
        else:
            out.append(d)
            idx.append(len(out) - 1)
    return np.array(out, np.float32), idx


def _angles(d: np.ndarray) -> str:
    theta = float(np.degrees(np.arccos(np.clip(d[2], -1, 1))))
    phi = float(np.degrees(np.arctan2(d[1], d[0]))) % 360
    return f"theta {theta:.2f} deg, phi {phi:.2f} deg"


def _grid(table: Path, rows: list[Entry]):
    """``(light_dirs, view_dirs, grid)`` with ``grid[l][v]`` the row of that pair."""
    lights, li = _distinct([r.wi for r in rows])
    views, vi = _distinct([r.wo for r in rows])
    grid: list[list[Entry | None]] = [[None] * len(views) for _ in lights]
    for r, a, b in zip(rows, li, vi, strict=True):
        old = grid[a][b]
        if old is not None:
            raise VrnError(
                f"{table}: {old.row} ({old.file}) and {r.row} ({r.file}) give the same "
                f"(light, view) pair (light {_angles(lights[a])}; view {_angles(views[b])}); "
                "each pair needs exactly one image"
            )
        grid[a][b] = r
    missing = [(a, b) for a in range(len(lights)) for b in range(len(views)) if grid[a][b] is None]
    if missing:
        a, b = missing[0]
        raise VrnError(
            f"{table}: {len(missing)} of the {len(lights)} x {len(views)} (light, view) pairs "
            f"have no image, e.g. light {a} ({_angles(lights[a])}) with view {b} "
            f"({_angles(views[b])}); a BTF needs every light with every view"
        )
    return lights, views, grid


def _spec(path: Path):
    """OpenImageIO's spec of ``path`` (header only), or a one-line error."""
    import OpenImageIO as oiio  # noqa: N813

    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        msg = oiio.geterror().strip().splitlines()
        raise VrnError(
            f"{path}: cannot read it as an image ({msg[0] if msg else 'unknown format'})"
        )
    spec = inp.spec()
    inp.close()
    if spec.nchannels not in (1, 2, 3, 4):
        raise VrnError(f"{path}: {spec.nchannels} channels; expected grey, grey+alpha, RGB or RGBA")
    return spec


def plan_import(folder, table=None, png_linear: bool = False, height=None) -> Plan:
    """Check the folder, the table and every image's header; nothing is written. ``height``:
    the ``--height`` file, which may lie in the folder without a row."""
    folder = Path(folder)
    if not folder.is_dir():
        raise VrnError(f"{folder}: no such folder")
    tpath = find_table(folder, table)
    rows = read_table(tpath)
    seen: dict[str, Entry] = {}
    for r in rows:
        key = str(Path(r.file))
        if key in seen:
            raise VrnError(
                f"{tpath}: {seen[key].row} and {r.row} both name {r.file}; each image "
                "belongs to one (light, view) pair"
            )
        seen[key] = r
        p = folder / r.file
        if not p.is_file():
            raise VrnError(f"{p}: missing image (named in {tpath.name}, {r.row})")
    named = {(folder / r.file).resolve() for r in rows}
    if height is not None:
        named.add(Path(height).resolve())
    extra = sorted(
        str(p.relative_to(folder))
        for p in folder.rglob("*")
        if p.is_file() and p.suffix.lower() in IMAGE_EXTS and p.resolve() not in named
    )
    if extra:
        shown = ", ".join(extra[:5]) + (f" and {len(extra) - 5} more" if len(extra) > 5 else "")
        raise VrnError(
            f"{folder}: {len(extra)} image(s) the table {tpath.name} does not name: {shown}; "
            "add a row for each or move them out of the folder"
        )
    lights, views, grid = _grid(tpath, rows)
    size, first, n_srgb = None, None, 0
    for r in rows:
        p = folder / r.file
        spec = _spec(p)
        if size is None:
            size, first = (spec.height, spec.width), p
        elif (spec.height, spec.width) != size:
            raise VrnError(
                f"{p}: {spec.width}x{spec.height} pixels, but {first.name} has "
                f"{size[1]}x{size[0]}; every image must have the same size"
            )
        n_srgb += not png_linear and _is_integer(spec)
    files = [[folder / grid[a][b].file for b in range(len(views))] for a in range(len(lights))]
    return Plan(folder, tpath, files, lights, views, size, n_srgb)


def _is_integer(spec) -> bool:
    return str(spec.format) in ("uint8", "uint16", "int8", "int16")


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    """The sRGB decoding curve (IEC 61966-2-1) on values in [0, 1]."""
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def read_rgb(path: Path, png_linear: bool = False) -> np.ndarray:
    """One image as linear RGB ``[H, W, 3]`` float32 (see the module docstring)."""
    import OpenImageIO as oiio  # noqa: N813

    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise VrnError(f"{path}: cannot read it as an image ({oiio.geterror().strip()})")
    spec = inp.spec()
    px = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    inp.close()
    if px is None:
        raise VrnError(f"{path}: cannot read its pixels ({oiio.geterror().strip()})")
    px = np.asarray(px, np.float32).reshape(spec.height, spec.width, spec.nchannels)
    rgb = np.repeat(px[..., :1], 3, -1) if spec.nchannels < 3 else px[..., :3]
    if _is_integer(spec) and not png_linear:
        rgb = srgb_to_linear(np.clip(rgb, 0.0, 1.0)).astype(np.float32)
    return np.ascontiguousarray(rgb)


def import_images(
    folder, out, table=None, png_linear: bool = False, resume: bool = False, progress=True,
    height=None,
) -> Path:  # fmt: skip
    """Convert the image set in ``folder`` into ``out`` (streaming, one view at a time).
    ``height``: the tile's height field and its record
    (:func:`vrneural.btf.height_import.read_height`), or None."""

    plan = plan_import(folder, table, png_linear, height and height[1]["source"])
    L, V = len(plan.light_dirs), len(plan.view_dirs)
    meta = {
        "name": plan.folder.resolve().name,
        "generator": {
            "tool": GENERATOR,
            "source": str(plan.folder),
            "table": str(plan.table),
            "table_sha256": hashlib.sha256(plan.table.read_bytes()).hexdigest(),
            "images": L * V,
            "integer_images": "kept as they are" if png_linear else "linearised from sRGB",
        },
        "seed": None,
    }
    if height is not None:
        meta["generator"]["height"] = height[1]
    if plan.n_srgb:
        print(
            f"{plan.folder}: {plan.n_srgb} of the {L * V} images are 8/16-bit integer images "
            "(PNG, TIFF): taken as sRGB and linearised (pass --png-linear if they hold linear "
            "values)",
            file=sys.stderr,
        )
    hf = None if height is None else height[0]
    w = BtfWriter(out, plan.light_dirs, plan.view_dirs, plan.size, meta, resume=resume, height=hf)

    def nonfinite(li, v, rgb):
        return f"{plan.files[li][v]}: {int((~np.isfinite(rgb)).sum())} non-finite values (NaN/Inf)"

    def read(li, v):
        return read_rgb(plan.files[li][v], png_linear)

    return w.import_views(read, nonfinite, plan.folder, "the images", progress)
