"""Head motion, stereo eyes and projection.

Conventions: right-handed world, y up, metres; a camera looks down its -z axis; clip space is
WebGPU's (x, y in [-1, 1], y up, depth in [0, 1]). Matrices are float64 ``[4, 4]`` acting on
column vectors. A head pose is (position ``[3]``, unit quaternion ``[x, y, z, w]``); the eyes sit
at ``-ipd/2`` and ``+ipd/2`` along the head's x axis.
"""

from __future__ import annotations

import csv
import functools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vrneural.errors import VrnError


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation ``[3, 3]`` of unit quaternion ``q = [x, y, z, w]``."""
    x, y, z, w = np.asarray(q, np.float64) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def look_rotation(forward, up=(0.0, 1.0, 0.0)) -> np.ndarray:
    """Camera-to-world rotation ``[3, 3]`` whose -z axis is ``forward``. Called every frame:
    scalar float64 arithmetic (the products of ``np.cross`` and ``np.linalg.norm``) and one
    array, instead of a dozen small numpy calls."""
    fx, fy, fz = (float(x) for x in forward)
    ux, uy, uz = (float(x) for x in up)
    n = math.sqrt(fx * fx + fy * fy + fz * fz)
    fx, fy, fz = fx / n, fy / n, fz / n
    rx, ry, rz = fy * uz - fz * uy, fz * ux - fx * uz, fx * uy - fy * ux  # f x up
    n = math.sqrt(rx * rx + ry * ry + rz * rz)
    if n < 1e-12:  # looking along ``up``: any right axis will do; the world's x
        rx, ry, rz, n = 1.0, 0.0, 0.0, 1.0
    rx, ry, rz = rx / n, ry / n, rz / n
    vx, vy, vz = ry * fz - rz * fy, rz * fx - rx * fz, rx * fy - ry * fx  # r x f
    return np.array([[rx, vx, -fx], [ry, vy, -fy], [rz, vz, -fz]])


@functools.lru_cache(maxsize=64)
def _perspective(fov_y_deg: float, aspect: float, near: float, far: float) -> np.ndarray:
    f = 1.0 / np.tan(np.radians(fov_y_deg) / 2)
    p = np.zeros((4, 4))
    p[0, 0] = f / aspect
    p[1, 1] = f
    p[2, 2] = far / (near - far)
    p[2, 3] = near * far / (near - far)
    p[3, 2] = -1.0
    p.setflags(write=False)  # cached and shared by every Eye
    return p


@dataclass
class Eye:
    """One eye at one frame: world position, view and projection matrices (not changed after
    creation: the products below are computed once)."""

    position: np.ndarray  # [3] metres
    view: np.ndarray  # [4, 4] world -> camera
    proj: np.ndarray  # [4, 4] camera -> clip

    @functools.cached_property
    def view_proj(self) -> np.ndarray:
        return self.proj @ self.view

    @functools.cached_property
    def planes(self) -> np.ndarray:
        """:func:`frustum_planes` of :attr:`view_proj`."""
        return frustum_planes(self.view_proj)


def window_matrix(size, crop=None, jitter=(0.0, 0.0)) -> np.ndarray:
    """Clip-space matrix ``[4, 4]`` (applied after the projection) that renders the window
    ``crop = (x0, y0, full_w, full_h)`` of a ``full_w x full_h`` image into an image of ``size =
    (w, h)`` pixels (no crop: the whole image, ``size`` itself), shifted by ``jitter`` pixels
    (x right, y down) of that image: a sub-pixel offset for supersampling."""
    w, h = size
    x0, y0, fw, fh = crop if crop is not None else (0, 0, w, h)
    # NDC x of the window's left and right edges in the full image; y up (row 0 at the top)
    left, right = 2 * x0 / fw - 1, 2 * (x0 + w) / fw - 1
    top, bottom = 1 - 2 * y0 / fh, 1 - 2 * (y0 + h) / fh
    sx, sy = 2 / (right - left), 2 / (top - bottom)
    m = np.eye(4)
    m[0, 0], m[1, 1] = sx, sy
    m[0, 3] = -sx * (left + right) / 2 - 2 * jitter[0] / w
    m[1, 3] = -sy * (top + bottom) / 2 + 2 * jitter[1] / h
    return m


def eyes_from_pose(pos, rot, ipd: float, n_eyes: int, fov_y: float, aspect: float) -> list[Eye]:
    """Eye(s) of a head at ``pos [3]`` with rotation ``rot [3, 3]`` (one eye: the head centre)."""
    offsets = [-ipd / 2, ipd / 2] if n_eyes == 2 else [0.0]
    out = []
    proj = _perspective(float(fov_y), float(aspect), 0.05, 100.0)  # shared, never written
    pos = np.asarray(pos, np.float64)
    for o in offsets:
        p = pos + rot[:, 0] * o
        view = np.eye(4)
        view[:3, :3] = rot.T
        view[:3, 3] = -rot.T @ p
        out.append(Eye(p, view, proj))
    return out


class HeadPath:
    """Head pose as a function of time ``t`` (s): ``pose(t) -> (position [3], rotation [3,3])``."""

    def pose(self, t: float):
        raise NotImplementedError


@dataclass
class OrbitPath(HeadPath):
    """Built-in smooth, slow path: the head sways on a small ellipse (amplitude ``sway`` m,
    period ``period`` s) around ``centre`` while looking at ``target``."""

    centre: tuple = (0.0, 1.25, 1.05)
    target: tuple = (0.1, 0.8, 0.0)
    sway: float = 0.12
    period: float = 8.0

    def pose(self, t: float):
        a = 2 * math.pi * t / self.period
        cx, cy, cz = self.centre
        p = (cx + self.sway * math.sin(a), cy + self.sway * 0.3 * math.sin(2 * a), float(cz))
        tx, ty, tz = self.target
        return np.array(p), look_rotation((tx - p[0], ty - p[1], tz - p[2]))


#: How far a pose log's quaternion length may be from 1 (logs written with few decimals)
QUAT_TOLERANCE = 0.01


class PoseLogPath(HeadPath):
    """A recorded pose log: CSV rows ``t, x, y, z, qx, qy, qz, qw`` (header optional), times
    in seconds, increasing, counted from the first row (a log of absolute timestamps plays from
    its start); positions interpolated linearly, rotations by normalised lerp."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        if not self.path.is_file():
            raise VrnError(f"{self.path}: head-motion pose log not found")
        rows, lines, hint = [], [], ""
        with open(self.path, newline="", encoding="utf-8-sig") as f:
            for i, row in enumerate(csv.reader(f)):
                if not row or row[0].strip().startswith("#"):
                    continue
                sep = next((c for c in ";\t|" if len(row) == 1 and c in row[0]), None)
                hint = f" (columns are separated by commas, not {sep!r})" if sep else ""
                try:
                    vals = [float(v) for v in row]
                except ValueError:
                    if i == 0:
                        continue  # header
                    raise VrnError(
                        f"{self.path}:{i + 1}: non-numeric value in {row}{hint}"
                    ) from None
                if len(vals) != 8:
                    raise VrnError(f"{self.path}:{i + 1}: expected 8 columns, got {len(vals)}")
                rows.append(vals)
                lines.append(i + 1)
        a = np.asarray(rows, np.float64)
        if len(a) < 1:
            raise VrnError(f"{self.path}: pose log has no rows of 8 numbers{hint}")

        def first(bad: np.ndarray, what: str) -> None:  # the first bad row, by its line
            if bad.any():
                raise VrnError(f"{self.path}:{lines[int(np.argmax(bad))]}: {what}")

        first(~np.isfinite(a).all(axis=1), "NaN/Inf value in the row")
        first(np.append(False, np.diff(a[:, 0]) <= 0), "time is not after the previous row's")
        norm = np.linalg.norm(a[:, 4:8], axis=1)
        first(norm < 1e-6, "zero quaternion (qx qy qz qw = 0 0 0 0)")
        off = np.abs(norm - 1.0) > QUAT_TOLERANCE
        k = int(np.argmax(off))
        first(
            off, f"quaternion of length {norm[k]:.4g}; a unit one expected (+-{QUAT_TOLERANCE:g})"
        )
        self.t, self.p, self.q = a[:, 0] - a[0, 0], a[:, 1:4], a[:, 4:8]

    def pose(self, t: float):
        t = float(np.clip(t, self.t[0], self.t[-1]))
        i = int(np.clip(np.searchsorted(self.t, t, side="right") - 1, 0, len(self.t) - 1))
        j = min(i + 1, len(self.t) - 1)
        s = 0.0 if j == i else (t - self.t[i]) / (self.t[j] - self.t[i])
        q1 = self.q[j] if np.dot(self.q[i], self.q[j]) >= 0 else -self.q[j]
        q = (1 - s) * self.q[i] + s * q1
        return (1 - s) * self.p[i] + s * self.p[j], quat_to_matrix(q)


#: rows of ``view_proj`` that make the clip planes: m3 + m0, m3 - m0, m3 + m1, m3 - m1, m2 (near:
#: WebGPU depth >= 0), m3 - m2
_PLANE_ROWS = np.array(
    [[1, 0, 0, 1], [-1, 0, 0, 1], [0, 1, 0, 1], [0, -1, 0, 1], [0, 0, 1, 0], [0, 0, -1, 1]], float
)


def frustum_planes(view_proj: np.ndarray) -> np.ndarray:
    """The 6 planes ``[6, 4]`` (normals inward, normalised) of a WebGPU clip volume."""
    planes = _PLANE_ROWS @ view_proj
    return planes / np.sqrt((planes[:, :3] ** 2).sum(1))[:, None]
