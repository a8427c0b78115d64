"""The live viewer: an event loop around :meth:`Renderer.frame
<vrneural.runtime.renderer.Renderer.frame>` plus input handling.

Per frame (rendercanvas calls :meth:`View._draw` right after handling the pending events):
the renderer for the current knobs renders frame ``f`` at scene time ``t`` from the camera's
head pose (the same call `vrneural run` makes, with a pose of its own), the split view's
reference renderer every ``split_every`` frames, then one present pass tonemaps the eye
textures into the canvas's texture on the GPU (:mod:`.present`) with the HUD on top. Nothing
is read back unless a screenshot, a recording or :attr:`View.keep_shown` asks for it.

The renderer interface used: ``frame(f, t, head)``, ``colour_textures()``, ``read_eyes()``,
``invalidate()``, ``lights`` (replaced entries) and ``s.reuse`` / ``s.schedule``.
"""

from __future__ import annotations

import dataclasses
import signal
import sys
import time
from collections import deque

import numpy as np

from vrneural.errors import VrnError
from vrneural.viewer.backends import jupyter_canvas, window_canvas
from vrneural.viewer.camera import ViewCamera
from vrneural.viewer.config import check_view_config
from vrneural.viewer.controls import Controls
from vrneural.viewer.frame import REPLAY_MAX, FrameInput, FrameWork
from vrneural.viewer.keys import KeyMap, load_keys
from vrneural.viewer.startup import configs, load, start_live
from vrneural.viewer.state import Renderers


