"""The renderer's resolved settings (profile + scene + options) and their limits; light, so
that configs and the viewer can name them without loading the GPU modules."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

MODES = ("texture", "screen", "reference")
RADIANCE = ("per-eye", "shared")
#: the most frames a renderer lets the GPU queue (Settings.frames_in_flight)
FRAMES_IN_FLIGHT_MAX = 3
#: the most point lights a frame shades (`run --lights`, every bench; the shaders loop over them)
LIGHTS_MAX = 64
#: the longest refresh sweep of adaptive reuse, in frames
ADAPTIVE_PERIOD_MAX = 16
#: how the texture and screen passes filter neural textures: "exact" (taps and weights computed
#: in float32 in the shader, the twin's arithmetic) or "hardware" (the sampler's filtering;
#: runtime/codegen_sample.py); the reference mode always "exact"
NEURAL_FILTERS = ("exact", "hardware")
#: eye colour targets (Settings.target; their formats: vrneural.runtime.forward.TARGETS)
TARGETS = ("hdr", "display")
#: how the forward pass clears the eyes' colour: "compute" (a compute pass, then the render pass
#: loads it), "pass" (the render pass's own clear), "auto" (compute on GPUs, pass on CPU adapters:
#: each the faster where measured, runtime/forward.py: clear_colour)
COLOUR_CLEARS = ("auto", "compute", "pass")
#: how the forward pass resets the eyes' depth: "pass" (the render pass clears it every frame),
#: "slices" (cleared every DEPTH_SLICES frames; in between, each frame's depths go to a nearer
#: slice of the depth range than the last frame's, so that whatever is left there lies behind
#: them: runtime/forward.py: begin_pass), "auto" (slices on discrete GPUs, where a render pass's
#: clear goes through the raster back end; pass elsewhere: a tiler clears for free, and loading
#: depth costs it bandwidth)
DEPTH_CLEARS = ("auto", "pass", "slices")
#: frames one depth clear serves with depth_clear "slices" (each gets 1/DEPTH_SLICES of the
#: depth range: 2 bits of depth32float's precision)
DEPTH_SLICES = 4
#: samples per pixel of the eyes' targets (Settings.msaa; WebGPU's sample counts)
MSAA = (1, 4)
#: the footprint the prefiltered neural textures are looked up at, with resolution from the
#: screen (Settings.lod_footprint): "pixel" (one atlas texel or, where it is larger, the pixel
#: where the object is nearest the eye: the chosen side is a power of two at or above the one
#: giving a texel per pixel, so a texel is up to 2.5x smaller than a pixel, and a radiance
#: texture prefiltered only to its texel aliases once the forward pass minifies it without
#: mips: docs/lod.md), "texel" (one atlas texel, as without resolution from the screen: the
#: radiance mips filter the rest), "auto" (pixel without radiance mips, texel with them)
LOD_FOOTPRINTS = ("auto", "pixel", "texel")
#: the most footprint taps per axis of the texture-space pass (Settings.lod_taps): 8 x 8 = 64
#: network evaluations per texel at most
LOD_TAPS_MAX = 8


@dataclass
class Settings:
    """Resolved run settings (profile + scene + CLI)."""

    eyes: int = 2
    reuse: int = 4
    texture_res: int = 1200
    texture_res_given: bool = False  # --texture-res on the command line: beats objects' own
    eye_res: tuple = (2064, 2208)
    frames: int = 90
    fps: float = 90.0
    fov_y: float = 96.0
    ipd: float = 0.063
    n_lights: int = 3
    mode: str = "texture"
    schedule: str = "staggered"
    precision: str = "f32"  # resolved (f32 | f16)
    reference: object = None  # NeuralMaterial used by every object in reference mode
    #: "per-eye": a radiance texture per object and eye; "shared": one per object, shaded from
    #: the eyes' centre and sampled by both (half the texture-space work)
    radiance: str = "per-eye"
    #: adaptive reuse (``--reuse auto``): refresh an object when its view or light directions
    #: have turned by this many degrees (runtime/adaptive.py); None: every reuse + 1 frames
    reuse_budget: float | None = None
    #: render the window ``(x0, y0)`` of a ``full_w x full_h`` eye image, ``eye_res`` in size
    #: (``(x0, y0, full_w, full_h)``; the bench's crops at the headset's pixel density)
    crop: tuple | None = None
    #: radiance textures with mip chains, rebuilt after each update and sampled trilinearly
    #: (anisotropically where the adapter allows) by the forward pass (runtime/radiance_mips.py)
    mips: bool = False
    #: each object's radiance texture side chosen at each update from its size on screen
    #: (about one texel per pixel; a power of two up to its side above; runtime/screen_res.py)
    screen_res: bool = False
    #: with screen_res, the footprint of the neural-texture lookups (LOD_FOOTPRINTS)
    lod_footprint: str = "auto"
    #: sample the packs' prefiltered neural-texture pyramids at each block's footprint (False:
    #: level 0 everywhere, as packs without pyramids)
    neural_lod: bool = True
    #: footprint taps (texture mode): where an atlas texel's footprint (or, with lod_footprint
    #: "pixel", the pixel's, stretched along the view by 1 / cos where the surface is seen
    #: obliquely) spans n > 1 neural texels, the texture-space pass shades n points along each
    #: axis (rounded, at most lod_taps) and stores their mean, the network's output averaged
    #: over the footprint (an exact prefilter, at the taps' count in evaluations; a pyramid is
    #: then looked up at each tap's share). 1: one point per texel, as before
    lod_taps: int = 1
    #: where the texture-space pass marches a pack's parallax (height field or neural offset):
    #: "auto" (once per 2x2 block where the block spans at most one texel of the march's
    #: grid, else per texel: vrneural.parallax.auto_blocks), "pack" (the march it trained
    #: with), "texel" or "block"
    parallax_march: str = "auto"
    #: frames the GPU may have queued while the host encodes the next (1 = none ahead)
    frames_in_flight: int = 2
    #: eye colour targets: "hdr" (rgba16float radiance: EXR, FLIP) or "display" (8-bit
    #: Reinhard-tonemapped sRGB, texture mode only: where HDR output is not needed)
    target: str = "hdr"
    #: how the forward pass clears the eyes' colour (COLOUR_CLEARS); the frames are the same
    colour_clear: str = "auto"
    #: how the forward pass resets the eyes' depth (DEPTH_CLEARS); the frames are the same but
    #: where two surfaces are closer than the depth's precision
    depth_clear: str = "auto"
    #: samples per pixel of the eyes' colour and depth (MSAA; 4: silhouettes and seams
    #: antialiased by coverage, each pixel still shaded once per triangle; mode texture only)
    msaa: int = 1
    #: neural-texture filtering of the texture and screen passes: "hardware" (the sampler's
    #: bilinear / trilinear filtering: its weights at the adapter's sub-texel precision) or
    #: "exact" (taps and weights in float32 in the shader, the numpy twin's arithmetic)
    neural_filter: str = "hardware"


def shaded_material(mat, s: Settings, cache: dict):
    """The pack ``mat`` (a NeuralMaterial or None) as this render shades it: without its
    pyramids when ``s.neural_lod`` is off, and in texture mode with the march of
    ``s.parallax_march`` (unless ``"pack"``). ``cache``: the renderer's, so each pack is
    adapted once (``id(pack)`` -> the adapted pack)."""
    if mat is None:
        return None
    if id(mat) in cache:
        return cache[id(mat)]
    out = mat
    if not s.neural_lod and mat.lod_levels > 1:
        out = dataclasses.replace(out, levels={})
    march = s.parallax_march
    if s.mode == "texture" and march != "pack" and mat.parallax_kind != "off":
        if march != mat.parallax_march:
            out = dataclasses.replace(out, parallax={**mat.parallax, "march": march})
    cache[id(mat)] = out
    return out
