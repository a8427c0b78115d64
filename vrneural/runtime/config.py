"""``RunConfig``: what `vrneural run` takes (each field's help is its --help line), and its
resolution against a device profile, the scene and the adapter."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from vrneural.atlas.config import MAX_RESOLUTION, MIN_RESOLUTION
from vrneural.config import opt, resolved, unset
from vrneural.errors import VrnError, check_int, check_range, count
from vrneural.runtime.profiles import PROFILES, get_profile
from vrneural.runtime.schedule import SCHEDULES
from vrneural.runtime.settings import (
    COLOUR_CLEARS,
    DEPTH_CLEARS,
    DEPTH_SLICES,
    FRAMES_IN_FLIGHT_MAX,
    LIGHTS_MAX,
    LOD_FOOTPRINTS,
    LOD_TAPS_MAX,
    MODES,
    MSAA,
    NEURAL_FILTERS,
    RADIANCE,
    TARGETS,
    Settings,
)


@dataclass
class RunConfig:
    scene: str | None = opt(None, "scene file (TOML); the built-in scene when omitted", cli=False)
    eyes: int | None = unset(2, "number of eyes (1 or 2)")
    reuse: int | str | None = unset(
        None,
        "N: frames reusing one update (profile default: 4), or 'auto': refresh each object "
        "when its view or light directions have turned by --reuse-budget degrees",
        type=lambda text: int(text) if re.fullmatch(r"\s*[+-]?[0-9]+\s*", text) else text,
    )
    reuse_budget: float | None = unset(
        2.0, "--reuse auto: degrees a view or light direction may turn before a refresh"
    )
    mips: bool | None = unset(
        False,
        "radiance textures with mip chains (coverage-weighted, rebuilt after each update), "
        "sampled trilinearly and anisotropically: far or grazing surfaces average instead of "
        "aliasing",
    )
    screen_res: bool | None = unset(
        False,
        "each object's radiance-texture side from its size on screen (about one texel per "
        "pixel; a power of two up to its own side)",
    )
    lod_footprint: str = opt(
        "auto",
        "with --screen-res, the footprint a pack's prefiltered neural textures are looked up "
        "at: pixel (an atlas texel or, where larger, the pixel where the object is nearest the "
        "eye: the texture is then prefiltered as the screen shows it), texel (an atlas texel, "
        "as without --screen-res: the radiance mips filter the rest) or auto (pixel without "
        "--mips, texel with them)",
        choices=LOD_FOOTPRINTS,
    )
    neural_lod: bool = opt(
        True,
        "sample a pack's prefiltered neural-texture pyramid at each block's footprint "
        "(packs without one: level 0 alone); off: level 0 everywhere",
    )
    lod_taps: int = opt(
        1,
        "footprint taps per axis at most (texture mode): where an atlas texel's footprint "
        "(or, with --lod-footprint pixel, the pixel's, longer along the view where the surface "
        "is seen obliquely) spans n > 1 neural texels, shade n points along each axis and store "
        "their mean: an exact prefilter, at up to N^2 the network's evaluations "
        f"(1 to {LOD_TAPS_MAX}; 1: one per texel)",
    )
    parallax_march: str = opt(
        "auto",
        "where the texture-space pass marches a pack's parallax (height field or neural "
        "offset): auto (once per 2x2 block where a block spans at most one texel of the "
        "material, as at the headset's density; else per texel), pack (the march it trained "
        "with), texel or block",
        choices=("auto", "pack", "texel", "block"),  # vrneural.parallax.RENDER_MARCHES
    )
    neural_filter: str = opt(
        "hardware",
        "how neural textures are filtered: hardware (the sampler's bilinear and trilinear "
        "filtering, its weights at the adapter's sub-texel precision: 8 bits on most GPUs) or "
        "exact (taps and weights in float32 in the shader, as the numpy twin); --mode "
        "reference is always exact",
        choices=NEURAL_FILTERS,
    )
    radiance: str | None = unset(
        "per-eye",
        "radiance textures per object: per-eye, or shared by both eyes (shaded from their "
        "centre: half the texture-space work)",
        choices=RADIANCE,
    )
    frames_in_flight: int = opt(
        2,
        f"frames the GPU may queue while the next is encoded (1-{FRAMES_IN_FLIGHT_MAX}; 1: the "
        "host waits for each frame before encoding the next)",
    )
    target: str = opt(
        "hdr",
        "eye colour targets: hdr (rgba16float radiance: PNG + EXR frames) or display (8-bit "
        "tonemapped sRGB, half the bytes per pixel: PNG frames and video, no EXR; --mode "
        "texture only)",
        choices=TARGETS,
    )
    colour_clear: str = opt(
        "auto",
        "how the forward pass clears the eyes' colour: compute (a compute pass; the render pass "
        "loads it), pass (the render pass's clear), auto (compute on GPUs, pass on CPU "
        "adapters); the same frames",
        choices=COLOUR_CLEARS,
    )
    depth_clear: str = opt(
        "auto",
        f"how the forward pass resets the depth: pass (cleared every frame), slices (cleared "
        f"every {DEPTH_SLICES} frames, each frame in between drawing into a nearer slice of the "
        "depth range), auto (slices on discrete GPUs, pass elsewhere); the same frames but "
        "where surfaces are closer than the depth's precision",
        choices=DEPTH_CLEARS,
    )
    msaa: int = opt(
        1,
        "samples per pixel of the eyes' colour and depth: 4 antialiases silhouettes and seams "
        "by coverage (each pixel still shaded once per triangle, from the radiance texture); "
        "--mode texture only",
        choices=MSAA,
    )
    profile: str | None = opt(None, "device profile: quest3 (default), quest2, preview, tiny")
    texture_res: int | None = opt(
        None, "radiance texture side per eye per object (default: the profile's)"
    )
    eye_res: str | None = opt(None, "pixels per eye, WIDTHxHEIGHT (profile default)")
    frames: int = opt(90, "display frames to render")
    lights: int | None = opt(
        None, "point lights: the first N of the scene (default: the profile's, at most the scene's)"
    )
    mode: str = opt("texture", "texture | screen | reference", choices=MODES)
    schedule: str | None = unset(
        "staggered", "reuse schedule: staggered | burst", choices=SCHEDULES
    )
    precision: str = opt("auto", "auto | f16 | f32", choices=("auto", "f16", "f32"))
    reference: str | None = opt(
        None,
        "teacher pack (.vrnm) for --mode reference, for every neural object "
        "(default: each material's own reference pack)",
    )
    pack: str | None = opt(
        None,
        "runtime pack (.vrnm, from `vrneural distill` or `export`) shown on the built-in "
        "scene's three neural objects instead of the bundled materials (default: none)",
    )
    out: str | None = opt(None, "output directory (default: a new out/run-YYYYmmdd-HHMMSS per run)")
    video: bool = opt(True, "write OUT/stereo.mp4, both eyes side by side (imageio-ffmpeg)")
    video_scale: int | None = unset(
        4,
        "video downscale factor (integer; by default less for eyes under 1024 pixels, so "
        "that each eye keeps 256)",
    )
    save_frames: str = opt(
        "first,last",
        "frames saved as PNG + EXR (PNG alone with --target display): 'first,last', 'all', "
        "'none', '0,45'",
    )
    force: bool = opt(False, "overwrite an existing output directory")


#: the longest update interval N (`run --reuse`, every bench): 1000 frames between updates
REUSE_MAX = 1000


def parse_res(s, field: str = "--eye-res") -> tuple[int, int]:
    """``"2064x2208"`` (or, from Python, ``(2064, 2208)``) -> ``(width, height)``, checked."""
    if isinstance(s, (tuple, list)) and len(s) == 2:
        s = f"{s[0]}x{s[1]}"
    m = re.fullmatch(r"\s*([0-9]+)\s*[xX]\s*([0-9]+)\s*", str(s))  # ASCII digits, no signs
    if m is None:
        raise VrnError(f"{field} = {s!r} must be WIDTHxHEIGHT, e.g. 2064x2208")
    w, h = int(m[1]), int(m[2])
    if not (16 <= w <= 16384 and 16 <= h <= 16384):
        raise VrnError(f"{field} = {s!r} is out of range; each side in [16, 16384]")
    return w, h


def max_texture_res(adapter) -> int:
    """Largest radiance texture side R accepted: the atlas stage's maximum (8192), the
    adapter's 2D texture limit, and its storage-binding limit for the largest per-atlas buffer,
    the geometry atlas's ``vec4`` per 2x2 block (``R * R / 4 * 16`` bytes, like an ``R * R`` u32
    image: 128 MiB on lavapipe -> 5792), rounded down to even."""
    lim = adapter.limits
    ids = math.isqrt(int(lim.get("max_storage_buffer_binding_size", 2**27)) // 4)  # R^2 / 4 * 16
    r = min(int(lim["max_texture_dimension_2d"]), MAX_RESOLUTION, ids)
    return r - r % 2


def resolve(cfg: RunConfig, scene, adapter) -> Settings:
    """Profile < scene < CLI (``--texture-res`` also beats objects' ``texture_res``);
    validates ranges against the adapter (``AdapterSummary``)."""
    from vrneural.runtime.codegen import check_taps, resolve_precision
    from vrneural.runtime.scene import Scene  # tomllib, packs: when a run resolves, not for --help

    if not isinstance(cfg, RunConfig):
        raise VrnError(f"resolve: cfg is a {type(cfg).__name__}, expected a RunConfig")
    if not isinstance(scene, Scene):
        raise VrnError(
            f"resolve: scene is a {type(scene).__name__}, expected a Scene (load_scene(path) "
            "or builtin_scene())"
        )
    if not hasattr(adapter, "limits"):
        raise VrnError("resolve: adapter must be adapter_summary() (vrneural.gpu.device)")
    cfg = resolved(cfg)  # the fields not given: their defaults
    for name, allowed in (
        ("mode", MODES), ("schedule", SCHEDULES), ("neural_filter", NEURAL_FILTERS),
        ("target", TARGETS), ("colour_clear", COLOUR_CLEARS), ("depth_clear", DEPTH_CLEARS),
        ("lod_footprint", LOD_FOOTPRINTS),
    ):  # fmt: skip
        if getattr(cfg, name) not in allowed:
            raise VrnError(
                f"--{name.replace('_', '-')} = {getattr(cfg, name)!r} is not allowed; choose "
                f"{', '.join(allowed)}"
            )
    if cfg.msaa not in MSAA:
        raise VrnError(f"--msaa = {cfg.msaa!r} is not allowed; choose {', '.join(map(str, MSAA))}")
    if cfg.msaa > 1 and cfg.mode != "texture":
        raise VrnError(
            f"--msaa {cfg.msaa} needs --mode texture (--mode {cfg.mode} shades each pixel once "
            "from a single-sample visibility target); drop --msaa or use --mode texture"
        )
    check_taps(cfg.lod_taps)
    if cfg.lod_taps > 1 and cfg.mode != "texture":
        raise VrnError(
            f"--lod-taps {cfg.lod_taps} needs --mode texture (the taps average the texture-space "
            f"pass's texels; --mode {cfg.mode} shades each pixel once); drop --lod-taps or use "
            "--mode texture"
        )
    if cfg.target == "display" and cfg.mode != "texture":
        raise VrnError(
            f"--target display needs --mode texture (--mode {cfg.mode} writes HDR pixels from a "
            "compute pass); drop --target or use --mode texture"
        )
    reuse_given, budget = parse_reuse(cfg.reuse, cfg.reuse_budget)
    for name in ("frames", "eyes", "texture_res", "lights"):
        v = getattr(cfg, name)
        if v is not None:  # None: the profile's
            check_int(f"--{name.replace('_', '-')}", v)
    # run-only fields: `vrneural run` applies them before it calls resolve
    if cfg.scene is not None:
        raise VrnError(
            f"RunConfig.scene = {cfg.scene!r} is the command line's; in Python pass the scene "
            "to resolve (load_scene(path) or builtin_scene())"
        )
    if cfg.pack is not None:
        raise VrnError(
            f"RunConfig.pack = {cfg.pack!r} is the command line's; in Python call "
            "vrneural.runtime.run.use_pack(scene, path) and pass that scene to resolve"
        )
    if cfg.profile is not None and not cfg.profile:  # "" fell through to the scene's
        raise VrnError(f"--profile is empty; choose one of: {', '.join(PROFILES)}")
    prof = get_profile(cfg.profile or scene.profile or "quest3")  # the scene's is checked
    check_range("--eyes", cfg.eyes, 1, 2)
    reuse = prof.reuse if reuse_given is None else reuse_given
    check_range("--reuse", reuse, 0, REUSE_MAX)
    if cfg.radiance not in RADIANCE:
        raise VrnError(f"--radiance = {cfg.radiance!r} is not allowed; choose per-eye or shared")
    if cfg.radiance == "shared" and cfg.eyes != 2:
        raise VrnError(
            f"--radiance shared needs --eyes 2 (one texture for both eyes); --eyes is {cfg.eyes}"
        )
    check_range("--frames", cfg.frames, 1, 1_000_000)
    tex = prof.texture_res if cfg.texture_res is None else cfg.texture_res
    max_tex = adapter.limits["max_texture_dimension_2d"]
    # [8, max_texture_res]: the atlas stage's bounds and the adapter's; odd is rejected below
    check_range("--texture-res", tex, MIN_RESOLUTION, max_texture_res(adapter))
    for i, o in enumerate(scene.objects):
        for key in ("texture_res", "min_texture_res"):
            v = getattr(o, key)
            if v and v > max_texture_res(adapter):
                raise VrnError(
                    f"{scene.src}: objects[{i}].{key} = {v} is above the maximum "
                    f"{max_texture_res(adapter)} (atlas stage and adapter limits)"
                )
    if tex % 2:
        raise VrnError(f"--texture-res = {tex} must be even (2x2 blocks)")
    eye_res = parse_res(cfg.eye_res) if cfg.eye_res else prof.eye_res
    if max(eye_res) > max_tex:
        raise VrnError(f"--eye-res = {eye_res} is above the adapter maximum {max_tex}")
    if cfg.mode == "texture" and cfg.eyes * eye_res[0] > max_tex:  # one target, side by side
        raise VrnError(
            f"--eye-res = {eye_res} with --eyes {cfg.eyes}: mode texture draws the eyes side by "
            f"side in one target {cfg.eyes * eye_res[0]} pixels wide, above the adapter maximum "
            f"{max_tex}; use a width of at most {max_tex // cfg.eyes}"
        )
    if cfg.lights is None:  # the profile's count, capped at what the scene defines
        n_lights = min(prof.lights, len(scene.lights))
    else:
        n_lights = cfg.lights
        check_range("--lights", n_lights, 0, LIGHTS_MAX)  # 0: neural objects render black
        if n_lights > len(scene.lights):
            raise VrnError(
                f"--lights = {n_lights} but the scene has {count(len(scene.lights), 'light')}"
            )
    precision = resolve_precision(
        cfg.precision, adapter.is_cpu, adapter.features.get("shader-f16", False)
    )
    if cfg.mode == "reference":  # the teacher always runs in f32 (it is the ground truth)
        if cfg.precision == "f16":
            raise VrnError(
                "--precision f16 does not apply to --mode reference (the teacher always runs "
                "in f32); drop --precision or use --mode texture|screen"
            )
        precision = "f32"
    ref = None
    if cfg.reference and cfg.mode != "reference":
        raise VrnError(
            f"--reference = {cfg.reference!r} is only used by --mode reference (the mode is "
            f"{cfg.mode!r}); add --mode reference or drop --reference"
        )
    if cfg.reference:
        from pathlib import Path

        from vrneural.formats.vrnm import read_vrnm

        if not Path(cfg.reference).is_file():
            raise VrnError(f"--reference = {cfg.reference!r}: file not found")
        ref = read_vrnm(cfg.reference)
    check_int("--frames-in-flight", cfg.frames_in_flight, 1, FRAMES_IN_FLIGHT_MAX)
    return Settings(
        eyes=cfg.eyes,
        reuse=int(reuse),
        texture_res=int(tex),
        texture_res_given=cfg.texture_res is not None,
        eye_res=tuple(eye_res),
        frames=int(cfg.frames),
        fps=prof.fps,
        fov_y=prof.fov_y,
        ipd=scene.ipd if scene.ipd is not None else prof.ipd,
        n_lights=int(n_lights),
        mode=cfg.mode,
        schedule=cfg.schedule,
        precision=precision,
        reference=ref,
        radiance=cfg.radiance,
        reuse_budget=budget,
        mips=bool(cfg.mips),
        screen_res=bool(cfg.screen_res),
        lod_footprint=cfg.lod_footprint,
        neural_lod=bool(cfg.neural_lod),
        lod_taps=int(cfg.lod_taps),
        parallax_march=cfg.parallax_march,
        frames_in_flight=cfg.frames_in_flight,
        neural_filter=cfg.neural_filter,
        target=cfg.target,
        colour_clear=cfg.colour_clear,
        depth_clear=cfg.depth_clear,
        msaa=cfg.msaa,
    )


def parse_reuse(reuse, budget: float) -> tuple[int | None, float | None]:
    """``--reuse`` (None, a whole number, or ``"auto"``) and ``--reuse-budget`` ->
    ``(N or None for the profile's, the adaptive budget or None)``."""
    if isinstance(reuse, str) and reuse.strip().lower() == "auto":
        if not (isinstance(budget, (int, float)) and 0 < budget <= 180):
            raise VrnError(f"--reuse-budget = {budget!r} is out of range; allowed (0, 180] degrees")
        return None, float(budget)
    if isinstance(reuse, str):
        raise VrnError(
            f"--reuse = {reuse!r} must be a whole number of frames in [0, {REUSE_MAX}], or 'auto'"
        )
    if reuse is not None:
        check_int("--reuse", reuse)
    return reuse, None
