"""Drawing the renderer's eyes into the viewer's target (``shaders/view_present.wgsl``) and
its numpy twin :func:`compose`.

The HDR eye textures (``rgba16float``) stay on the GPU: one render pass maps each window
pixel to an image pixel and tonemaps it through :func:`tonemap_lut`, a table of
:func:`vrneural.runtime.output.tonemap` over all 65536 float16 values, so a pixel shown at
scale 1 is bit for bit the pixel `vrneural run` writes to its PNG.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from vrneural.gpu.bindings import Binding, Bindings, Struct
from vrneural.gpu.device import get_device
from vrneural.gpu.readback import upload_buffer, upload_texture
from vrneural.gpu.shaders import render_wgsl
from vrneural.runtime.output import tonemap

MAX_MARKERS = 9


def tonemap_lut(exposure: float = 1.0) -> np.ndarray:
    """``[65536]`` uint32: the 8-bit display value of every float16 bit pattern, by
    :func:`~vrneural.runtime.output.tonemap` (so NaN and negatives as it maps them)."""
    h = np.arange(65536, dtype=np.uint32).astype(np.uint16).view(np.float16)
    with np.errstate(all="ignore"):  # the NaN and infinity patterns, handled by tonemap
        rgb = np.repeat(h.astype(np.float32)[None, :, None], 3, axis=2)
        return tonemap(rgb, exposure)[0, :, 0].astype(np.uint32)


@dataclass
class Layout:
    """What one present pass shows: ``eyes`` (HDR textures, side by side) or, split,
    ``eyes[0]`` left of column ``split`` and ``right`` (HDR, or 8-bit display colours when
    ``right_is_display``) from there on. ``markers``: window ``(x, y, on)`` per light."""

    eyes: list
    image: tuple[int, int]  # (width, height) of the image: eye width x eyes, or one eye
    split: int | None = None
    right: object = None
    right_is_display: bool = False
    markers: list = field(default_factory=list)
    selected: int = -1
    split_line: bool = False


def fit(window: tuple[int, int], image: tuple[int, int]) -> tuple[float, float, float]:
    """``(x0, y0, scale)``: the image centred in the window, as large as fits; whole-number
    scales when it fits at least once (scale 1: each window pixel is one image pixel)."""
    s = min(window[0] / image[0], window[1] / image[1])
    if s >= 1:
        s = float(int(s))
    x0 = float(int((window[0] - image[0] * s) / 2))
    y0 = float(int((window[1] - image[1] * s) / 2))
    return x0, y0, s


#: one draw's uniform (a panel or an overlay)
DRAW = Struct(
    "Draw",
    [("origin", "vec2<f32>", "window pixel of the source's (0, 0)"),
     ("scale", "f32", "window pixels per source pixel"),
     ("kind", "u32", "overlay: 0 the texture times tint, 1 fill with tint"),
     ("tint", "vec4<f32>", "overlay: colour multiplier (fill: the colour)")],
)  # fmt: skip
#: the present pass's bind group: every draw's uniform in one buffer at dynamic offsets
PRESENT_BINDINGS = Bindings([
    Binding(0, "D", "uniform", DRAW, dynamic=True),
    Binding(1, "src", "texture", "texture_2d<f32>"),
    Binding(2, "lut", "storage", "array<u32>", "f16 bits -> 8-bit display value"),
])  # fmt: skip
SLOT = 256  # bytes per draw's uniforms (the dynamic-offset alignment)
SLOTS = 16
RING = 15  # marker ring size, pixels


def _ring() -> np.ndarray:
    """``[RING, RING, 4]`` uint8: a white ring (alpha), the light marker."""
    c = (RING - 1) / 2
    y, x = np.mgrid[0:RING, 0:RING]
    d = np.hypot(x - c, y - c)
    a = np.clip(1.6 - np.abs(d - 5.5), 0, 1)
    out = np.full((RING, RING, 4), 255, np.uint8)
    out[..., 3] = np.round(a * 255).astype(np.uint8)
    return out


@functools.cache
def _pipelines(target_format: str):
    import wgpu

    dev = get_device()
    entries = PRESENT_BINDINGS.layout_entries(wgpu.ShaderStage.FRAGMENT, sized=True)
    layout = dev.create_bind_group_layout(entries=entries)
    code = render_wgsl("view_present", structs=DRAW.wgsl(), bindings=PRESENT_BINDINGS.wgsl())
    mod = dev.create_shader_module(code=code, label="view_present")
    pl = dev.create_pipeline_layout(bind_group_layouts=[layout])
    blend = {
        "color": {"src_factor": "src-alpha", "dst_factor": "one-minus-src-alpha"},
        "alpha": {"src_factor": "one", "dst_factor": "one-minus-src-alpha"},
    }
    pipes = {}
    srgb = {"SRGB": target_format.endswith("-srgb")}
    for entry, target in (
        ("fs_panel", {"format": target_format}),
        ("fs_display", {"format": target_format}),
        ("fs_overlay", {"format": target_format, "blend": blend}),
    ):
        pipes[entry] = dev.create_render_pipeline(
            layout=pl,
            vertex={"module": mod, "entry_point": "vs_main", "buffers": []},
            primitive={"topology": "triangle-list"},
            fragment={"module": mod, "entry_point": entry, "targets": [target], "constants": srgb},
            label=f"view_present/{entry}",
        )
    return pipes, layout


def _clip(rect, window) -> tuple[int, int, int, int] | None:
    """``rect = (x0, y0, x1, y1)`` (floats) rounded and cut to the window; None if empty."""
    x0, y0 = max(0, round(rect[0])), max(0, round(rect[1]))
    x1, y1 = min(window[0], round(rect[2])), min(window[1], round(rect[3]))
    return (x0, y0, x1 - x0, y1 - y0) if x1 > x0 and y1 > y0 else None


class Presenter:
    """The present pipelines for one target format, with the table, per-draw uniforms, the HUD
    texture and the marker ring."""

    def __init__(self, target_format: str, exposure: float = 1.0):
        import wgpu

        self.dev = get_device()
        self.format = target_format
        self.srgb = target_format.endswith("-srgb")
        self.pipes, self.layout = _pipelines(target_format)
        self.lut = upload_buffer(tonemap_lut(exposure), wgpu.BufferUsage.STORAGE, "tonemap lut")
        u = wgpu.BufferUsage.UNIFORM | wgpu.BufferUsage.COPY_DST
        self.params = self.dev.create_buffer(size=SLOT * SLOTS, usage=u)
        tb = wgpu.TextureUsage.TEXTURE_BINDING
        self.ring = upload_texture(_ring(), "rgba8unorm", tb, "marker")
        self.white = upload_texture(np.full((1, 1, 4), 255, np.uint8), "rgba8unorm", tb)
        self.hud = None
        self.hud_size = (0, 0)
        self._binds: dict = {}

    def set_hud(self, rgba: np.ndarray | None) -> None:
        """Upload the HUD ``[H, W, 4]`` uint8 (straight alpha), or remove it (None)."""
        import wgpu

        if rgba is None:
            self.hud_size = (0, 0)
            return
        h, w = rgba.shape[:2]
        if self.hud is None or self.hud.size[0] < w or self.hud.size[1] < h:
            size = (max(w, 256), max(h, 256))
            self.hud = self.dev.create_texture(
                size=(*size, 1),
                format="rgba8unorm",
                usage=wgpu.TextureUsage.TEXTURE_BINDING | wgpu.TextureUsage.COPY_DST,
                label="hud",
            )
        self.dev.queue.write_texture(
            {"texture": self.hud},
            np.ascontiguousarray(rgba, np.uint8),
            {"bytes_per_row": w * 4, "rows_per_image": h},
            (w, h, 1),
        )
        self.hud_size = (w, h)

    def _bind(self, tex):
        if id(tex) not in self._binds:
            if len(self._binds) > 32:  # renderers come and go: keep a few
                self._binds.clear()
            entries = PRESENT_BINDINGS.entries(
                {
                    "D": {"buffer": self.params, "offset": 0, "size": DRAW.size},
                    "src": tex.create_view(),
                    "lut": {"buffer": self.lut},
                }
            )
            self._binds[id(tex)] = (
                self.dev.create_bind_group(layout=self.layout, entries=entries),
                tex,  # keeps the texture alive while its id is a key
            )
        return self._binds[id(tex)][0]

    def draws(self, window: tuple[int, int], lay: Layout) -> list[tuple]:
        """``[(entry point, texture, scissor (x, y, w, h), origin, scale, kind, tint)]``."""
        x0, y0, s = fit(window, lay.image)
        h = lay.image[1] * s
        out = []
        one = (1.0, 1.0, 1.0, 1.0)

        def add(entry, tex, rect, origin=None, scale=1.0, kind=0, tint=one):
            """A draw of ``tex`` into ``rect`` cut to the window (none when nothing is left)."""
            rect = _clip(rect, window)
            if rect:
                out.append((entry, tex, rect, origin or (rect[0], rect[1]), scale, kind, tint))

        def panel(tex, a, b, origin_x, entry="fs_panel"):
            add(entry, tex, (x0 + a * s, y0, x0 + b * s, y0 + h), (origin_x, y0), s)

        if lay.split is None:
            for e, tex in enumerate(lay.eyes):
                w = tex.size[0]
                panel(tex, e * w, (e + 1) * w, x0 + e * w * s)
        else:
            panel(lay.eyes[0], 0, lay.split, x0)
            entry = "fs_display" if lay.right_is_display else "fs_panel"
            panel(lay.right, lay.split, lay.image[0], x0, entry)
            if lay.split_line:  # a grey line (kind 1: filled with the tint)
                xs, grey = x0 + lay.split * s, (0.85, 0.85, 0.85, 1.0)
                add("fs_overlay", self.white, (xs, y0, xs + 1, y0 + h), (0, 0), 1.0, 1, grey)
        for k, (mx, my, on) in enumerate(lay.markers[:MAX_MARKERS]):
            c = RING // 2
            tint = (1.0, 0.85, 0.1, 1.0) if k == lay.selected else one if on else (0.45,) * 3 + (1,)
            add("fs_overlay", self.ring, (mx - c, my - c, mx - c + RING, my - c + RING), tint=tint)
        if self.hud_size[0] and self.hud is not None:
            add("fs_overlay", self.hud, (8, 8, 8 + self.hud_size[0], 8 + self.hud_size[1]), (8, 8))
        return out[:SLOTS]

    def encode(self, encoder, target, window: tuple[int, int], lay: Layout, view_format=None):
        """Record the present pass drawing ``lay`` into texture ``target`` (``window`` pixels;
        viewed as ``view_format`` when given)."""
        draws = self.draws(window, lay)
        data = np.zeros((SLOTS, SLOT), np.uint8)
        for i, (_, _, _, origin, scale, kind, tint) in enumerate(draws):
            d = DRAW.view(data[i, : DRAW.size])[0]
            d["origin"], d["scale"], d["kind"], d["tint"] = origin, scale, kind, tint
        self.dev.queue.write_buffer(self.params, 0, data.tobytes())
        view = target.create_view(format=view_format) if view_format else target.create_view()
        rp = encoder.begin_render_pass(
            color_attachments=[
                {"view": view, "load_op": "clear", "store_op": "store", "clear_value": (0, 0, 0, 1)}
            ]
        )
        for i, (entry, tex, rect, *_) in enumerate(draws):
            rp.set_pipeline(self.pipes[entry])
            rp.set_bind_group(0, self._bind(tex), [i * SLOT])
            rp.set_scissor_rect(*rect)
            rp.draw(3)
        rp.end()


def compose(
    eyes_hdr: list[np.ndarray], right=None, split: int | None = None, right_is_display=False
):
    """Numpy twin of the present pass at scale 1 without HUD or markers: ``[H, W, 3]`` uint8
    of the eyes ``[H, W, >=3]`` side by side, or (``split``) eye 0 left of column ``split`` and
    ``right`` (HDR, or display colours in [0, 1] when ``right_is_display``) from there on."""
    if split is None:
        return np.concatenate([tonemap(e) for e in eyes_hdr], axis=1)
    out = tonemap(eyes_hdr[0])
    if right_is_display:
        r = np.clip(np.round(np.asarray(right[..., :3], np.float32) * 255), 0, 255)
        out[:, split:] = r.astype(np.uint8)[:, split:]
    else:
        out[:, split:] = tonemap(right)[:, split:]
    return out