class View(FrameWork):
    """`vrneural view` in Python: ``View(scene).show()`` in Jupyter, ``View(scene).run()`` for
    a window. ``scene``: a Scene, a scene file path, or None (the built-in scene); ``options``:
    any :class:`~vrneural.runtime.config.RunConfig` or
    :class:`~vrneural.viewer.config.ViewConfig` field (``profile="tiny"``, ``eyes=2``,
    ``split="flip"``, ``frames=100``); defaults: the preview profile, one eye."""

    def __init__(self, scene=None, config=None, view=None, **options):
        from vrneural.gpu.device import adapter_summary, get_device

        self.cfg, self.vc = configs(config, view, options)
        check_view_config(self.vc)
        self.keymap = load_keys(self.vc.keys) if self.vc.keys else KeyMap()
        self.scene = load(scene, self.cfg)
        self.adapter = adapter_summary()
        self.dev = get_device()
        self.renderers = Renderers(self.scene, self.cfg, self.adapter, self._building)
        self.live = start_live(self.renderers, self.vc)
        self.r, _ = self.renderers.get(self.live)
        for w in self.r.warnings:
            print(f"warning: {w}", file=sys.stderr)
        self.head_path = self.r.head  # the scene's (orbit or pose log), as run plays it
        self.lights = [dataclasses.replace(lt) for lt in self.r.lights]
        self.live.lights_on = [True] * len(self.lights)
        self.camera = ViewCamera((0, 0, 0), (0, 0, -1))
        self.reset_camera()
        self.f, self.t = 0, 0.0
        self.split_every = self.vc.split_every or (30 if self.adapter.is_cpu else 1)
        self.controls = Controls(self)
        self.canvas = self.context = self.presenter = None
        self.keep_shown = False  # read every frame back into .shown (tests, scripts)
        self.shown: np.ndarray | None = None  # [H, W, 3] uint8, the last frame read back
        self.records: deque = deque(maxlen=10_000)
        self.replay_log: list[FrameInput] | None = []  # since the renderer was taken up
        self.status: tuple[str, float, bool] | None = None
        self.hooks: list = []
        self.failure: BaseException | None = None
        self.fps_window: deque = deque(maxlen=240)
        self._init_frame_work()

    # ----- public API

    def run(self) -> dict:
        """Open a window (glfw) and run until it is closed (or ``frames`` are drawn); returns
        :meth:`summary`. Ctrl-C or SIGTERM close it after the frame being drawn (a second one
        stops that frame) and raise :class:`KeyboardInterrupt`, as `run` does; the video of
        ``record`` is kept. An error closes it too: then no video is left behind."""
        canvas, loop = window_canvas(self.window_size(), self.title(), self.vc.vsync)
        self._open(canvas, loop)
        before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
        self.stopper = "install"  # taken over inside the loop, which takes SIGINT at its start
        try:
            loop.run()
        except BaseException as e:
            self.failure = e
        finally:
            self.stopper = None
            for sig, handler in before.items():
                if handler is not None:
                    signal.signal(sig, handler)
        stopped = isinstance(self.failure, KeyboardInterrupt) or self.interrupted
        self._finish(failed=self.failure is not None and not stopped)
        if stopped:
            raise KeyboardInterrupt
        if self.failure is not None:
            raise self.failure
        return self.summary()

    def show(self):
        """The viewer as a Jupyter widget (rendercanvas's Jupyter backend); display it as a
        cell's output."""
        size = self.window_size()
        canvas, loop = jupyter_canvas(size, self.title())
        # the size until the browser reports its own (a notebook run without one, nbclient,
        # draws at this size)
        canvas.handle_event({"event_type": "resize", "width": size[0], "height": size[1],
                             "pixel_ratio": 1.0})  # fmt: skip
        self._open(canvas, loop)
        return canvas

    def after_frame(self, fn) -> None:
        """Call ``fn(view, record)`` after every frame drawn (scripts, tests)."""
        self.hooks.append(fn)

    def close(self) -> None:
        """Close the window (after the frame being drawn)."""
        if self.canvas is not None and not self.canvas.get_closed():
            self.loop.call_soon(self.canvas.close)

    def pose(self):
        """The head pose rendered: the scene's head path at ``t`` or the free camera."""
        if self.live.follow_head:
            return self.head_path.pose(self.t)
        return self.camera.pose()

    def reset_camera(self) -> None:
        """The free camera at the head path's start, its orbit target at the scene's centre
        depth."""
        pos, rot = self.head_path.pose(0.0)
        fwd = -rot[:, 2]
        centre = np.mean([o.model[:3, 3] for o in self.scene.objects], axis=0)
        self.camera.reset_to(pos, fwd, max(0.3, float((centre - pos) @ fwd)))

    def say(self, msg: str, alert: bool = False) -> None:
        """A status line on the HUD for a few seconds (alerts also go to stderr)."""
        self.status = (msg, time.perf_counter(), alert)
        if alert:
            print(f"warning: {msg}", file=sys.stderr)

    def fps(self) -> float:
        """Frames per second over the last second (wall clock between frames' ends)."""
        last = self.fps_window[-1] if self.fps_window else 0.0
        ends = [e for e in self.fps_window if e >= last - 1.0]
        if len(ends) < 2:
            return 0.0
        return (len(ends) - 1) / max(ends[-1] - ends[0], 1e-9)

    def summary(self) -> dict:
        """Frames drawn and their timings (the first frame, which compiles, left out)."""
        recs = list(self.records)[1:] or list(self.records)
        iv = np.diff([r.end for r in self.records]) * 1e3 if len(self.records) > 1 else []
        return {
            "frames": len(self.records),
            "fps_median": float(1e3 / np.median(iv)) if len(iv) else 0.0,
            "frame_interval_ms_median": float(np.median(iv)) if len(iv) else 0.0,
            "render_ms_median": float(np.median([r.render_ms for r in recs])) if recs else 0.0,
            "present_ms_median": float(np.median([r.present_ms for r in recs])) if recs else 0.0,
            "recorded": str(self.recorded) if self.recorded else None,
            "screenshots": [str(p) for p in self.shots],
        }

    def replay_offscreen(self) -> list[np.ndarray]:
        """The current renderer's frames since it was (re)activated, rendered again by a new
        offscreen :class:`~vrneural.runtime.renderer.Renderer` with the same settings: its
        eyes' HDR ``[H, W, 4]`` float32, what the window's last frame must show."""
        from vrneural.runtime.renderer import Renderer

        if self.replay_log is None:
            raise VrnError(
                f"replay_offscreen: more than {REPLAY_MAX} frames since this renderer was "
                "taken up; their inputs were not kept"
            )
        r = Renderer(self.scene, dataclasses.replace(self.r.s))
        for fi in self.replay_log:
            r.s.reuse, r.s.schedule, r.s.reuse_budget = fi.reuse, fi.schedule, fi.reuse_budget
            r.lights[:] = fi.lights
            r.frame(fi.f, fi.t, fi.head)
        return r.read_eyes()

    # ----- sizes and titles

    def title(self) -> str:
        return f"vrneural view: {self.scene.name}"

    def image_size(self) -> tuple[int, int]:
        """The image shown: the eyes side by side (one eye in split view)."""
        w, h = self.r.s.eye_res
        return (w if self.live.split != "off" else w * self.r.s.eyes, h)

    def window_size(self) -> tuple[int, int]:
        if self.vc.window:
            from vrneural.runtime.config import parse_res

            return parse_res(self.vc.window, "--window")
        w, h = self.image_size()
        k = min(1.0, 1920 / w, 1080 / h)
        return max(16, int(w * k)), max(16, int(h * k))

    def image_scale(self) -> float:
        """Logical window pixels per image pixel."""
        from vrneural.viewer.present import fit

        size = self.canvas.get_physical_size() if self.canvas else self.window_size()
        ratio = self.canvas.get_pixel_ratio() if self.canvas else 1.0
        return fit(size, self.image_size())[2] / max(ratio, 1e-6)

    def _building(self, what: str) -> None:
        if getattr(self, "canvas", None) is not None:
            self.say(what)
