"""The direction table of an image-set BTF (:mod:`vrneural.btf.imageset`): CSV or JSON, one
row per image, angles in degrees or unit vectors; every value checked, errors name the row."""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vrneural.errors import VrnError

TABLE_NAMES = ("directions.csv", "directions.json")
ANGLE_KEYS = ("theta_i", "phi_i", "theta_v", "phi_v")
VECTOR_KEYS = ("wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z")


@dataclass
class Entry:
    """One row: the image's path relative to the folder, ``wi`` and ``wo`` (unit ``[3]``
    float64), and where it is for messages (``"line 4"`` of a CSV, ``"image 3"`` of JSON)."""

    file: str
    wi: np.ndarray
    wo: np.ndarray
    row: str


def find_table(folder: Path, table=None) -> Path:
    """``table`` (absolute, or relative to the working folder, then to ``folder``), else the
    one of :data:`TABLE_NAMES` in the folder (both there is an error: which one is meant?)."""
    if table:
        t = Path(table)
        if t.is_absolute():
            if not t.is_file():
                raise VrnError(f"{t}: no such direction table (--table)")
            return t
        inside = Path(folder) / t  # relative: as given (the working folder), then in the folder
        for c in (t, inside):
            if c.is_file():
                return c
        raise VrnError(
            f"--table {table}: no such direction table, neither {t} (from the working folder) "
            f"nor {inside} is a file"
        )
    have = [folder / n for n in TABLE_NAMES if (folder / n).is_file()]
    if not have:
        raise VrnError(
            f"{folder}: no direction table ({' or '.join(TABLE_NAMES)}) in the folder; write "
            "one (columns file, theta_i, phi_i, theta_v, phi_v in degrees) or pass --table FILE"
        )
    if len(have) > 1:
        raise VrnError(f"{folder}: both {TABLE_NAMES[0]} and {TABLE_NAMES[1]}; pass --table FILE")
    return have[0]


def _number(where: str, key: str, value) -> float:
    if isinstance(value, bool):  # JSON true/false: float() would take them as 1 and 0
        raise VrnError(f"{where}: {key} = {value!r} is not a number")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise VrnError(f"{where}: {key} = {value!r} is not a number") from None
    if not math.isfinite(x):
        raise VrnError(f"{where}: {key} = {value!r} is not a finite number")
    return x


def _direction(where: str, kind: str, theta: float, phi: float) -> np.ndarray:
    t, p = f"theta_{kind}", f"phi_{kind}"
    what = "light" if kind == "i" else "view"
    if theta > 90.0:
        raise VrnError(
            f"{where}: {t} = {theta:g} deg puts the {what} below the horizon; allowed [0, 90]"
        )
    if theta < 0.0:
        raise VrnError(f"{where}: {t} = {theta:g} is out of range; allowed [0, 90] (degrees)")
    if not -360.0 <= phi <= 360.0:
        raise VrnError(f"{where}: {p} = {phi:g} is out of range; allowed [-360, 360] (degrees)")
    th, ph = math.radians(theta), math.radians(phi)
    return np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])


def _vector(where: str, name: str, xyz: list[float]) -> np.ndarray:
    d = np.asarray(xyz, np.float64)
    n = float(np.linalg.norm(d))
    what = "light" if name == "wi" else "view"
    if abs(n - 1.0) > 1e-3:
        raise VrnError(f"{where}: {name} = {d.tolist()} is not a unit vector (length {n:.4g})")
    if d[2] < -1e-6:
        raise VrnError(
            f"{where}: {name} = {d.tolist()} puts the {what} below the horizon ({name}_z < 0)"
        )
    d = d / n
    d[2] = max(d[2], 0.0)
    return d


