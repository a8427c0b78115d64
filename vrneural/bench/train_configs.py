"""The configs of the benches that train networks (`vrneural bench quality|widths|tradeoff|
distance`), each field's help its --help line: a light module, which the CLI's parser imports
without the benches (each bench module imports its config from here).
"""

from __future__ import annotations

from typing import ClassVar

from vrneural.bench.parts import QUICK_BUDGET, QUICK_SCORED, PackBudget, Scored, bench_config
from vrneural.btf.config import PRESET_NAMES
from vrneural.config import QuickConfig, choices, floats, ints, listed, opt, part, unset, words
from vrneural.distill.config import COMPILE_MODES, StudentShape, TrainBudget
from vrneural.runtime.config import REUSE_MAX

#: ``bench quality --parallax``: which variants it adds
BENCH_PARALLAX = ("off", "height", "neural", "both")


@bench_config(
    "quality",
    "CI-sized run: 16^2 texels, 8 directions, 2 epochs, 5 LM steps",
    force="use an existing --out: retrain every network and rewrite the reports (other files "
    "in it are kept)",
    resume="reuse the checkpoints in OUT that match this run (same config, BTF and teacher): "
    "finished ones as they are, interrupted or shorter ones continued; train the rest",
)
class QualityConfig(QuickConfig, TrainBudget, StudentShape):
    """`vrneural bench quality`: the training fields it shares with `distill` (seed, --ema,
    --lr-patience, --device, --compile, --neumip-dirs, --width, --wide-start) apply to every
    network but the teacher, as `distill` takes them."""

    presets: tuple[str, ...] | None = unset(
        ("leather", "fabric", "wood"),
        "comma-separated synthetic BTF presets (none by default when --btf is given)",
        items=words,
    )
    btf: tuple[str, ...] = opt(
        (),
        "comma-separated .btf files to bench beside --presets, each labelled by its file name "
        "(--res and --dirs apply to the presets only)",
        items=listed(empty=False),
    )
    out: str = opt("bench-quality", "output directory", cli=False)
    res: int | None = unset(32, "BTF texels per side")
    dirs: int | None = unset(30, "light and view directions (dirs^2 slices)")
    teacher_epochs: int | None = unset(12, "teacher epochs")
    epochs: int | None = unset(12, "epochs of every student and baseline network")
    lafortune_iters: int | None = unset(30, "Levenberg-Marquardt iterations of the Lafortune fit")
    repeats: int = opt(
        1, "train every network but the teacher with this many seeds (seed, seed+1, ...)"
    )
    parallax: str = opt(
        "off",
        "height: also train the height-field parallax variants (a teacher, the distilled "
        "student and NeuMIP, each with --parallax height) beside the others, which train "
        "without parallax; neural: the neural-offset variants (NeuMIP with offset, the paper's "
        "full model, and a teacher and student with the module); both: all of them (see "
        "docs/parallax.md)",
        choices=BENCH_PARALLAX,
    )
    jobs: int = opt(
        1,
        "train this many networks at once, each in its own process (teachers first, then "
        "every network and seed of every preset; with --device cuda see docs/training.md on MPS)",
    )

    def resolved(self) -> QualityConfig:
        """The fields not given: ``--quick``'s (``QUICK``) or the defaults; no
        presets by default when ``--btf`` names files."""
        return super().resolved({"presets": ()} if self.btf else {})


QualityConfig.QUICK = QualityConfig(res=16, dirs=8, teacher_epochs=2, epochs=2, lafortune_iters=5)


METHODS = {
    "student": (dict(method="student"), "student (coarse-to-fine, distilled)"),
    "student_nodistill": (
        dict(method="student", distill=False),
        "student w/o distillation",
    ),
    "single8": (dict(method="single8"), "single-level (distilled)"),
}


STARTS = {"plain": "from random weights", "wide": "wide start (2W, pruned to W)"}


