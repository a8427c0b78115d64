"""Screen-space per-pixel shading (``shaders/screen_space.wgsl``): the comparison modes.

``--mode screen``: the same student per pixel every frame (constant weights, chosen precision).
``--mode reference``: the best network per pixel in f32 with storage-buffer weights (a teacher
pack if given, else the material's own pack). The visibility pass (forward.py, ``*_vis``
entry points) runs first; this pass writes the neural objects' pixels into the eye's colour.
"""

from __future__ import annotations

import math

import numpy as np

from vrneural.gpu.device import get_device, has_feature
from vrneural.gpu.pipelines import compute_pipeline
from vrneural.gpu.uniforms import UniformArena
from vrneural.material import NeuralMaterial
from vrneural.runtime.codegen import material_spec, screen_space_wgsl
from vrneural.runtime.gpu_material import GpuAtlas, GpuMaterial
from vrneural.runtime.interface import LIGHT, SCREEN_PARAMS, screen_bindings
from vrneural.runtime.reference import normal_matrix
from vrneural.runtime.texture_pass import (
    ARGS_BINDINGS,
    CompactionBuffers,
    dispatch_compacted,
    pack_lights_into,
)

PARAMS_BYTES = SCREEN_PARAMS.size  # 256


def screen_rect(centre, radius, view_proj, width, height) -> tuple[int, int, int, int]:
    """Pixel rectangle ``(x0, y0, w, h)`` covering a world bounding sphere (the whole screen
    when the sphere reaches behind the eye)."""
    c = np.asarray(centre, np.float64)
    corners = c + radius * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    clip = np.c_[corners, np.ones(8)] @ np.asarray(view_proj, np.float64).T
    if (clip[:, 3] <= 1e-6).any():
        return (0, 0, width, height)
    ndc = clip[:, :2] / clip[:, 3:]
    x0 = int(np.clip(np.floor((ndc[:, 0].min() + 1) / 2 * width), 0, width))
    x1 = int(np.clip(np.ceil((ndc[:, 0].max() + 1) / 2 * width), 0, width))
    y0 = int(np.clip(np.floor((1 - ndc[:, 1].max()) / 2 * height), 0, height))
    y1 = int(np.clip(np.ceil((1 - ndc[:, 1].min()) / 2 * height), 0, height))
    return (x0, y0, max(0, x1 - x0), max(0, y1 - y0))


class ScreenSpacePass:
    """Compiled per-pixel kernel for one material."""

    def __init__(
        self,
        mat: NeuralMaterial,
        precision="f32",
        n_lights=1,
        weights="constants",
        subgroups=None,
        filtering="exact",
    ):
        self.mat = mat
        self.n_lights = max(1, n_lights)  # size of the lights uniform (0 lights: one unused)
        self.subgroups = has_feature("subgroup") if subgroups is None else subgroups
        self.code = screen_space_wgsl(mat, precision, n_lights, weights, self.subgroups, filtering)
        self.gmat = GpuMaterial(mat, weights, filtering)
        self.bindings = screen_bindings(material_spec(mat, weights, filtering), n_lights)
        self.pipes = {
            e: compute_pipeline(self.code, e, label=f"screen_space/{e}")
            for e in ("cull", "args", "main")
        }


_SCRATCH: dict = {}


def _scratch(width: int, height: int) -> CompactionBuffers:
    """The compaction buffers for one eye size, shared by every screen target: their
    dispatches run one after another in a pass."""
    key = (get_device(), width, height)
    if key not in _SCRATCH:
        _SCRATCH[key] = CompactionBuffers(width * height)
    return _SCRATCH[key]


class ScreenTarget:
    """One (object, eye) per-pixel shading dispatch; its uniforms live in ``arena`` (the
    renderer's, written once per frame; by default one of its own, written at every
    :meth:`update`)."""

    def __init__(self, spass: ScreenSpacePass, gatlas: GpuAtlas, eye_targets, counters, arena=None):
        self.spass = spass
        self.size = eye_targets.size
        self.arena = arena or UniformArena("screen target", auto_flush=True)
        self.p_off = self.arena.alloc(PARAMS_BYTES)
        self.l_off = self.arena.alloc(LIGHT.size * spass.n_lights)
        self.compact = _scratch(*self.size)
        self._res = {
            "verts": {"buffer": gatlas.verts},
            "faces": {"buffer": gatlas.faces},
            "vis": eye_targets.vis.create_view(),
            "out_tex": eye_targets.colour.create_view(),
            "counters": {"buffer": counters.buf},
            **self.compact.resources(),
            **spass.gmat.resources(),
        }
        self._binds: dict | None = None
        self.rect = (0, 0, 0, 0)

    @property
    def binds(self) -> dict:
        """The entry points' bind groups, made on first use (after the arena's last alloc)."""
        if self._binds is None:
            res = dict(self._res)
            res["P"] = self.arena.binding(self.p_off, PARAMS_BYTES)
            res["lights"] = self.arena.binding(self.l_off, LIGHT.size * self.spass.n_lights)
            used = {  # an entry point's auto layout holds the bindings it uses, and only those
                "cull": ("P", "vis", "todo", "todo_n"),
                "args": ARGS_BINDINGS,
                "main": tuple(k for k in res if k not in ("todo_n", "ind")),
            }
            self._binds = {
                e: get_device().create_bind_group(
                    layout=self.spass.pipes[e].get_bind_group_layout(0),
                    entries=self.spass.bindings.entries(res, keys),
                )
                for e, keys in used.items()
            }
        return self._binds

    def update(self, model, eye, tiling, inv_view_proj, light_pos, light_rgb, slot, obj_id, rect):
        """Uniforms of this dispatch; ``rect`` = (x0, y0, w, h) pixels to cover."""
        w, h = self.size
        self.rect = rect
        ar = self.arena
        p = SCREEN_PARAMS.view(ar.view(self.p_off, PARAMS_BYTES, np.uint8))[0]
        m32 = np.asarray(model, np.float32)
        p["model"] = m32.T
        p["normal_mat"] = normal_matrix(m32).T
        p["eye"][:3] = np.asarray(eye, np.float32)[:3]
        p["tiling"] = np.asarray(tiling, np.float32)
        p["inv_view_proj"] = np.asarray(inv_view_proj, np.float32).T
        p["screen"] = (w, h, slot, obj_id)
        p["rect"] = rect
        lights = LIGHT.view(ar.view(self.l_off, LIGHT.size * self.spass.n_lights, np.uint8))
        pack_lights_into(lights, light_pos, light_rgb)
        ar.written()

    def dispatch(self, cp) -> None:
        """Record this target's dispatches into compute pass ``cp``: list the rectangle's pixels
        that show the object, then shade only those."""
        w, h = self.rect[2], self.rect[3]
        if w and h:
            cull_grid = (math.ceil(w / 8), math.ceil(h / 8))
            dispatch_compacted(cp, self.spass.pipes, self.binds, cull_grid, self.compact.ind)
