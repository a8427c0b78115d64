"""The commands of one frame (mixed into :class:`~vrneural.runtime.renderer.Renderer`): the
texture-space updates in one compute pass, then the forward pass (mode texture: one pass, the
eyes side by side, each eye's render bundle in its viewport; the screen modes: per eye, the
forward pass and the per-pixel pass). Everything goes into the frame's one encoder;
uniforms into the renderer's arena (sent once, before the submit).

With ``Renderer.pass_clock = "wall"`` each pass is instead submitted alone and waited for, and
timed by the wall clock (``_cut``): per-pass times on an adapter whose timestamps do not cover
a pass (runtime/timecheck.py), at the price of frames in flight and of the submits.
"""

from __future__ import annotations

import time

import numpy as np

from vrneural.runtime import forward as fw
from vrneural.runtime.screen_pass import screen_rect


class FrameEncoding:
    """Encoding half of the renderer (its state lives on the Renderer)."""

    #: "timestamps" (one submit per frame, GPU timestamps) or "wall" (a submit per pass, each
    #: waited for and timed by the wall clock; no frames in flight)
    pass_clock = "timestamps"

    def _writes(self, name: str):
        return self.timer.writes(name) if self.pass_clock != "wall" else None

    def _cut(self, enc, name: str):
        """``pass_clock == "wall"``: submit what ``enc`` holds (the pass ``name`` after any
        commands before it), wait for it, add its wall ms to the frame's ``_wall`` and return
        a new encoder; otherwise ``enc``."""
        if self.pass_clock != "wall":
            return enc
        self._wall[name] = self._wall.get(name, 0.0) + self._submit_and_wait(enc)
        return self.dev.create_command_encoder()

    def _submit_and_wait(self, enc) -> float:
        """Submit ``enc`` (the arena's uniforms first) and wait for it; returns the wall ms."""
        self.arena.flush()
        t0 = time.perf_counter()
        self.dev.queue.submit([enc.finish()])
        self.dev.queue.read_buffer(self.counters.buf, 0, 16)  # a copy after the pass: waits
        return (time.perf_counter() - t0) * 1e3

    def _encode_texture(self, enc, todo, eyes, lp, lc):
        """All of a frame's texture-space dispatches, in one compute pass; returns the
        encoder to go on with."""
        if self.pass_clock == "wall":  # everything before the pass, first
            enc = self._cut(enc, "_before")
        cp = enc.begin_compute_pass(timestamp_writes=self._writes("texture"))
        self._dispatch_updates(cp, todo, eyes, lp, lc)
        cp.end()
        return self._cut(enc, "texture")

    def _dispatch_updates(self, cp, todo, eyes, lp, lc) -> None:
        """The updates ``todo = [(k, object, phase, period)]`` into the open compute pass
        ``cp``: their uniforms written, each target's dispatches recorded."""
        bound, shading = None, self._shading_eyes(eyes)
        for k, n, phase, period in todo:
            tiling = (n.desc.material.tiling,) * 2 + (0.0, 0.0)
            for e, ((pos, margin), tgt) in enumerate(zip(shading, n.targets, strict=True)):
                slot = k * self.s.eyes + e
                tgt.update(
                    n.desc.model, pos, tiling, lp, lc, phase, period, slot, margin, n.lod_scale
                )
                bound = tgt.dispatch(cp, phase, period, bound=bound)

    def _encode_eyes(self, enc, eyes, lp, lc) -> tuple:
        """Per eye, the forward pass (replaying its bundle) and, in the screen modes, the
        per-pixel pass; returns the (object, eye) pairs culled there and the encoder."""
        s = self.s
        shift = np.eye(4)
        shift[:3, 3] = self.origin
        lp_r = lp - self.origin
        culled = 0
        vps = []
        for eye, et in zip(eyes, self.eye_t, strict=True):
            vps.append(eye.view_proj @ shift)  # origin-relative position -> clip
            et.update(vps[-1], eye.position - self.origin, lp_r, lc)
        if s.mode == "texture":  # the eyes side by side: one pass
            if self.pass_clock == "wall":
                enc = self._cut(enc, "_before")
            self.encode_forward(enc)
            return culled, self._cut(enc, "forward")
        for e, eye in enumerate(eyes):
            if self.pass_clock == "wall":
                enc = self._cut(enc, "_before")
            self.encode_forward(enc, e)
            enc = self._cut(enc, "forward")
            culled += self._encode_screen(enc, e, eye, vps[e], lp_r, lc)
            enc = self._cut(enc, "screen")
        return culled, enc

    def encode_forward(
        self, enc, e: int | None = None, bundles: list | None = None, name="forward", timer=None
    ) -> None:
        """The forward pass of eye ``e`` (None: of every eye) into ``enc``: the eyes' bundles
        (or ``bundles``: the bench's floors over the same draws), timed as ``name`` (by
        ``timer``, default the frame's). Eyes side by side in one set of targets
        (:meth:`EyeTargets.side_by_side <vrneural.runtime.forward.EyeTargets.side_by_side>`,
        mode texture) are drawn in one pass, a viewport each; otherwise a pass per eye."""
        if self._bundles is None:
            self._bundles = [
                fw.record_bundle(et, self.draw_list(e, et)) for e, et in enumerate(self.eye_t)
            ]
        bundles = bundles or self._bundles
        ts = timer.writes if timer is not None else self._writes
        ets = self.eye_t

        def begin(et):  # the clear's time (a compute pass where there is one) counts too
            return fw.begin_pass(enc, et, ts(name), ts(name) if et.compute_clear else None)

        shared = len(ets) > 1 and ets[1].colour is ets[0].colour
        if shared:
            if e is not None:  # a pass clears the whole target: the other eyes' too
                raise ValueError("encode_forward: eyes side by side are drawn together (e=None)")
            rp = begin(ets[0])
            for et, b in zip(ets, bundles, strict=True):
                fw.viewport(rp, et)
                rp.execute_bundles([b])
            rp.end()
            return
        for k in range(len(ets)) if e is None else (e,):
            rp = begin(ets[k])
            rp.execute_bundles([bundles[k]])
            rp.end()

    def draw_list(self, e: int, et, fragment: str | None = None) -> list:
        """Eye ``e``'s draws ``[(pipeline, object bind group, DrawObject)]``; ``fragment``
        replaces every draw's fragment entry point (``fs_floor_*``: the bench's floors; plain
        objects then sample the first radiance texture)."""
        s = self.s
        vis = s.mode != "texture"
        nl, na, mips, ms = et.n_lights, len(self.lights), s.mips, et.samples
        out = []
        for d, n in self.draws:
            d = d if n is None else n.draw  # a neural object: the atlas level in use
            if fragment is not None:
                tgt = (n or self.neural[0]).targets
                tgt = tgt[e if len(tgt) > 1 else 0]
                pipe = fw.render_pipeline(nl, fragment, False, na, et.format, mips, ms)
                key = ("eye", e, tgt.R) if n is not None else ("floor", e, tgt.R)
                bg = d.bind_group(tgt.sample_view, key, mips)
            elif n is None:
                pipe = fw.render_pipeline(
                    nl, "fs_plain_vis" if vis else "fs_plain", vis, na, et.format, False, ms
                )
                bg = d.bind_group(None, "plain")
            elif vis:
                pipe = fw.render_pipeline(nl, "fs_neural_vis", True, na)
                bg = d.bind_group(None, "plain")
            else:
                pipe = fw.render_pipeline(nl, "fs_neural", False, na, et.format, mips, ms)
                tgt = n.targets[e if len(n.targets) > 1 else 0]  # shared: one for both
                bg = d.bind_group(tgt.sample_view, ("eye", e), mips)
            out.append((pipe, bg, d))
        return out

    def _encode_screen(self, enc, e: int, eye, vp_r, lp_r, lc) -> int:
        s = self.s
        inv = np.linalg.inv(vp_r)
        cp = enc.begin_compute_pass(timestamp_writes=self._writes("screen"))
        culled = 0
        for k, n in enumerate(self.neural):
            if not self._visible(n, [eye]):
                culled += 1
                continue
            tiling = (n.desc.material.tiling,) * 2 + (0.0, 0.0)
            tgt = n.targets[e]
            c, r = self.world_sphere(n)
            rect = screen_rect(c, r, eye.view_proj, *s.eye_res)
            slot = k * s.eyes + e
            model_r, eye_r = self.rebase(n.desc.model), eye.position - self.origin
            tgt.update(model_r, eye_r, tiling, inv, lp_r, lc, slot, n.idx, rect)
            tgt.dispatch(cp)
        cp.end()
        return culled
