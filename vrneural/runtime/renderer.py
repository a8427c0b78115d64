"""The frame loop: per frame, the scheduled texture-space updates of visible neural objects
(per eye), then one forward pass drawing both eyes side by side (or, in the screen-space modes,
per eye the visibility pass and the per-pixel compute pass), all in one command buffer and one
submit. ``frame()`` returns without waiting for the GPU (up to ``Settings.frames_in_flight``
frames queued); the frame's counters and per-pass GPU ms (timestamps) come back in its own
submit and arrive in its :class:`~vrneural.runtime.stats.FrameStats` later (runtime/stats.py).
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import numpy as np

from vrneural.errors import VrnError, check_int, count
from vrneural.gpu.device import get_device
from vrneural.gpu.readback import read_texture
from vrneural.gpu.timing import GpuTimer
from vrneural.gpu.uniforms import UniformArena
from vrneural.runtime import forward as fw
from vrneural.runtime import settings
from vrneural.runtime.adaptive import coverage_slack, near_scale, object_directions
from vrneural.runtime.assets import collapsed_triangles, get_mesh, lost_triangles
from vrneural.runtime.camera import (
    Eye,
    OrbitPath,
    PoseLogPath,
    eyes_from_pose,
    window_matrix,
)
from vrneural.runtime.codegen import reference_weights
from vrneural.runtime.encode import FrameEncoding
from vrneural.runtime.gpu_material import GpuAtlas
from vrneural.runtime.lights import light_arrays
from vrneural.runtime.objects import NeuralObject, bounding_sphere
from vrneural.runtime.output import tonemap
from vrneural.runtime.schedule import frame_slice
from vrneural.runtime.screen_pass import ScreenSpacePass, ScreenTarget
from vrneural.runtime.screen_res import choose, level_sides, mesh_area, wanted_side
from vrneural.runtime.settings import (
    ADAPTIVE_PERIOD_MAX,
    COLOUR_CLEARS,
    DEPTH_CLEARS,
    DEPTH_SLICES,
    FRAMES_IN_FLIGHT_MAX,
    MSAA,
    NEURAL_FILTERS,
    RADIANCE,
    Settings,
)
from vrneural.runtime.stats import FrameResults, FrameStats
from vrneural.runtime.texture_pass import CounterBuffer, TextureSpacePass, TextureTarget
from vrneural.warn import VrnWarning

TARGETS = tuple(fw.TARGETS)

__all__ = ["FrameStats", "Renderer", "Settings"]


class Renderer(FrameEncoding):
    """Everything on the device for one scene and settings; :meth:`frame` renders one frame.

    What a live caller (`vrneural view`) may use between frames, and nothing else: ``lights``
    (the :class:`~vrneural.runtime.lights.PointLight` list shaded, of fixed length
    ``s.n_lights``: replace entries to move, recolour or switch off a light), ``s.reuse`` and
    ``s.schedule`` (read every frame), :meth:`frame` with a scene time and a head pose of its
    own, :meth:`colour_textures` (to draw the eyes on the GPU without a read-back) and
    :meth:`invalidate`."""

    def __init__(self, scene, s: Settings, progress=None):
        if not isinstance(s, Settings):
            raise VrnError(
                f"Renderer: settings are a {type(s).__name__}, expected Settings: pass "
                "resolve(run_config, scene, adapter_summary())"
            )
        if s.radiance not in RADIANCE:
            raise VrnError(
                f"radiance = {s.radiance!r} is not allowed; choose {', '.join(RADIANCE)}"
            )
        if s.radiance == "shared" and s.eyes != 2:
            raise VrnError(
                f"--radiance shared needs two eyes (a texture shared by both); --eyes is {s.eyes}"
            )
        check_int("frames_in_flight", s.frames_in_flight, 1, FRAMES_IN_FLIGHT_MAX)
        if s.target not in TARGETS:
            raise VrnError(f"target = {s.target!r} is not allowed; choose {', '.join(TARGETS)}")
        if s.neural_filter not in NEURAL_FILTERS:
            raise VrnError(
                f"neural_filter = {s.neural_filter!r} is not allowed; choose "
                f"{', '.join(NEURAL_FILTERS)}"
            )
        if s.colour_clear not in COLOUR_CLEARS:
            raise VrnError(
                f"colour_clear = {s.colour_clear!r} is not allowed; choose "
                f"{', '.join(COLOUR_CLEARS)}"
            )
        if s.depth_clear not in DEPTH_CLEARS:
            raise VrnError(
                f"depth_clear = {s.depth_clear!r} is not allowed; choose {', '.join(DEPTH_CLEARS)}"
            )
        if s.msaa not in MSAA:
            raise VrnError(f"msaa = {s.msaa!r} is not allowed; choose {', '.join(map(str, MSAA))}")
        if s.msaa > 1 and s.mode != "texture":
            raise VrnError(
                f"msaa = {s.msaa} needs mode 'texture' (mode {s.mode!r} shades each pixel once "
                "from a single-sample visibility target)"
            )
        if s.target == "display" and s.mode != "texture":
            raise VrnError(
                f"target = 'display' needs mode 'texture' (mode {s.mode!r} writes HDR pixels "
                "from a compute pass)"
            )
        self.scene, self.s = scene, s
        #: sub-pixel offset (x, y) of the rendered image in pixels (supersampled references)
        self.jitter = (0.0, 0.0)
        #: per eye, the crop window's top-left pixel ``(x0, y0)`` in the whole eye image for
        #: the next frame (a window that follows an object); None: ``Settings.crop``'s
        self.crop_origins: list | None = None
        self.dev = get_device()
        w, h = s.eye_res
        screen = s.mode != "texture"
        self.lights = scene.lights[: s.n_lights]
        nl = max(1, len(self.lights))
        #: every per-frame uniform, written with one write_buffer per frame
        self.arena = UniformArena("frame uniforms")
        from vrneural.gpu.device import adapter_summary

        cc, dc = s.colour_clear, s.depth_clear
        if cc == "auto":  # each the faster where measured (forward.clear_colour)
            cc = "pass" if adapter_summary().is_cpu else "compute"
        if dc == "auto":  # forward.begin_pass
            dc = "slices" if adapter_summary().adapter_type == "DiscreteGPU" else "pass"
        #: how the forward pass clears the colour: "compute" or "pass" (auto resolved)
        self.colour_clear = cc
        #: how it resets the depth: "pass" or "slices" (auto resolved)
        self.depth_clear = dc
        kw = {
            "target": s.target,
            "compute_clear": cc == "compute",
            "depth_slices": DEPTH_SLICES if dc == "slices" else 1,
            "samples": s.msaa,  # 1 in the screen modes (checked above)
        }
        if screen:  # the per-pixel pass reads and writes each eye's own targets
            self.eye_t = [
                fw.EyeTargets(w, h, nl, vis=True, arena=self.arena, **kw) for _ in range(s.eyes)
            ]
        else:  # the eyes side by side: one forward pass draws them all
            max_tex = int(self.dev.limits["max-texture-dimension-2d"])
            if s.eyes * w > max_tex:
                raise VrnError(
                    f"eye_res = {s.eye_res} with {s.eyes} eyes: mode texture draws the eyes "
                    f"side by side in one target {s.eyes * w} pixels wide, above the adapter "
                    f"maximum {max_tex}; use a width of at most {max_tex // s.eyes}"
                )
            self.eye_t = fw.EyeTargets.side_by_side(s.eyes, w, h, nl, self.arena, **kw)
        self.head = OrbitPath() if scene.head == "orbit" else PoseLogPath(scene.head)
        # Floating origin: everything uploaded to the GPU is relative to the first eye position
        # (subtracted in float64), so scenes far from the world origin keep f32 precision.
        self.origin = np.asarray(self.eyes_at(0)[0].position, np.float64)
        n_neural = sum(o.material.kind == "neural" for o in scene.objects)
        self.counters = CounterBuffer(max(1, n_neural * s.eyes))
        self.timer = GpuTimer(max_passes=2 * n_neural * s.eyes + 2 * s.eyes + 2)
        self.neural: list[NeuralObject] = []
        self.warnings: list[str] = []  # one line each; `run` prints them and keeps them
        self.draws = []
        passes: dict = {}
        self._shaded: dict = {}  # id(pack) -> the pack as shaded (settings.shaded_material)
        with warnings.catch_warnings(record=True) as caught:  # mesh warnings go in the summary
            warnings.simplefilter("always", VrnWarning)
            for i, o in enumerate(scene.objects):
                self._add_object(i, o, passes, progress)
        for w in caught:
            if issubclass(w.category, VrnWarning):
                line = " ".join(str(w.message).splitlines())
                if line not in self.warnings:  # a mesh file used by several objects: once
                    self.warnings.append(line)
            else:  # not ours: shown as it would have been
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        self.results = FrameResults(self.timer, self.counters, s.frames_in_flight, screen)
        #: passes whose timestamps this adapter does not cover (runtime/timecheck.py: checked
        #: right after the first frame; until then none)
        self.untimed: tuple = ()
        #: the check's measurements per pass (timestamps vs wall clock); None before it ran
        self.timestamp_check: dict | None = None
        self._bundles: list | None = None  # per eye, the forward pass's draws (first frame)

    def _add_object(self, i: int, o, passes: dict, progress) -> None:
        """Load object ``i``'s mesh; a neural one also gets its atlas, pass and targets."""
        from vrneural.atlas import build_atlas

        scene, s = self.scene, self.s
        say = progress or (lambda text: None)
        where = f"{scene.src}: objects[{i}] ({o.name})"  # what its errors and warnings name
        say(f"{o.name}: load mesh {o.mesh}")
        mesh = get_mesh(o.mesh, scene.base, f"{scene.src}: objects[{i}].mesh", o.crease_angle)
        if o.material.kind == "plain":
            m = o.material
            plain = (m.albedo, m.specular, m.shininess)
            self.draws.append((fw.DrawObject(mesh, None, self.rebase(o.model), i, plain), None))
            return
        res = max(s.texture_res, o.min_texture_res or 0)
        knob = "--texture-res" if res == s.texture_res else "its min_texture_res"
        if o.texture_res and not s.texture_res_given:
            res, knob = o.texture_res, "its texture_res"
        elif o.texture_res and res != o.texture_res:
            self.warnings.append(
                f"{where}: --texture-res {s.texture_res} overrides its texture_res = "
                f"{o.texture_res}"
                + (f" (min_texture_res {o.min_texture_res} kept)" if res != s.texture_res else "")
            )
        say(f"{o.name}: atlas {res}^2, {len(mesh.faces)} triangles")
        try:
            atlas = build_atlas(mesh, res, atlas_uv=o.atlas_uv, progress=progress is not None)
        except VrnError as e:  # name the object and the knobs that set its resolution
            raise VrnError(f"{where} at {res}^2 texels ({knob}): {e}") from None
        lost = lost_triangles(atlas.stats, res, "they show their neighbours' shading")
        if lost and s.mode == "texture":  # the other modes shade pixels, not texels
            self.warnings.append(f"{where}: {lost}; raise texture_res / min_texture_res")
        flat = collapsed_triangles(atlas.stats)
        if flat and s.mode == "texture":
            self.warnings.append(f"{where}: {flat}")
        c, r = bounding_sphere(atlas.mesh)
        n = NeuralObject(i, o, atlas, GpuAtlas(atlas), c, r)
        n.side, n.mesh = res, mesh
        if s.screen_res and s.mode == "texture":
            n.area = mesh_area(atlas.mesh) * abs(np.linalg.det(o.model[:3, :3])) ** (2 / 3)
            sides = []
            for side in level_sides(res):  # every level's atlas now (cached on disk after)
                try:
                    say(f"object {o.name}: atlas {side}^2")
                    n.levels[side] = (build_atlas(mesh, side), None, None, None)
                    sides.append(side)
                except VrnError:  # too small for the mesh's charts: the larger ones only
                    break
            n.level_sides = tuple(sides)
        mat = settings.shaded_material(o.material.neural, s, self._shaded)
        if s.mode == "reference":
            ref = s.reference or o.material.reference
            if ref is None and o.material.source.endswith(".vrnm"):
                hint = o.material.reference_hint  # --pack: where we looked
                how = (
                    f"pass --reference TEACHER.vrnm ({hint})"
                    if hint
                    else "set material.reference in the scene or pass --reference TEACHER.vrnm"
                )
                raise VrnError(
                    f"{where}: --mode reference needs a teacher for "
                    f"{Path(o.material.source).name}: {how}"
                )
            method = ref.meta.get("method") if ref is not None else None
            if method not in (None, "teacher"):  # allowed (a comparison), but not ground truth
                self.warnings.append(
                    f"{where}: the reference is a {method} pack, not a teacher: reference mode "
                    "shows that network, not the ground truth"
                )
            mat = ref or mat  # a procedural material is its own ground truth
        key = id(mat)
        if key not in passes:
            say(f"{o.name}: compile shaders ({s.mode} mode)")
            try:
                passes[key] = self._make_pass(mat)
            except VrnError as e:  # name the object and its pack, not the BTF inside
                src = o.material.source or "procedural"
                raise VrnError(f"{scene.src}: objects[{i}] ({o.name}, {src}): {e}") from None
        n.tpass = passes[key]
        shared = s.mode == "texture" and s.radiance == "shared"
        for e in range(1 if shared else s.eyes):
            n.targets.append(self._make_target(passes[key], n, e))
        self.neural.append(n)
        n.draw = fw.DrawObject(atlas.mesh, atlas.uv_atlas, self.rebase(o.model), i)
        n.levels[res] = (atlas, n.gatlas, n.draw, n.targets)
        self.draws.append((None, n))

    def _use_level(self, n: NeuralObject, side: int) -> None:
        """Shade and draw neural object ``n`` at radiance-texture side ``side`` (screen_res):
        its GPU atlas, draw and targets are made on first use; the level gets a full update
        before it is shown."""
        atlas, gatlas, draw, targets = n.levels[side]
        if gatlas is None:
            gatlas = GpuAtlas(atlas)
            draw = fw.DrawObject(atlas.mesh, atlas.uv_atlas, self.rebase(n.desc.model), n.idx)
            n.atlas, n.gatlas = atlas, gatlas
            targets = [self._make_target(n.tpass, n, e) for e in range(len(n.targets))]
            n.levels[side] = (atlas, gatlas, draw, targets)
        n.atlas, n.gatlas, n.draw, n.targets, n.side = atlas, gatlas, draw, targets, side
        n.fresh = False
        self._bundles = None  # the eyes' draws name the level's vertices and texture

    def _level_for(self, n: NeuralObject, eyes) -> int:
        """The side :mod:`~vrneural.runtime.screen_res` picks for ``n`` seen by ``eyes``; sets
        ``n.lod_scale`` (``Settings.lod_footprint``)."""
        s = self.s
        c, r = self.world_sphere(n)
        d = min(float(np.linalg.norm(c - e.position)) for e in eyes) - r
        cover = float(np.mean(n.levels[n.level_sides[0]][0].tri_ids != 0xFFFFFFFF))
        h = s.crop[3] if s.crop else s.eye_res[1]
        want = wanted_side(n.area, cover, max(d, 0.01), s.fov_y, h)
        side = choose(n.level_sides, n.side, want)
        # the pixel over the texel where the texel is the smaller (a side rounded up, or kept
        # by the hysteresis): the neural textures are then prefiltered to what a pixel covers
        pixel = s.lod_footprint == "pixel" or (s.lod_footprint == "auto" and not s.mips)
        n.lod_scale = max(1.0, side / want) if pixel else 1.0
        return side

    def rebase(self, model: np.ndarray) -> np.ndarray:
        """``model [4, 4]`` with the floating origin subtracted (float64)."""
        m = np.array(model, np.float64)
        m[:3, 3] -= self.origin
        return m

    def _make_pass(self, mat):
        s = self.s
        if s.mode == "texture":
            return TextureSpacePass(
                mat, s.precision, len(self.lights), filtering=s.neural_filter, taps=s.lod_taps
            )
        if s.mode == "screen":
            return ScreenSpacePass(mat, s.precision, len(self.lights), filtering=s.neural_filter)
        if s.mode == "reference":
            return ScreenSpacePass(mat, "f32", len(self.lights), weights=reference_weights(mat))
        raise VrnError(f"mode = {s.mode!r} is not allowed; choose texture, screen or reference")

    def _make_target(self, p, n: NeuralObject, eye: int):
        if self.s.mode == "texture":
            return TextureTarget(p, n.gatlas, self.counters, self.arena, mips=self.s.mips)
        return ScreenTarget(p, n.gatlas, self.eye_t[eye], self.counters, self.arena)

    @staticmethod
    def world_sphere(n: NeuralObject) -> tuple[np.ndarray, float]:
        """Object ``n``'s bounding sphere in the world (centre [3], radius m)."""
        model = n.desc.model
        key = model.tobytes()
        if n.sphere[0] != key:  # computed again only when the model matrix changed
            c = model[:3, :3] @ n.centre + model[:3, 3]
            r = n.radius * float(np.linalg.norm(model[:3, :3], axis=0).max())
            n.sphere = (key, c, r, np.append(c, 1.0))
        return n.sphere[1], n.sphere[2]

    def _visible(self, n: NeuralObject, eyes) -> bool:
        """Whether ``n``'s bounding sphere touches any eye's frustum (conservative)."""
        self.world_sphere(n)
        _, _, r, ch = n.sphere
        return any(bool((e.planes @ ch >= -r).all()) for e in eyes)

    def _visible_all(self, eyes) -> list[bool]:
        """:meth:`_visible` of every neural object (one product per eye for all of them)."""
        if not self.neural:
            return []
        for n in self.neural:
            self.world_sphere(n)
        ch = np.array([n.sphere[3] for n in self.neural]).T  # [4, objects]
        r = np.array([n.sphere[2] for n in self.neural])
        vis = np.zeros(len(self.neural), bool)
        for e in eyes:
            vis |= (e.planes @ ch >= -r).all(0)
        return vis.tolist()

    def eyes_at(self, frame: int, t: float | None = None, head=None):
        """The eyes at display frame ``frame`` (the whole view: visibility and shading): the
        scene's head path at time ``t`` (s; default ``frame / fps``), or the head pose
        ``head = (position [3], rotation [3, 3])`` (metres, camera-to-world) when given: a live
        camera."""
        s = self.s
        if head is None:
            pos, rot = self.head.pose(frame / s.fps if t is None else t)
        else:
            pos, rot = (np.asarray(a, np.float64) for a in head)
            if (
                pos.shape != (3,)
                or rot.shape != (3, 3)
                or not np.isfinite([*pos, *rot.ravel()]).all()
            ):
                raise VrnError(
                    f"head = (position {pos.shape}, rotation {rot.shape}): expected a finite "
                    "position [3] and rotation [3, 3]"
                )
        w, h = s.crop[2:] if s.crop else s.eye_res
        return eyes_from_pose(pos, rot, s.ipd, s.eyes, s.fov_y, w / h)

    def raster_eyes(self, eyes) -> list:
        """``eyes`` with the projection the images are rendered with: the crop window
        (``Settings.crop``) and the sub-pixel :attr:`jitter` applied."""
        s = self.s
        if s.crop is None and self.jitter == (0.0, 0.0):
            return eyes
        out = []
        for e, eye in enumerate(eyes):
            crop = s.crop
            if crop is not None and self.crop_origins is not None:
                crop = (*self.crop_origins[e], *crop[2:])
            m = window_matrix(s.eye_res, crop, self.jitter)
            out.append(Eye(eye.position, eye.view, m @ eye.proj))
        return out

    def _slices(self, f: int, eyes, lp) -> tuple[list, int, int]:
        """The texture-space work of frame ``f``: ``[(k, object, phase, period)]``, and the
        counts of objects updated and culled."""
        s = self.s
        sl = frame_slice(f, s.reuse, s.schedule)
        adaptive = s.reuse_budget is not None
        centre = np.mean([e.position for e in eyes], axis=0) if adaptive else None
        todo, culled = [], 0
        for k, (n, vis) in enumerate(zip(self.neural, self._visible_all(eyes), strict=True)):
            if not vis:
                culled += 1
                n.fresh = False
                continue
            if n.level_sides:  # resolution from the screen
                side = self._level_for(n, eyes)
                if side != n.side:
                    self._use_level(n, side)
            if not n.fresh:  # first sight (or back in view): one full update
                n.fresh = True
                todo.append((k, n, 0, 1))
                if s.reuse_budget is not None:
                    n.adapt.restart(object_directions(n.desc.model, n.centre, centre, lp))
                continue
            if s.reuse_budget is not None:
                model = n.desc.model
                dirs = object_directions(model, n.centre, centre, lp)
                scale = near_scale(model, n.centre, n.radius, np.vstack([centre[None], lp]))
                budget = s.reuse_budget * coverage_slack(self._coverage(n, eyes[0]))
                staggered = s.schedule == "staggered"
                a = n.adapt.step(dirs, scale, budget, ADAPTIVE_PERIOD_MAX, staggered)
                if a.update:
                    todo.append((k, n, a.phase, a.period))
            elif sl.update:
                todo.append((k, n, sl.phase, sl.period))
        return todo, len(todo), culled

    def _coverage(self, n: NeuralObject, eye) -> float:
        """The fraction of the (whole) eye image the object's bounding sphere covers."""
        c, r = self.world_sphere(n)
        d = float(np.linalg.norm(c - eye.position))
        if d <= r:
            return 1.0
        w, h = self.s.crop[2:] if self.s.crop else self.s.eye_res
        ang = np.arcsin(r / d)  # the sphere's angular radius
        half = np.radians(self.s.fov_y) / 2
        frac = np.pi * (np.tan(ang) / np.tan(half)) ** 2 / (4 * w / h)
        return float(min(frac, 1.0))

    def frame(self, f: int, t: float | None = None, head=None) -> FrameStats:
        """Render display frame ``f``: encode and submit it, and return without waiting for the
        GPU (its statistics fill in when it has finished: :class:`FrameStats`). ``f`` drives
        the reuse schedule; ``t`` (s, default ``f / fps``) the lights' motion and the head
        path; ``head`` replaces the head path (see :meth:`eyes_at`). Waits only when
        ``Settings.frames_in_flight`` frames are still queued (or, with :attr:`pass_clock`
        ``"wall"``, after every pass)."""
        check_int("frame", f, 0)
        s = self.s
        t0, c0 = time.perf_counter(), time.thread_time()
        slot = self.results.begin()
        if self.pass_clock == "wall":
            self.results.wait()
        self._wall: dict = {}
        eyes = self.eyes_at(f, t, head)
        lp, lc = light_arrays(self.lights, f / s.fps if t is None else t)
        self._last = (eyes, lp, lc)
        enc = self.dev.create_command_encoder()
        self.counters.clear(enc)
        updated = culled = 0
        if s.mode == "texture":
            todo, updated, culled = self._slices(f, eyes, lp)
            if todo:
                enc = self._encode_texture(enc, todo, eyes, lp, lc)
        c, enc = self._encode_eyes(enc, self.raster_eyes(eyes), lp, lc)
        culled += c
        names = self.results.copy_into(enc, slot)
        self.arena.flush()
        self.dev.queue.submit([enc.finish()])
        wall = {k: v for k, v in self._wall.items() if not k.startswith("_")}
        untimed = self.untimed if self.pass_clock != "wall" else ()
        st = FrameStats(f, 0 if s.mode != "texture" else updated, culled, untimed)
        st.clock = self.pass_clock
        if s.mode == "texture":  # per neural object: side, texels allocated; blocks shaded later
            st.object_res = [n.side for n in self.neural]
            st.object_texels = [n.side**2 * len(n.targets) for n in self.neural]
            st.object_lod_scale = [n.lod_scale for n in self.neural]
            st._objects = (len(self.neural), s.eyes)
        st._start, st.in_flight = t0, self.results.in_flight()
        self.results.submitted(slot, st, names, wall or None)
        st.host_ms = (time.perf_counter() - t0) * 1e3
        st.cpu_ms = (time.thread_time() - c0) * 1e3
        if self.timestamp_check is None:  # after the first frame: are the timestamps true?
            from vrneural.runtime.timecheck import check_timestamps

            self.timestamp_check = check_timestamps(self)
            self.untimed = tuple(k for k, v in self.timestamp_check.items() if not v["covered"])
            st.untimed = self.untimed
        return st

    def set_frames_in_flight(self, depth: int) -> None:
        """Let the GPU queue ``depth`` frames from the next one on (1..3; waits for those in
        flight now)."""
        check_int("frames_in_flight", depth, 1, FRAMES_IN_FLIGHT_MAX)
        self.wait()
        self.s.frames_in_flight = depth
        self.results = FrameResults(self.timer, self.counters, depth, self.s.mode != "texture")

    def wait(self) -> None:
        """Wait until the GPU has finished every submitted frame; their statistics are in."""
        self.results.wait()

    def latest_stats(self) -> FrameStats | None:
        """The newest frame whose statistics are in, without waiting (the viewer's HUD)."""
        self.results.poll()
        return self.results.latest

    def _shading_eyes(self, eyes) -> list[tuple[np.ndarray, float]]:
        """Where each radiance texture is shaded from: ``(eye position, facing margin)`` per
        eye, or once from the eyes' centre with a margin of half their distance (shared)."""
        if self.s.radiance == "shared":
            a, b = eyes[0].position, eyes[1].position
            return [((a + b) / 2, float(np.linalg.norm(a - b)) / 2)]
        return [(e.position, 0.0) for e in eyes]

    def colour_textures(self) -> list:
        """The eyes' HDR colour textures (``rgba16float``, sampled-texture usage) as the last
        :meth:`frame` left them, for drawing them on the GPU without a read-back (`vrneural
        view`): commands submitted after that frame see its result. In mode texture one
        texture, the eyes side by side (``eyes x eye_res`` wide); in the screen modes one per
        eye."""
        out = []
        for et in self.eye_t:
            if all(et.colour is not t for t in out):
                out.append(et.colour)
        return out

    def _read_colour(self) -> list[np.ndarray]:
        """Each eye's colour target as stored (its columns of a shared texture)."""
        got: dict = {}
        out = []
        for et in self.eye_t:
            if id(et.colour) not in got:
                got[id(et.colour)] = read_texture(et.colour)
            out.append(got[id(et.colour)][:, et.x0 : et.x0 + et.size[0]])
        return out

    def invalidate(self) -> None:
        """Forget what the radiance textures hold: the next frame gives every visible neural
        object one full update, as on first sight (a renderer taken up again after others ran,
        or a camera that jumped)."""
        for n in self.neural:
            n.fresh = False

    def read_eyes(self) -> list[np.ndarray]:
        """The eyes' HDR colour ``[H, W, 4]`` float32 of the last frame (waits for it)."""
        if self.s.target != "hdr":
            raise VrnError(
                f"read_eyes: this renderer's eye targets are {self.s.target!r} (tonemapped, 8 "
                "bits); HDR needs target 'hdr' (read_display gives the display colours)"
            )
        self.wait()
        return [c.astype(np.float32) for c in self._read_colour()]

    def read_display(self) -> list[np.ndarray]:
        """The eyes' display colours ``[H, W, 3]`` uint8 (sRGB) of the last frame (waits for
        it): the display target as it is, or the HDR target through ``output.tonemap``."""
        self.wait()
        if self.s.target == "display":
            return [np.ascontiguousarray(c[..., :3]) for c in self._read_colour()]
        return [tonemap(c.astype(np.float32)) for c in self._read_colour()]

    def radiance(self, obj: int = 0, eye: int = 0) -> np.ndarray:
        """Radiance texture ``[R, R, 4]`` float32 of neural object ``obj`` (counting neural
        objects only, in scene order) for ``eye``; texture mode only. RGB is linear radiance
        where the last update shaded a front-facing block, alpha 0 outside the atlas charts."""
        if self.s.mode != "texture":
            raise VrnError(
                f"radiance: there are radiance textures only in mode 'texture' (this renderer "
                f"is in mode {self.s.mode!r})"
            )
        n = len(self.neural)
        check_int("radiance: obj", obj)
        check_int("radiance: eye", eye)
        if not 0 <= obj < n:
            raise VrnError(
                f"radiance: obj = {obj!r} is out of range; the scene has "
                f"{count(n, 'neural object')} (0..{n - 1}; plain objects are not counted)"
            )
        if not 0 <= eye < self.s.eyes:
            raise VrnError(f"radiance: eye = {eye!r} is out of range; eyes 0..{self.s.eyes - 1}")
        tgts = self.neural[obj].targets
        return read_texture(tgts[eye if len(tgts) > 1 else 0].texture).astype(np.float32)
