"""Head motion for the trade-off bench: saccade-like yaw turns as pose logs.

A head turn is a rotation about the neck, not about the eyes: the eyes sit ``NECK_UP`` above and
``NECK_FORWARD`` in front of the pivot, so a yaw of ``a`` moves them by about
``NECK_FORWARD * a`` sideways. That translation, not the rotation, is what makes a radiance
texture stale (texture space follows the geometry exactly; only ``wo`` changes), so the logs
model it. A turn log holds ``still`` seconds at rest, one turn of ``amplitude`` degrees at a
constant ``speed`` (deg/s), then rest again, sampled at the display rate, in the runtime's pose-log
CSV format (``t, x, y, z, qx, qy, qz, qw``; :class:`vrneural.runtime.camera.PoseLogPath`).
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from vrneural.outputs import atomic_path
from vrneural.runtime.camera import look_rotation

#: eye centre above and in front of the neck pivot, metres (a common VR neck model)
NECK_UP = 0.12
NECK_FORWARD = 0.08
#: where the head looks from and at (the benches' scenes are built around it)
HEAD = np.array([0.0, 1.3, 1.0])
TARGET = np.array([0.0, 1.3, 0.0])


def _quaternion(m: np.ndarray) -> np.ndarray:
    """``[x, y, z, w]`` (w >= 0, unit) of the rotation matrix ``m [3, 3]``."""
    w = np.sqrt(max(1e-12, 1 + m[0, 0] + m[1, 1] + m[2, 2])) / 2
    q = np.array([(m[2, 1] - m[1, 2]) / (4 * w), (m[0, 2] - m[2, 0]) / (4 * w),
                  (m[1, 0] - m[0, 1]) / (4 * w), w])  # fmt: skip
    return q / np.linalg.norm(q)


def turn_frames(speed: float, amplitude: float, still: float, fps: float) -> tuple[int, int]:
    """(first frame of the turn, frames it lasts) of :func:`turn_log`."""
    start = round(still * fps)
    return start, 0 if speed <= 0 else max(1, round(amplitude / speed * fps))


def turn_poses(speed: float, amplitude: float = 30.0, still: float = 0.1, after: float = 0.2,
               fps: float = 90.0) -> np.ndarray:  # fmt: skip
    """Rows ``[t, x, y, z, qx, qy, qz, qw]``: rest, a yaw turn of ``amplitude`` degrees at
    ``speed`` deg/s about the neck (centred on the view of :data:`TARGET`), rest."""
    start, n = turn_frames(speed, amplitude, still, fps)
    total = start + n + round(after * fps) + 1
    base = look_rotation(TARGET - HEAD)
    neck = np.array([0.0, NECK_UP, -NECK_FORWARD])  # the eyes from the pivot, head frame
    pivot = HEAD - base @ neck
    rows = []
    for f in range(total):
        k = np.clip((f - start) / n, 0.0, 1.0) if n else 0.0
        a = np.radians(amplitude * (k - 0.5) if n else 0.0)  # the yaw about world +y
        m = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]) @ base
        rows.append([f / fps, *(pivot + m @ neck), *_quaternion(m)])
    return np.asarray(rows)


def write_pose_log(path: Path, rows: np.ndarray) -> Path:
    """Write ``rows`` as a pose-log CSV with a header line."""
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t", "x", "y", "z", "qx", "qy", "qz", "qw"])
        w.writerows([[f"{v:.9g}" for v in r] for r in rows])
    return path


def peak_speed(log) -> float:
    """The largest yaw-rate of a pose log (:class:`PoseLogPath`), degrees per second, between
    consecutive rows (the speed a CSV log is labelled with in the report)."""
    q = log.q / np.linalg.norm(log.q, axis=1, keepdims=True)
    dots = np.abs((q[1:] * q[:-1]).sum(1)).clip(0, 1)
    ang = np.degrees(2 * np.arccos(dots))
    dt = np.diff(log.t)
    return float((ang / np.maximum(dt, 1e-9)).max()) if len(dt) else 0.0
