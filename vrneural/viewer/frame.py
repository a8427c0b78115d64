"""One viewer frame (:class:`FrameWork`, mixed into :class:`~vrneural.viewer.view.View`):
render with the active renderer, the split view's reference and FLIP map, the HUD, the
present pass into the canvas texture, and the optional read-backs (screenshot, recording)."""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from vrneural.errors import VrnError
from vrneural.interrupt import Stop
from vrneural.scoring.metrics import pixels_per_degree
from vrneural.viewer.backends import _capabilities, target_format
from vrneural.viewer.camera import project
from vrneural.viewer.controls import effective_lights
from vrneural.viewer.hud import LINE_PX, PAD, panel
from vrneural.viewer.hud_text import hud_lines
from vrneural.viewer.outputs import FlipWorker, Recorder, save_shot
from vrneural.viewer.shot import shot_settings

#: frames since a renderer was taken up that :meth:`View.replay_offscreen` can render again
REPLAY_MAX = 5000


@dataclass
class FrameInput:
    """What a frame was rendered from: enough to render it again offscreen."""

    f: int
    t: float
    head: tuple
    lights: list
    reuse: int
    schedule: str
    reuse_budget: float | None = None  # adaptive reuse (`U`)


@dataclass
class FrameRecord:
    """One drawn frame: timings (perf_counter seconds, ms), the renderer's statistics, the
    settings it was rendered with, and the key actions handled just before it
    (``(action, event time_stamp, handled at)``: each key's effect shows in this frame)."""

    frame: int
    start: float
    end: float
    render_ms: float
    present_ms: float
    stats: object
    settings: dict
    inputs: list = field(default_factory=list)