@bench_config(
    "widths",
    "CI-sized run: 16^2 texels, 8 directions, 2 epochs, widths 4,8, 1 seed (options "
    "given explicitly win)",
    force="use an existing --out: retrain every network, rewrite the reports",
    resume="reuse the checkpoints in OUT that match this run (same settings, BTF and teacher): "
    "finished ones as they are, interrupted ones continued; train the rest",
)
class WidthsConfig(QuickConfig):
    """`vrneural bench widths`."""

    preset: str = opt(
        "leather", "synthetic BTF preset: " + ", ".join(PRESET_NAMES) + " (btf synth)"
    )
    out: str = opt("bench-widths", "output directory", cli=False)
    res: int | None = unset(32, "BTF texels per side")
    dirs: int | None = unset(16, "light and view directions (dirs^2 slices)")
    teacher_epochs: int | None = unset(24, "teacher epochs")
    epochs: int | None = unset(
        24, "epochs of every other network (a wide start takes half of them)"
    )
    widths: tuple[int, ...] | None = unset(
        (4, 8, 12, 16),
        "comma-separated hidden widths W, each in [1, 64] (at most 32 with wide)",
        items=ints(1, 64),
    )
    methods: tuple[str, ...] = opt(
        ("student",),
        "comma-separated networks trained at every width: student (coarse-to-fine, "
        "distilled), student_nodistill (on ground truth alone), single8 (the single-level "
        "4-layer net, W wide; distill --method single8 --width W); NeuMIP (4 x 25) is always "
        "trained as the reference",
        items=choices(list(METHODS)),
    )
    starts: tuple[str, ...] = opt(
        ("plain", "wide"),
        "comma-separated: plain (from random weights), wide (2W wide for epochs // 2, then "
        "pruned to W for the rest: distill --wide-start 2W)",
        items=choices(list(STARTS)),
    )
    seed: int = opt(0, "seed of synthesis, initialisation and data order")
    repeats: int | None = unset(3, "seeds of every network but the teacher (seed, seed+1, ...)")
    device: str = opt("cpu", "train on cpu, cuda or cuda:N (teach/distill --device)")
    compile: str = opt(
        "off", "torch.compile the networks (teach/distill --compile)", choices=COMPILE_MODES
    )
    jobs: int = opt(1, "train this many networks at once, each in its own process")


WidthsConfig.QUICK = WidthsConfig(
    res=16, dirs=8, teacher_epochs=2, epochs=2, widths=(4, 8), repeats=1
)


@bench_config(
    "tradeoff",
    "CI-sized: 48-pixel crops, 2 spp, 3 frames, rest and one 300 deg/s turn, no light, "
    "distance or tiling sweep, textures 128,256 (base 256), N 0,4, one tiny-trained preset",
)
class TradeoffConfig(QuickConfig):
    """`vrneural bench tradeoff`."""

    score: Scored = part(Scored)
    speeds: tuple[float, ...] | None = unset(
        (0, 100, 200, 300, 400),
        "head-turn speeds (deg/s) of the built-in logs",
        items=floats(0.0, 2000.0),
    )
    turn: float = opt(30.0, "yaw of each built-in head turn, degrees")
    near: float = opt(0.5, "distance (m) of the sphere in the head-turn conditions (arm's length)")
    poses: tuple[str, ...] = opt(
        (), "more pose logs (CSV: t,x,y,z,qx,qy,qz,qw) scored as conditions", items=listed()
    )
    light_speed: float | None = unset(
        120.0, "the moving light's speed about the sphere, deg/s (0: none)"
    )
    distances: tuple[float, ...] | None = unset(
        (),
        "sphere distances (m) of a distance sweep (default none: `bench distance` has it)",
        items=floats(0.2, 100.0),
    )
    tilings: tuple[float, ...] | None = unset(
        (),
        "material tilings of a tiling sweep (default none: `bench distance`)",
        items=floats(0.01, 1000.0),
    )
    texture_res: tuple[int, ...] | None = unset(
        (256, 512, 1024), "texture sides compared", items=ints()
    )
    base_res: int | None = unset(
        512, "texture side of the base setting (the sphere is ~105 px across)"
    )
    reuse: tuple[int, ...] | None = unset(
        (0, 2, 4, 8), "update intervals N compared", items=ints(0, REUSE_MAX)
    )
    base_reuse: int = opt(4, "N of the base setting")
    lights: int = opt(2, "point lights (the key light moves in the moving-light condition)")
    presets: tuple[str, ...] | None = unset(
        ("leather", "metal"),
        "synthetic BTF presets of the trained packs: the first for every condition, the others "
        "(glossy metal: staleness and eye disparity show on highlights) for the base and the "
        "fastest turn",
        items=listed(empty=False),
    )
    budget: PackBudget = part(PackBudget)
    packs: str | None = opt(
        None,
        "directory with teacher/student/student_nodistill/single8/neumip.vrnm (skips training; "
        "each must be what its name says, all from one BTF and its teacher); replaces --presets",
    )


