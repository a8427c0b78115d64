"""The viewer's camera: orbit around a target, fly (WASD + mouse look), or follow the scene's
head path; and dragging a light in the view plane.

Conventions as :mod:`vrneural.runtime.camera`: right-handed world, y up, metres; the camera
looks down its -z axis. A pose is ``(position [3], rotation [3, 3])`` camera-to-world, the head
pose :meth:`Renderer.frame <vrneural.runtime.renderer.Renderer.frame>` takes. Yaw turns about
+y (0: looking down -z), pitch about the camera's x axis (positive: looking up), both radians.
"""

from __future__ import annotations

import math

import numpy as np

from vrneural.runtime.camera import look_rotation

PITCH_MAX = math.radians(89.0)
#: radians of yaw / pitch per logical pixel of mouse drag
DRAG_RADIANS = 0.005
#: orbit distance factor per wheel notch (glfw reports 100 per notch, as browsers do)
ZOOM_PER_NOTCH = 1.1
MIN_DISTANCE = 0.05


def forward_of(yaw: float, pitch: float) -> np.ndarray:
    """Unit view direction ``[3]`` of a yaw and pitch."""
    cp = math.cos(pitch)
    return np.array([-math.sin(yaw) * cp, math.sin(pitch), -math.cos(yaw) * cp])


def yaw_pitch(forward) -> tuple[float, float]:
    """Yaw and pitch of a view direction ``[3]`` (inverse of :func:`forward_of`)."""
    f = np.asarray(forward, np.float64)
    f = f / np.linalg.norm(f)
    pitch = math.asin(float(np.clip(f[1], -1.0, 1.0)))
    return math.atan2(-f[0], -f[2]), float(np.clip(pitch, -PITCH_MAX, PITCH_MAX))


class ViewCamera:
    """A free camera. ``orbit`` mode: dragging turns the camera about ``target`` at
    ``distance``; ``fly`` mode: dragging turns it in place. WASD/QE move both camera and target
    (``speed`` m/s); the wheel zooms (orbit) or changes the speed (fly)."""

    def __init__(self, position, forward, distance: float = 1.5):
        self.mode = "orbit"
        self.speed = 0.6  # m/s
        self.reset_to(position, forward, distance)

    def reset_to(self, position, forward, distance: float | None = None) -> None:
        """Put the camera at ``position [3]`` looking along ``forward [3]``; the orbit target
        lies ``distance`` m ahead."""
        self.yaw, self.pitch = yaw_pitch(forward)
        if distance is not None:
            self.distance = max(float(distance), MIN_DISTANCE)
        self.position = np.asarray(position, np.float64).copy()

    @property
    def forward(self) -> np.ndarray:
        return forward_of(self.yaw, self.pitch)

    @property
    def target(self) -> np.ndarray:
        return self.position + self.distance * self.forward

    def pose(self) -> tuple[np.ndarray, np.ndarray]:
        """``(position [3], rotation [3, 3])`` camera-to-world, no roll."""
        return self.position.copy(), look_rotation(self.forward)

    def drag(self, dx: float, dy: float) -> None:
        """Turn by a mouse drag of ``dx, dy`` logical pixels (orbit: about the target)."""
        target = self.target
        self.yaw -= dx * DRAG_RADIANS
        self.pitch = float(np.clip(self.pitch - dy * DRAG_RADIANS, -PITCH_MAX, PITCH_MAX))
        if self.mode == "orbit":
            self.position = target - self.distance * self.forward

    def pan(self, dx: float, dy: float) -> None:
        """Move camera and target in the view plane by a drag (``distance``-scaled)."""
        rot = look_rotation(self.forward)
        k = self.distance * DRAG_RADIANS
        self.position = self.position - rot[:, 0] * dx * k + rot[:, 1] * dy * k

    def wheel(self, dy: float) -> None:
        """A wheel turn (``dy`` > 0: towards the user, as browsers report it)."""
        f = ZOOM_PER_NOTCH ** (dy / 100.0)
        if self.mode == "orbit":
            target = self.target
            self.distance = max(self.distance * f, MIN_DISTANCE)
            self.position = target - self.distance * self.forward
        else:
            self.speed = float(np.clip(self.speed / f, 0.01, 100.0))

    def move(self, right: float, up: float, forward: float, dt: float) -> None:
        """Fly: move by ``speed * dt`` along the camera's right / world up / view axes
        (each of ``right, up, forward`` in -1, 0, 1)."""
        rot = look_rotation(self.forward)
        d = rot[:, 0] * right + np.array([0.0, 1.0, 0.0]) * up + self.forward * forward
        n = np.linalg.norm(d)
        if n > 0:
            self.position = self.position + d / n * self.speed * dt


def drag_point(point, pose, fov_y: float, dx: float, dy: float, height: float):
    """``point [3]`` moved in the plane facing the camera at its depth so that it follows a
    drag of ``dx, dy`` pixels in an image ``height`` pixels tall (vertical field of view
    ``fov_y`` degrees); points behind the camera do not move."""
    pos, rot = (np.asarray(a, np.float64) for a in pose)
    p = np.asarray(point, np.float64)
    depth = float(-(p - pos) @ rot[:, 2])
    if depth <= 1e-6:
        return p.copy()
    metres_per_pixel = 2 * depth * math.tan(math.radians(fov_y) / 2) / height
    return p + (rot[:, 0] * dx - rot[:, 1] * dy) * metres_per_pixel


def project(point, pose, fov_y: float, aspect: float, size) -> tuple[float, float] | None:
    """Pixel ``(x, y)`` of world ``point [3]`` in an image of ``size = (width, height)``
    (y down), or None behind the camera."""
    pos, rot = (np.asarray(a, np.float64) for a in pose)
    c = rot.T @ (np.asarray(point, np.float64) - pos)
    if c[2] >= -1e-6:
        return None
    t = math.tan(math.radians(fov_y) / 2)
    x = c[0] / (-c[2] * t * aspect)
    y = c[1] / (-c[2] * t)
    return (x + 1) / 2 * size[0], (1 - y) / 2 * size[1]