class FrameWork:
    """The per-frame half of the viewer (state lives on the :class:`View`)."""

    def _init_frame_work(self) -> None:
        self.want_shot = False
        self.shots: list = []
        self.recorder = None
        self.recorded = None
        self.flip = None  # FlipWorker, started on first use
        self.flip_tex = None
        self.flip_mean: float | None = None
        self.flip_frame: int | None = None  # the frame the FLIP map shown was computed at
        self.flip_pending: int | None = None
        self.split_frame: int | None = None
        self.split_key = None
        self.t_last: float | None = None
        self.can_read = True
        self.view_format = None
        self.good = (self.live.mode, self.live.precision, self.live.texture_res,
                     self.live.texture_res_given, self.live.radiance)  # fmt: skip
        self._shot_target = None
        self.stopper = None  # View.run: Ctrl-C / SIGTERM close the window between frames
        self.interrupted = False

    # ----- opening and closing

    def _open(self, canvas, loop) -> None:
        import wgpu

        from vrneural.viewer.present import Presenter

        self.canvas, self.loop = canvas, loop
        ctx = canvas.get_wgpu_context()
        fmt, view_fmt = target_format(ctx, self.dev.adapter)
        usages = _capabilities(ctx, self.dev.adapter).get("usages")
        tu = wgpu.TextureUsage
        self.can_read = usages is None or bool(int(usages) & tu.COPY_SRC)
        usage = tu.RENDER_ATTACHMENT | (tu.COPY_SRC if self.can_read else 0)
        views = [view_fmt] if view_fmt != fmt else []
        ctx.configure(device=self.dev, format=fmt, usage=usage, view_formats=views)
        self.context, self.view_format = ctx, (view_fmt if views else None)
        self.presenter = Presenter(view_fmt)
        canvas.add_event_handler(self.controls.handle, "*")
        if self.vc.record:
            if not self.can_read:
                raise VrnError(
                    "--record: this window's surface cannot be copied from (no COPY_SRC usage)"
                )
            self.recorder = Recorder(self.vc.record, self.r.s.fps)
        canvas.request_draw(self._draw)

    def _finish(self, failed: bool = False) -> None:
        """After the loop: finish the video (closed or stopped: kept, playable; failed: no
        half-written video left behind, as `run` does), stop the FLIP worker."""
        try:
            if self.recorder is not None:
                rec, self.recorder = self.recorder, None
                if failed:
                    rec.writer.abort()
                else:
                    self.recorded = rec.close()
        finally:
            if self.flip is not None:
                self.flip.close()

    # ----- the frame

    def _draw(self) -> None:
        """rendercanvas's draw function: a failure closes the window and is raised by
        :meth:`View.run` (rendercanvas would log it and go on drawing). Ctrl-C and SIGTERM
        are taken here, inside the loop (rendercanvas's own SIGINT handler would close the
        window in the middle of a frame, with a swap-chain texture acquired and not presented):
        the first closes the window after this frame, a second one stops the frame."""
        if self.stopper == "install":
            self.stopper = Stop().__enter__()  # View.run puts the handlers back
        stop = self.stopper if isinstance(self.stopper, Stop) else None
        try:
            if stop is not None:
                stop.second_raises = True
            self._frame()
        except BaseException as e:  # returned, not raised: rendercanvas presents what it has
            self.failure = e
            self.close()
        finally:
            if stop is not None:
                stop.second_raises = False
                if stop.flag and not self.interrupted:
                    self.interrupted = True
                    self.close()

    def _frame(self) -> None:
        start = time.perf_counter()
        dt = 0.0 if self.t_last is None else min(start - self.t_last, 0.25)
        self.t_last = start
        inputs, self.controls.inputs = self.controls.inputs, []
        self.controls.move(dt)
        r = self._active()
        head = self.pose()
        lights = effective_lights(self.lights, self.live.lights_on)
        r.lights[:] = lights
        t0 = time.perf_counter()
        st = r.frame(self.f, self.t, head)
        if self.replay_log is not None:  # bounded: a long session keeps no history
            self.replay_log.append(
                FrameInput(self.f, self.t, head, lights, r.s.reuse, r.s.schedule, r.s.reuse_budget)
            )
            if len(self.replay_log) > REPLAY_MAX:
                self.replay_log = None
        right, display = self._split(head, lights)
        t1 = time.perf_counter()
        lay = self._layout(r, right, display)
        last = self.records[-1] if self.records else None
        show_hud = self.live.hud or self.live.help
        # the newest statistics that have come back (reading this frame's would wait for it)
        self.presenter.set_hud(self._hud_panel(r.latest_stats(), last) if show_hud else None)
        tex = self.context.get_current_texture()
        enc = self.dev.create_command_encoder()
        self.presenter.encode(enc, tex, tuple(tex.size[:2]), lay, self.view_format)
        self.dev.queue.submit([enc.finish()])
        if self.keep_shown or self.recorder is not None:
            self.shown = self._read(tex)
            if self.recorder is not None:
                self.recorder.add(self.shown)
        if self.want_shot:
            self.want_shot = False
            self._screenshot(r, lay)
        end = time.perf_counter()
        settings = {
            "mode": r.s.mode,
            "precision": r.s.precision,
            "texture_res": r.s.texture_res,
            "reuse": r.s.reuse,
            "schedule": r.s.schedule,
            "radiance": r.s.radiance,
            "adaptive": r.s.reuse_budget is not None,
            "reuse_budget": r.s.reuse_budget,
            "lights_on": list(self.live.lights_on),
            "split": self.live.split,
            "camera": "head path" if self.live.follow_head else self.camera.mode,
            "hud": self.live.hud,
        }
        rec = FrameRecord(
            self.f, start, end, (t1 - t0) * 1e3, (end - t1) * 1e3, st, settings, inputs
        )
        self.records.append(rec)
        self.fps_window.append(end)
        self.f += 1
        if not self.live.paused:
            self.t += 1.0 / r.s.fps
        for hook in self.hooks:
            hook(self, rec)
        if self.vc.frames and len(self.records) >= self.vc.frames:
            self.close()

    def _active(self):
        """The renderer for the current knobs; a knob that cannot be had (reference mode
        without a teacher, say) goes back, with the reason on the HUD."""
        live = self.live
        try:
            r, built = self.renderers.get(live)
        except VrnError as e:
            self.say(str(e), alert=True)
            (live.mode, live.precision, live.texture_res, live.texture_res_given,
             live.radiance) = self.good  # fmt: skip
            r, built = self.renderers.get(live)
        self.good = (live.mode, live.precision, live.texture_res, live.texture_res_given,
                     live.radiance)  # fmt: skip
        if r is not self.r:
            r.invalidate()  # taken up again: its radiance textures are another view's
            self.replay_log = []
            self.r = r
            k = live.key()
            took = self.renderers.build_s.get(k)
            self.say(
                f"{k[0]} mode, {k[1]}, {k[2]}^2"
                + (", shared radiance" if k[4] == "shared" else "")
                + (f" (built in {took:.1f} s)" if built else " (kept from before)")
                + (f"; {r.warnings[0]}" if r.warnings else "")
            )
        r.s.reuse, r.s.schedule = live.reuse, live.schedule
        r.s.reuse_budget = self.renderers.budget if live.adaptive else None
        return r

    def _split(self, head, lights):
        """The split view's right half: ``(texture, is_display_colours)`` or ``(None, _)``."""
        live = self.live
        if live.split == "off":
            return None, False
        try:
            rr, _ = self.renderers.get(live, "reference")
        except VrnError as e:
            self.say(f"split view: {e}", alert=True)
            live.split = "off"
            return None, False
        key = (live.split, live.key("reference"), id(self.r))
        busy = live.split == "flip" and self.flip is not None and self.flip.busy
        due = self.split_key != key or (
            not busy and (self.split_frame is None or self.f - self.split_frame >= self.split_every)
        )
        if due:
            self.split_key, self.split_frame = key, self.f
            if rr is not self.r:
                rr.lights[:] = lights
                rr.frame(self.f, self.t, head)
            if live.split == "flip":
                self._submit_flip(rr)
        if live.split == "flip":
            self._collect_flip()
            if self.flip_tex is not None:
                return self.flip_tex, True
        return rr.colour_textures()[0], False

    def _submit_flip(self, rr) -> None:
        if self.flip is None:
            self.flip = FlipWorker()
        ppd = pixels_per_degree(self.r.s.eye_res[1], self.r.s.fov_y)
        if self.flip.submit(rr.read_eyes()[0], self.r.read_eyes()[0], ppd):
            self.flip_pending = self.f

    def _collect_flip(self) -> None:
        import wgpu

        from vrneural.gpu.readback import upload_texture

        res = self.flip.result() if self.flip is not None else None
        if res is None:
            return
        rgba, self.flip_mean = res
        self.flip_frame = self.flip_pending
        if self.flip_tex is not None and tuple(self.flip_tex.size[:2]) == rgba.shape[1::-1]:
            h, w = rgba.shape[:2]
            self.dev.queue.write_texture(
                {"texture": self.flip_tex}, rgba, {"bytes_per_row": w * 4, "rows_per_image": h},
                (w, h, 1),
            )  # fmt: skip
        else:
            tu = wgpu.TextureUsage  # (COPY_SRC: a test reads it back)
            self.flip_tex = upload_texture(
                rgba, "rgba8unorm", tu.TEXTURE_BINDING | tu.COPY_SRC, "flip map"
            )

    def _layout(self, r, right, display: bool):
        from vrneural.viewer.present import Layout, fit

        size = self.image_size()
        eyes = r.colour_textures()
        markers = []
        if self.live.hud:
            x0, y0, s = fit(self.canvas.get_physical_size(), size)
            w, h = r.s.eye_res
            for lt, on in zip(self.lights, self.live.lights_on, strict=True):
                p = project(lt.at(self.t), self.pose(), r.s.fov_y, w / h, (w, h))
                if p is not None and 0 <= p[0] < w and 0 <= p[1] < h:
                    markers.append((x0 + p[0] * s, y0 + p[1] * s, on))
                else:
                    markers.append((-100.0, -100.0, on))  # off screen: drawn nowhere
        if self.live.split == "off":
            return Layout(eyes, size, markers=markers, selected=self.live.selected)
        live = self.live
        return Layout(
            eyes[:1], size, size[0] // 2, right, display, markers, live.selected, live.hud
        )

    def _hud_panel(self, st, last):
        lines, alert = hud_lines(self, st, last)
        w, h = self.canvas.get_physical_size()
        # the statistics take at most half of a small window (two lines at least); the help
        # may take all of it
        tall = h - 16 if self.live.help else max(h // 2, 2 * LINE_PX + 2 * PAD)
        return panel(lines, alert, max_width=w - 16, max_height=tall)

    # ----- read-backs

    def _read(self, tex) -> np.ndarray:
        """``[H, W, 3]`` uint8 RGB of the canvas texture just drawn."""
        from vrneural.gpu.readback import read_texture

        if not self.can_read:
            raise VrnError("this canvas's texture cannot be read back (no COPY_SRC usage)")
        a = read_texture(tex)
        return np.ascontiguousarray(
            a[..., [2, 1, 0]] if str(tex.format).startswith("bgra") else a[..., :3]
        )

    def _screenshot(self, r, lay) -> None:
        """``P``: the image at scale 1 without HUD or markers (PNG), its HDR (EXR: the eyes,
        or in split view eye 0 | the reference's eye 0) and the settings (JSON)."""
        import wgpu

        from vrneural.gpu.readback import read_texture
        from vrneural.viewer.present import Presenter

        w, h = lay.image
        if self._shot_target is None or tuple(self._shot_target.size[:2]) != (w, h):
            tu = wgpu.TextureUsage
            self._shot_target = self.dev.create_texture(
                size=(w, h, 1), format="rgba8unorm", usage=tu.RENDER_ATTACHMENT | tu.COPY_SRC
            )
            self._shot_presenter = Presenter("rgba8unorm")
        enc = self.dev.create_command_encoder()
        plain = dataclasses.replace(lay, markers=[], split_line=False)
        self._shot_presenter.encode(enc, self._shot_target, (w, h), plain)
        self.dev.queue.submit([enc.finish()])
        ldr = read_texture(self._shot_target)[..., :3]
        eyes = r.read_eyes()
        if lay.split is None:
            hdr = np.concatenate(eyes, axis=1)[..., :3]
        else:
            hdr = eyes[0][..., :3].copy()
            rr, _ = self.renderers.get(self.live, "reference")
            hdr[:, lay.split :] = rr.read_eyes()[0][:, lay.split :, :3]
        try:
            paths = save_shot(self.vc.shots, ldr, hdr, shot_settings(self))
        except VrnError as e:
            self.say(f"screenshot: {e}", alert=True)
            return
        self.shots += paths
        self.say(f"saved {paths[0]} (+ .exr, .json)")