TradeoffConfig.QUICK = TradeoffConfig(
    score=QUICK_SCORED,
    speeds=(0, 300),
    light_speed=0.0,
    distances=(),
    tilings=(),
    texture_res=(128, 256),
    base_res=256,
    reuse=(0, 4),
    presets=("leather",),
    budget=QUICK_BUDGET,
)


@bench_config(
    "distance",
    "CI-sized: distances 1,10, tiling 8, 48-pixel crops, 2 spp, 3 frames, texture 256, tiny "
    "training",
)
class DistanceConfig(QuickConfig):
    """`vrneural bench distance`."""

    distances: tuple[float, ...] | None = unset(
        (0.3, 1, 3, 10, 20), "sphere distances (m)", items=floats(0.2, 100.0)
    )
    tilings: tuple[float, ...] | None = unset(
        (1, 4, 8, 16), "material tilings, at 1 m", items=floats(0.01, 1000.0)
    )
    size: float = opt(0.5, "sphere diameter (m)")
    texel_mm: float = opt(
        1.0,
        "size (mm) of one material texel on the sphere at tiling 1 (about a quest3 pixel at "
        "1 m, so that 10 m and tiling 8 minify the material; 7.8 for a 32^2 BTF is one tile "
        "per sphere radian, this bench's scale before 2026-12-04)",
    )
    texture_res: int | None = unset(
        1200, "radiance texture side (the cap screen-res chooses under)"
    )
    reuse: int = opt(4, "N (staggered)")
    variants: tuple[str, ...] = opt(
        (),
        "the variants rendered, by key (comma-separated; default all): all-off, mips, "
        "screen-res, neural-lod, neural-lod+trained, all-on, screen-res+neural-lod, 4x-msaa, "
        "all-on+4x-msaa, screen-res+neural-lod+4x-msaa, taps, screen-res+taps+4x-msaa, "
        "screen-res+neural-lod+taps+4x-msaa",
        items=listed(),
    )
    taps: int = opt(
        4,
        "footprint taps per axis at most of the variants with taps (run --lod-taps): up to "
        "taps^2 network evaluations per texel",
    )
    score: Scored = part(Scored)
    preset: str = opt("leather", "synthetic BTF preset of the trained packs")
    budget: PackBudget = part(PackBudget)

    #: packs trained 24 epochs, not the shared 4: with 4, the LOD pack's level 0 is noisier
    #: than the plain student's and flickers more at 0.3 m (docs/lod.md); 24 cost a minute.
    #: A reference of 64 samples per pixel, not 16: where the material is minified (7 texels
    #: per pixel at 10 m) 16 samples alias, and the reference's own frame-to-frame change,
    #: which flicker is judged against, is then mostly its sampling noise (docs/lod.md).
    #: BTFs of 24 x 24 directions, not 10 x 10: with 10 the student's own error against the
    #: teacher (supersampled) is 3x larger at 10 m and swamps the filtering it is to judge
    DEFAULTS: ClassVar[dict] = {"teacher_epochs": 24, "epochs": 24, "spp": 64, "btf_dirs": 24}


#: ``--quick``: the CI-sized run, under the flags given
DistanceConfig.QUICK = DistanceConfig(
    distances=(1, 10),
    tilings=(8,),
    score=QUICK_SCORED,
    texture_res=256,
    budget=QUICK_BUDGET,
)
