"""Input: rendercanvas events (keys, pointer, wheel) -> the viewer's knobs, camera and lights.

Events are handled when rendercanvas processes them, right before it draws the next frame, so
a key changes the very next frame (nothing is queued behind it). Knobs that need another
renderer are only marked here; the frame builds or fetches it (:class:`~.state.Renderers`).
"""

from __future__ import annotations

import dataclasses
import time

from vrneural.runtime.lights import PointLight
from vrneural.runtime.schedule import SCHEDULES
from vrneural.runtime.settings import MODES, RADIANCE
from vrneural.viewer.camera import drag_point
from vrneural.viewer.config import SPLITS
from vrneural.viewer.keys import HELD
from vrneural.viewer.state import cycle, step_reuse, step_texture

#: held key -> (right, up, forward)
MOVES = {
    "forward": (0, 0, 1),
    "back": (0, 0, -1),
    "left": (-1, 0, 0),
    "right": (1, 0, 0),
    "down": (0, -1, 0),
    "up": (0, 1, 0),
}
#: key action -> the :class:`~.state.Live` switch it flips
TOGGLES = {"help": "help", "hud": "hud", "adaptive": "adaptive", "pause": "paused"}
#: key action -> (the :class:`~.state.Live` knob it steps, its values in order)
CYCLES = {
    "mode": ("mode", MODES),
    "schedule": ("schedule", SCHEDULES),
    "precision": ("precision", ("f32", "f16")),
    "radiance": ("radiance", RADIANCE),
    "split": ("split", SPLITS),
}


class Controls:
    """Turns events into changes of ``view.live``, ``view.camera`` and ``view.lights``."""

    def __init__(self, view):
        self.view = view
        self.held: set[str] = set()
        self.pointer: tuple[float, float] | None = None
        #: key actions handled since the last frame: (action, time_stamp of the event, time
        #: handled), both perf_counter seconds; the frame drawn next takes them (input-to-photon)
        self.inputs: list[tuple[str, float, float]] = []

    def handle(self, ev: dict) -> None:
        """The canvas's event handler (every event type)."""
        v, kind = self.view, ev.get("event_type")
        if kind in ("key_down", "key_up"):
            action = v.keymap.action(ev.get("key", ""))
            if action and kind == "key_down":
                now = time.perf_counter()
                stamp = ev.get("time_stamp")
                ok = isinstance(stamp, float) and 0 <= now - stamp < 60  # jupyter: JS clock
                self.inputs.append((action, stamp if ok else now, now))
            if action in HELD:
                (self.held.add if kind == "key_down" else self.held.discard)(action)
                if kind == "key_down":
                    self._leave_head_path()
            elif action and kind == "key_down":
                self.act(action)
        elif kind == "pointer_down":
            self.pointer = (ev["x"], ev["y"])
        elif kind == "pointer_up":
            if not ev.get("buttons"):
                self.pointer = None
        elif kind == "pointer_move" and ev.get("buttons") and self.pointer is not None:
            dx, dy = ev["x"] - self.pointer[0], ev["y"] - self.pointer[1]
            self.pointer = (ev["x"], ev["y"])
            self.drag(min(ev["buttons"]), dx, dy)
        elif kind == "wheel":
            self._leave_head_path()
            v.camera.wheel(ev.get("dy", 0.0))

    def act(self, action: str) -> None:
        """Do what key ``action`` (:data:`~.keys.ACTIONS`) does."""
        v = self.view
        live = v.live
        if action in TOGGLES:
            setattr(live, TOGGLES[action], not getattr(live, TOGGLES[action]))
        elif action in CYCLES:
            knob, values = CYCLES[action]
            setattr(live, knob, cycle(getattr(live, knob), values))
        elif action in ("reuse_up", "reuse_down"):
            step_reuse(live, 1 if action == "reuse_up" else -1)
        elif action in ("texture_up", "texture_down"):
            step_texture(live, action == "texture_up", v.adapter)
        elif action == "lights":
            on = not any(live.lights_on)
            live.lights_on = [on] * len(live.lights_on)
        elif action.startswith("light_"):
            k = int(action[6:]) - 1
            if k < len(live.lights_on):
                live.lights_on[k] = not live.lights_on[k]
            else:
                v.say(f"no light {k + 1}: {len(live.lights_on)} shaded (--lights N for more)")
        elif action == "select_light" and live.lights_on:
            live.selected = (live.selected + 1) % len(live.lights_on)
        elif action == "head_path":
            if live.follow_head:
                self._leave_head_path()
            else:
                live.follow_head = True
        elif action == "camera":
            v.camera.mode = "fly" if v.camera.mode == "orbit" else "orbit"
        elif action == "reset_camera":
            live.follow_head = False
            v.reset_camera()
        elif action == "screenshot":
            v.want_shot = True  # taken after the next frame is drawn
        elif action == "quit":
            v.close()

    def _leave_head_path(self) -> None:
        """A camera input while following the head path: go on from the path's pose."""
        v = self.view
        if v.live.follow_head:
            v.live.follow_head = False
            pos, rot = v.head_path.pose(v.t)
            v.camera.reset_to(pos, -rot[:, 2])

    def drag(self, button: int, dx: float, dy: float) -> None:
        """A drag of ``dx, dy`` logical pixels: 1 (left) turns the camera, 3 (middle) pans,
        2 (right) moves the selected light in the plane facing the camera."""
        v = self.view
        if button == 2:
            self.drag_light(dx, dy)
            return
        self._leave_head_path()
        if button == 1:
            v.camera.drag(dx, dy)
        elif button == 3:
            v.camera.pan(dx, dy)

    def drag_light(self, dx: float, dy: float) -> None:
        """Move the selected light (it stops circling: it stays where it is put)."""
        v = self.view
        k = v.live.selected
        if not 0 <= k < len(v.lights):
            return
        s = v.image_scale()  # window pixels per image pixel
        lt = v.lights[k]
        p = drag_point(lt.at(v.t), v.pose(), v.r.s.fov_y, dx / s, dy / s, v.r.s.eye_res[1])
        v.lights[k] = dataclasses.replace(lt, position=tuple(float(x) for x in p), motion="none")

    def move(self, dt: float) -> None:
        """Fly for ``dt`` seconds along the held keys."""
        if not self.held or dt <= 0:
            return
        r, u, f = (sum(axis) for axis in zip(*(MOVES[a] for a in self.held), strict=True))
        self.view.camera.move(r, u, f, dt)


def effective_lights(lights: list[PointLight], on: list[bool]) -> list[PointLight]:
    """The lights as shaded: switched-off ones at zero intensity (same count, same cost)."""
    return [
        lt if k else dataclasses.replace(lt, intensity=0.0)
        for lt, k in zip(lights, on, strict=True)
    ]
