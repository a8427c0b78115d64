"""The timing benches' configs (`vrneural bench frames|lights|materials|frame|kernels|atlas|runtime|
extremes`), each field's help its --help line: a light module, which the CLI's parser imports
without the benches (each bench module imports its config from here).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

from vrneural.bench.parts import QUICK_LOOP, Loop, bench_config
from vrneural.config import Config, QuickConfig, choices, ints, opt, part, unset, words
from vrneural.errors import VrnError
from vrneural.runtime.config import LIGHTS_MAX, REUSE_MAX
from vrneural.runtime.schedule import SCHEDULES

#: the meshes of `bench atlas` (built by :mod:`vrneural.bench.atlas_meshes`)
NAMES = ("ico6", "ico7", "torus", "knot", "cloth", "fan", "field", "lightmap")


@bench_config("frames", "CI-sized: textures 128,256; N 0,2,4; eyes 258x276; >= 2 frames")
class FramesConfig(QuickConfig):
    """`vrneural bench frames`."""

    texture_res: tuple[int, ...] | None = unset(
        (800, 1200, 1600, 2000), "radiance texture sides (comma-separated)", items=ints()
    )
    reuse: tuple[int, ...] | None = unset(
        (0, 1, 2, 4, 6), "update intervals N (comma-separated)", items=ints(0, REUSE_MAX)
    )
    schedules: tuple[str, ...] = opt(
        ("burst", "staggered"), "reuse schedules (comma-separated)", items=choices(SCHEDULES)
    )
    loop: Loop = part(Loop)
    lights: int = opt(1, "point lights")
    min_frames: int | None = unset(3, "at least this many measured frames per configuration")
    screen: bool = opt(True, "also measure per-pixel screen-space shading")


FramesConfig.QUICK = FramesConfig(
    texture_res=(128, 256), reuse=(0, 2, 4), loop=QUICK_LOOP, min_frames=2
)


@bench_config("lights", "CI-sized: lights 1,2,4; texture 256; eyes 258x276")
class LightsConfig(QuickConfig):
    """`vrneural bench lights`."""

    lights: tuple[int, ...] | None = unset(
        tuple(range(1, 9)), "light counts (comma-separated, 1..64)", items=ints(1, LIGHTS_MAX)
    )
    texture_res: int | None = unset(1200, "radiance texture side")
    reuse: int = opt(4, "update interval N")
    schedule: str = opt("staggered", "reuse schedule", choices=("burst", "staggered"))
    loop: Loop = part(Loop)


LightsConfig.QUICK = LightsConfig(lights=(1, 2, 4), texture_res=256, loop=QUICK_LOOP)


@bench_config("materials", "CI-sized: materials 1,2,3; texture 256; eyes 258x276")
class MaterialsConfig(QuickConfig):
    """`vrneural bench materials`."""

    materials: tuple[int, ...] | None = unset(
        (1, 2, 3, 4), "material counts (comma-separated, 1..8)", items=ints(1, 8)
    )
    texture_res: int | None = unset(1024, "radiance texture side per material")
    reuse: int = opt(7, "update interval N")
    schedule: str = opt("staggered", "reuse schedule", choices=("burst", "staggered"))
    lights: int = opt(3, "point lights")
    loop: Loop = part(Loop)


MaterialsConfig.QUICK = MaterialsConfig(materials=(1, 2, 3), texture_res=256, loop=QUICK_LOOP)


@bench_config("frame", "CI-sized: texture 128, eyes 96x96, 6 frames, 2 rounds")
class FrameConfig(QuickConfig):
    """`vrneural bench frame`."""

    texture_res: int | None = unset(1200, "radiance texture side")
    reuse: int = opt(4, "update interval N (staggered)")
    eye_res: str | None = unset("2064x2208", "pixels per eye, WIDTHxHEIGHT (quest3)")
    lights: int = opt(1, "point lights")
    frames: int | None = unset(20, "frames per loop measurement (after one cycle of warm-up)")
    repeats: int | None = unset(3, "passes timed alone per round (the median is kept)")
    rounds: int | None = unset(3, "interleaved rounds (the median over rounds is reported)")
    parallax_steps: int = opt(
        0,
        "also time the texture-space update of the same materials with height-field parallax "
        "of this many march steps, 1 to 64 (0 = off; see docs/parallax.md)",
    )
    neural_offset: bool = opt(
        False,
        "also time the texture-space update of the same materials with NeuMIP's neural offset "
        "(the student's module: 4 channels, 6 -> 8 -> 8 -> 1), per texel and per 2x2 block",
    )


FrameConfig.QUICK = FrameConfig(texture_res=128, eye_res="96x96", frames=6, repeats=2, rounds=2)


#: ``*_offset``: the network with NeuMIP's neural offset module of its size (issue #44), its
#: offset MLP per texel (``--parallax neural``, march per texel) beside the material's
NETWORKS = ("student", "single8", "neumip", "student_offset", "neumip_offset")


#: the networks ``--networks`` also takes at another width, ``NAME:W`` (distill --width W)
WIDENED = ("student", "single8")


def network_width(name: str) -> tuple[str, int] | None:
    """``(method, width)`` of ``student``/``single8`` (8 wide, the paper's) or ``student:W``/
    ``single8:W`` (``--networks``; W in [1, 64], as `distill --width`); None for another
    name. Raises a one-line error for such a name whose width is not such an integer."""
    method, sep, w = name.partition(":")
    if method not in WIDENED:
        return None
    if not sep:
        return method, 8
    if not (w.isdigit() and 1 <= int(w) <= 64):
        raise VrnError(
            f"--networks: {name!r}: {method}:W needs a width W in [1, 64] (distill --width)"
        )
    return method, int(w)


def network_names(flag: str, value) -> tuple[str, ...]:
    """``--networks``: each one of :data:`NETWORKS`, ``student:W`` or ``single8:W``, none
    twice."""
    # network_width: a pair for student(:W) and single8(:W), None otherwise, an error for a bad W
    patterns = tuple(f"{m}:W" for m in WIDENED)
    vals = choices((*NETWORKS, *patterns), network_width)(flag, value)
    seen: dict = {}
    for v in vals:  # student and student:8 are one network: measured and reported twice
        key = network_width(v) or v
        if key in seen:
            raise VrnError(f"{flag} names {seen[key]} and {v}, the same network")
        seen[key] = v
    return vals


@bench_config("kernels", "CI-sized: student and NeuMIP, 16384 texels, 2 repeats, sgemm 256")
class KernelsConfig(QuickConfig):
    """`vrneural bench kernels`."""

    texels: int | None = unset(
        1 << 18, "texels per evaluation (the student's coarse net runs on 1/4)"
    )
    repeats: int | None = unset(3, "timed repeats (median)")
    networks: tuple[str, ...] | None = unset(
        ("student", "single8", "neumip"),
        "networks (comma-separated): student, single8, neumip, or student:W / single8:W (W "
        "wide, as distill --width W)",
        items=network_names,
    )
    precisions: tuple[str, ...] = opt(
        ("f32", "f16"), "GPU precisions (f16 needs shader-f16)", items=choices(("f32", "f16"))
    )
    sgemm_n: int | None = unset(1024, "matrix side of the numpy sgemm roofline")
    threads: int = opt(
        0,
        "CPU threads of PyTorch and of numpy's sgemm (0: their default, every core; 1 avoids "
        "the oversubscription that makes both many times slower on a loaded machine)",
    )


KernelsConfig.QUICK = KernelsConfig(
    texels=16384, repeats=2, sgemm_n=256, networks=("student", "neumip")
)


def mesh_names(flag: str, value) -> tuple[str, ...]:
    """``--meshes``: at least one, each one of :data:`NAMES`."""
    names = words(flag, value)
    bad = [n for n in names if n not in NAMES]
    if bad or not names:
        raise VrnError(f"{flag}: {', '.join(bad) or '(none)'} not in {', '.join(NAMES)}")
    return names


@bench_config("atlas", "CI-sized: each mesh a few thousand triangles, 128-256^2, 128 px")
class AtlasBenchConfig(QuickConfig):
    """`vrneural bench atlas`."""

    meshes: tuple[str, ...] = opt(NAMES, "meshes to run (comma-separated)", items=mesh_names)
    seams: bool = opt(True, "render each atlas (Lambertian, texture vs screen) for the seam error")
    eye: int | None = unset(384, "seam renders: image side in pixels")


AtlasBenchConfig.QUICK = AtlasBenchConfig(eye=128)


#: Each measurement with its quick (smoke-run) arguments; the full run uses the defaults.
MEASUREMENTS = {
    "texture_vs_screen": {"texture_res": 256, "eye_res": (400, 440), "frames": 2},
    "constants_vs_buffer": {"res": 128, "repeats": 2},
    "vs_torch": {"res": 128, "repeats": 2},
    "mlp_only": {"n_blocks": 4096, "repeats": 2},
    "schedules": {"texture_res": 64, "eye_res": (96, 96), "frames": 16, "quality_frames": 12},
}


def selected(flag: str, value) -> tuple[str, ...]:
    """The measurements ``--only`` names, in its order (one-line VrnError if one is unknown)."""
    names = words(flag, value)
    if not names:
        raise VrnError(f"{flag} is empty; choose from {', '.join(MEASUREMENTS)}")
    for k in names:
        if k not in MEASUREMENTS:
            raise VrnError(
                f"{flag}: unknown measurement {k!r}; choose from {', '.join(MEASUREMENTS)}"
            )
    return names


@dataclass
class RuntimeConfig(Config):
    """`vrneural bench runtime`."""

    only: tuple[str, ...] = opt(
        tuple(MEASUREMENTS),
        f"comma-separated subset of: {', '.join(MEASUREMENTS)}",
        items=selected,
    )
    quick: bool = opt(False, "small sizes (a smoke run)")
    force: bool = opt(False, "overwrite an existing --out directory")
    progress: bool = opt(True, "show a progress bar (--no-progress: none)")


W, R = "works", "rejected"


class Case(NamedTuple):
    name: str
    group: str
    function: str  #: its function in ``tests/extremes/*.py``
    expect: str  #: ``works`` or ``rejected``
    checks: str  #: what it checks (the report's column)


def _group(group: str, rows: list[tuple]) -> list[Case]:
    """The cases of ``group``: rows of (name, function, expect, checks)."""
    return [Case(name, group, fn, expect, checks) for name, fn, expect, checks in rows]


CASES = [
    *_group("directions", [
        ("grazing_89.99deg", "case_dir_grazing", W, "finite, >= 0, Lipschitz-continuous"),
        ("normal_and_wi=-wo", "case_dir_normal_and_opposite", W, "h fallback (0,0,1)"),
        ("horizon_twin", "case_dir_horizon", W, "tapers to 0, no jump; 0 below"),
        ("horizon_gpu", "case_dir_horizon_gpu", W, "same on the GPU, f32 + f16"),
        ("grazing_gpu", "case_dir_grazing_gpu", W, "GPU vs twin at 89.99 deg"),
        ("terminator", "case_dir_terminator", W, "step <= 1% of peak, 3 modes"),
        ("unnormalized_frames", "case_dir_unnormalized", W, "scaled frames = unit"),
    ]),
    *_group("precision", [
        ("f16_vs_f32", "case_prec_f16_vs_f32", W, "max / p99.9 relative error"),
        ("clamp_1e6_at_1e-4m", "case_prec_clamp", W, "clamped to 65504, finite"),
        ("no_flush_to_zero", "case_prec_no_flush", W, "values >= 2^-14 kept"),
        ("wide_rgba32float", "case_prec_wide_storage", W, "option: cost + error"),
        ("intensity_above_1e6", "case_intensity_limit", R, "scene loader limit"),
    ]),
    *_group("geometry", [
        ("zero_area_3d", "case_geo_zero_area_3d", W, "skipped with a warning"),
        ("zero_area_uv", "case_geo_zero_area_uv", W, "fallback tangent frame"),
        ("slivers_1e-5", "case_geo_sliver", W, "atlas + kernel finite"),
        ("one_triangle", "case_geo_one_triangle", W, "atlas + kernel"),
        ("non_manifold", "case_geo_non_manifold", W, "fin + bow-tie"),
        ("nan_vertex", "case_geo_nan_vertex", R, "make_mesh"),
        ("inf_vertex_obj", "case_geo_inf_vertex_file", R, "load_mesh"),
        ("far_1e5m", "case_geo_far_origin", W, "camera-relative = at origin"),
        ("many_triangles", "case_geo_many_triangles", W, "1M (quick: 20k)"),
        ("far_1e5m_render", "case_set_far_origin_render", W, "image = at origin"),
    ]),
    *_group("settings", [
        ("tex_res_2_kernel", "case_set_kernel_res_2", W, "kernel alone, one block"),
        ("tex_res_2_run", "case_set_tex_res_2", R, "atlas needs R >= 8"),
        ("tex_res_odd", "case_set_tex_res_odd", R, "2x2 blocks"),
        ("tex_res_max", "case_set_tex_res_max", W, "largest accepted (quick: 1024)"),
        ("tex_res_above_max", "case_set_tex_res_above_max", R, "adapter max + 2"),
        ("reuse_N=0", "case_set_reuse_0", W, "update every frame"),
        ("reuse_N=1000", "case_set_reuse_1000", W, "staggered 1/1001"),
        ("lights_0", "case_set_lights_0", W, "black, no MLP work"),
        ("lights_16", "case_set_lights_16", W, "16 lights"),
        ("1_eye_1_frame", "case_set_one_eye_one_frame", W, "minimal run"),
    ]),
    *_group("training", [
        ("btf_all_zeros", "case_train_zeros", W, "finite, loss falls"),
        ("btf_hdr_1e4", "case_train_hdr", W, "finite (linear + log space)"),
        ("btf_nan", "case_train_nan", R, "one-line error"),
        ("lr_floor", "case_train_lr_floor", W, "reaches and keeps lr_min"),
        ("1_epoch", "case_train_one_epoch", W, "one epoch"),
    ]),
]  # fmt: skip


def case_names(flag: str, value) -> tuple[str, ...]:
    """``--only``: case names or groups of :data:`CASES`, at least one (one-line VrnError)."""
    text = value if isinstance(value, str) else ",".join(map(str, value))
    items = tuple(t.strip() for t in text.split(","))
    groups = ", ".join(sorted({c[1] for c in CASES}))
    if not all(items):
        what = "is empty" if not any(items) else f"= {text!r} has an empty item"
        raise VrnError(f"{flag} {what}; name cases or groups ({groups}), or leave it out")
    bad = sorted(set(items) - {c[0] for c in CASES} - {c[1] for c in CASES})
    if bad:
        raise VrnError(
            f"{flag} = {text!r}: unknown case or group {bad[0]!r}; groups: {groups}; "
            f"cases: {', '.join(c[0] for c in CASES)}"
        )
    return items


@dataclass
class ExtremesConfig(Config):
    """``vrneural bench extremes`` settings."""

    quick: bool = opt(
        False, "small sizes for the heavy cases (1M triangles -> 20k, max texture -> 1024)"
    )
    only: tuple[str, ...] | None = opt(
        None,
        "comma-separated case names or groups to run: "
        f"{', '.join(sorted({c[1] for c in CASES}))} (default: all)",
        items=case_names,
    )
    force: bool = opt(False, "overwrite an existing --out directory")
    progress: bool = opt(True, "show a progress bar (--no-progress: none)")