def _entry(where: str, row: str, rec: dict) -> Entry:
    f = str(rec.get("file") or "").strip()
    if not f:
        raise VrnError(f"{where}: no file name (column 'file')")
    if Path(f).is_absolute() or ".." in Path(f).parts:
        raise VrnError(f"{where}: file {f!r} must be a path inside the folder")

    def lacks(keys):  # the keys without a value in this row
        return [k for k in keys if rec.get(k) in (None, "")]

    if not lacks(ANGLE_KEYS):
        a = {k: _number(where, k, rec[k]) for k in ANGLE_KEYS}
        wi = _direction(where, "i", a["theta_i"], a["phi_i"])
        wo = _direction(where, "v", a["theta_v"], a["phi_v"])
    elif not lacks(VECTOR_KEYS):
        x = [_number(where, k, rec[k]) for k in VECTOR_KEYS]
        wi, wo = _vector(where, "wi", x[:3]), _vector(where, "wo", x[3:])
    else:  # name what is missing from the set the row started (angles when neither)
        given = [len(ks) - len(lacks(ks)) for ks in (ANGLE_KEYS, VECTOR_KEYS)]
        missing = lacks(VECTOR_KEYS if given[1] > given[0] else ANGLE_KEYS)
        raise VrnError(
            f"{where}: no value for {', '.join(missing)}; each image needs "
            f"{', '.join(ANGLE_KEYS)} (degrees) or {', '.join(VECTOR_KEYS)} (unit vectors)"
        )
    return Entry(f, wi, wo, row)


def read_table(path: Path) -> list[Entry]:
    """The rows of a CSV or JSON direction table (see the module docstring)."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as e:
        raise VrnError(f"{path}: cannot read the direction table ({e})") from None
    if path.suffix.lower() == ".json":
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as e:
            raise VrnError(f"{path}: not valid JSON ({e.msg}, line {e.lineno})") from None
        items = doc.get("images") if isinstance(doc, dict) else doc
        if not isinstance(items, list):
            raise VrnError(f'{path}: expected a list of images (or {{"images": [...]}})')
        rows = []
        for n, it in enumerate(items, 1):
            if not isinstance(it, dict):
                raise VrnError(f"{path}, image {n}: expected an object with file and directions")
            rec = dict(it)
            for name in ("wi", "wo"):
                v = rec.pop(name, None)
                if isinstance(v, list) and len(v) == 3:
                    rec.update({f"{name}_{c}": x for c, x in zip("xyz", v, strict=True)})
            rows.append(_entry(f"{path}, image {n}", f"image {n}", rec))
    else:
        reader = csv.DictReader(text.splitlines())
        if not reader.fieldnames or "file" not in [k.strip().lower() for k in reader.fieldnames]:
            raise VrnError(
                f"{path}: the first line must name the columns (file, theta_i, phi_i, theta_v, "
                "phi_v or file, wi_x, ..., wo_z)"
            )
        cols = [k.strip().lower() for k in reader.fieldnames]
        if not (set(ANGLE_KEYS) <= set(cols) or set(VECTOR_KEYS) <= set(cols)):
            raise VrnError(
                f"{path}, line 1: the columns are {', '.join(cols)}; they must be file, "
                f"{', '.join(ANGLE_KEYS)} (degrees) or file, {', '.join(VECTOR_KEYS)} "
                "(unit vectors)"
            )
        rows = []
        for rec in reader:
            extra = [v for v in rec.pop(None, None) or () if v.strip()]  # past the header
            if extra:
                raise VrnError(
                    f"{path}, line {reader.line_num}: {len(extra)} more field"
                    f"{'s' if len(extra) > 1 else ''} than the header's {len(cols)} columns "
                    f"({', '.join(repr(v) for v in extra)})"
                )
            clean = {(k or "").strip().lower(): (v or "").strip() for k, v in rec.items()}
            if not any(clean.values()):
                continue
            line = f"line {reader.line_num}"
            rows.append(_entry(f"{path}, {line}", line, clean))
    if not rows:
        raise VrnError(f"{path}: the direction table has no rows")
    return rows
