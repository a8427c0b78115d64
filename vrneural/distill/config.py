"""Stage configs for training (``vrneural teach``) and distillation (``vrneural distill``).

One field, one ``--flag``; the resolved config is stored in every checkpoint and written as
JSON beside every output. Model-size fields are explained in docs/training.md.
"""

from __future__ import annotations

from dataclasses import dataclass

from vrneural.config import opt, unset
from vrneural.errors import VrnError

SPACES = ("linear", "log")
METHODS = ("student", "single8", "neumip")
LOD_KINDS = ("filter", "levels")
COMPILE_MODES = ("off", "default", "reduce-overhead")
NEUMIP_DIRS = ("xy", "full")
PARALLAX = ("auto", "height", "neural", "off")  # vrneural.parallax.PARALLAX_CHOICES
# What a checkpoint written before a field existed used for it, where that differs from the
# field's default (resuming or reusing such a checkpoint must train what it trained).
BEFORE_FIELD = {
    "neumip_dirs": "full",  # NeuMIP read wi, wo and h before the option existed
    "parallax": "off",  # no parallax before issue #44
    "offset_weight": 0.0,  # no depth distillation before it existed
}

# What a --resume takes from the command line; every other field comes from the checkpoint.
RESUME_FREE = ("epochs", "output", "resume", "progress", "device", "compile", "threads")


@dataclass
class TrainBudget:
    """What a training run is given besides its data and length, shared by `teach`, `distill`
    and `bench quality` (which gives it to every network it trains but the teacher)."""

    seed: int | None = unset(0, "seed of initialisation, data order and texture-lookup jitter")
    ema: float | None = unset(
        0.0,
        "decay of an exponential moving average of the weights, evaluated and exported "
        "instead of the last step (0 = off; see docs/training.md)",
    )
    lr_patience: int | None = unset(2, "epochs without enough improvement before halving")
    device: str | None = unset(
        "cpu",
        "train on cpu, cuda or cuda:N (CUDA: same result to float tolerance, not bit-exact; "
        "see docs/training.md)",
    )
    compile: str | None = unset(
        "off",
        "torch.compile the networks: off, default, or reduce-overhead (adds CUDA graphs); "
        "fewer kernel launches per step, paid for with a compile at the start (see "
        "docs/training.md)",
        choices=COMPILE_MODES,
    )


@dataclass
class StudentShape:
    """The small networks' shape, shared by `distill` and `bench quality`."""

    neumip_dirs: str | None = unset(
        "xy",
        "NeuMIP's direction inputs: xy (wi.xy, wo.xy, as NeuMIP has them) or full (wi, wo, h "
        "like the student; a stronger baseline than the paper's, see docs/training.md)",
        choices=NEUMIP_DIRS,
    )
    width: int | None = unset(
        8,
        "hidden width of the student's M_c and M_f, and of single8 (NeuMIP is always 25); the "
        "paper's 8, or 12 with --wide-start 24 to come within a tenth of NeuMIP's L1 on our "
        "presets (see docs/quality.md)",
    )
    wide_start: int | None = unset(
        0,
        "train this wide for --epochs // 2 epochs (into <output>.wide.pt), then prune to "
        "--width and train on for the rest: --width and --init-from in one run; --resume of "
        "the output continues either half (0 = off, from random weights as the paper; 16 "
        "for the 8-wide student on hard data: its L1 0.95-0.98x on the path-traced presets; "
        "see docs/training.md)",
    )


@dataclass
class TrainConfig(TrainBudget):
    """Fields shared by every trainer (optimizer, schedule, data split, workflow)."""

    epochs: int | None = unset(
        20, "training epochs (one epoch = every training (wi, wo) slice once)"
    )
    lr: float | None = unset(5e-4, "initial Adam learning rate")
    lr_min: float | None = unset(1e-7, "ReduceLROnPlateau floor")
    lr_factor: float | None = unset(0.5, "ReduceLROnPlateau decay factor")
    lr_threshold: float | None = unset(
        5e-3, "halve lr when the test L1 improves by less than this (see docs/training.md)"
    )
    lr_threshold_mode: str | None = unset(
        "rel",
        "threshold mode: rel (fraction of the best L1) or abs (L1 units)",
        choices=("abs", "rel"),
    )
    tex_lr_scale: float | None = unset(10.0, "learning-rate multiplier for neural textures")
    test_fraction: float | None = unset(
        0.1, "held-out fraction of (wi, wo) pairs (distill: teacher's)"
    )
    split_seed: int | None = unset(
        0, "seed of the train/test split (distill reuses the teacher's split)"
    )
    max_test_slices: int | None = unset(64, "test slices used for the per-epoch test L1 (0 = all)")
    jitter: bool | None = unset(
        True, "stratified (jittered within the texel) neural-texture lookups"
    )
    space: str | None = unset(
        "linear", "output and loss space: linear, or log (log(1+y))", choices=SPACES
    )
    threads: int | None = unset(
        1, "torch CPU threads (1 was 15-70x faster than 2 on the shared 2-core box)"
    )
    parallax: str | None = unset(
        "auto",
        "move the neural textures' lookup along the view ray: auto (height where the BTF's "
        "height field has a texel of relief; without one neural where its views show 2 "
        "texels; else off), height (where the ray meets the "
        "height field), neural (NeuMIP's learned offset module, no height field needed) "
        "or off (see docs/parallax.md)",
        choices=PARALLAX,
    )
    parallax_steps: int | None = unset(
        16, "march steps of height-field parallax at the data's steepest view (fewer below), 1-64"
    )
    parallax_march: str | None = unset(
        "texel",
        "march per texel, or once per 2x2 block (a quarter of the height lookups; with "
        "--parallax neural: the offset module once per block)",
        choices=("texel", "block"),
    )
    progress: bool = opt(True, "show a tqdm progress bar")
    force: bool = opt(False, "overwrite existing outputs")
    resume: bool = opt(False, "continue the checkpoint at -o (exactly reproduces a straight run)")


@dataclass
class TeachConfig(TrainConfig):
    """``vrneural teach``: the 128-wide teacher ("NeuMIP Max"), arch ``single``."""

    btf: str = opt("", "input BTF file", cli=False)
    output: str = opt("teacher.pt", "output checkpoint", cli=False)
    width: int | None = unset(128, "hidden width of the teacher MLP")
    layers: int | None = unset(4, "linear layers of the teacher MLP (layers - 1 hidden)")
    channels: int | None = unset(8, "neural-texture channels (full BTF resolution)")
    export: bool | None = unset(
        True, "also write the .vrnm beside the checkpoint (t.pt -> t.vrnm; the per-pixel reference)"
    )


@dataclass
class DistillConfig(TrainConfig, StudentShape):
    """``vrneural distill``: a small model trained from a teacher (and the ground truth)."""

    teacher: str = opt("", "teacher checkpoint (from vrneural teach)", cli=False)
    output: str = opt("student.pt", "output checkpoint", cli=False)
    btf: str = opt("", "BTF file (default: the path recorded in the teacher)")
    method: str | None = unset(
        "student", "student (coarse_fine), single8 or neumip", choices=METHODS
    )
    distill: bool | None = unset(True, "use the teacher (Eq. 5); --no-distill: ground truth only")
    sigma: float | None = unset(0.1, "weight of L1(y_s, y_t)")
    lambda1: float | None = unset(0.1, "weight of L2(z_s1, T1 z_t1)")
    lambda2: float | None = unset(0.1, "weight of L2(z_s2, T2 z_t2)")
    init_from: str | None = unset(
        "",
        "start from this run of the same method and teacher (trained at this --width or wider), "
        "its hidden units pruned to --width; see docs/training.md",
    )
    # recorded in both halves of a --wide-start run (the wide one has no init_from): what the
    # whole run was started with, so that --resume of either half continues that run
    wide_start_epochs: int = opt(0, "with --wide-start: the epochs of both halves", cli=False)
    wide_start_width: int = opt(0, "with --wide-start: the width it is pruned to", cli=False)
    offset_weight: float | None = unset(
        0.0,
        "with --parallax neural from a teacher with one: weight of L1(r_s, r_t), the student's "
        "neural-offset ray depth against the teacher's (texels; 0 = off; see docs/parallax.md)",
    )
    lod_levels: int | None = unset(
        1,
        "prefiltered neural textures: pyramid levels (1 = level 0 alone), each trained against "
        "the BTF averaged over its texels' footprint (see "
        "docs/lod.md)",
    )
    lod_kind: str | None = unset(
        "filter",
        "filter: the levels are box averages of level 0 (linear latent downsampling, no "
        "parameters added); levels: each level a texture of its own (NeuMIP's)",
        choices=LOD_KINDS,
    )
    lod_weight: float | None = unset(
        1.0, "weight of the prefiltered levels' L1, shared by the levels"
    )
    coarse_channels: int | None = unset(8, "student U_c channels (one texel per 2x2 block)")
    fine_channels: int | None = unset(8, "student U_f channels (full BTF resolution)")
    export: bool | None = unset(
        True, "also write the runtime pack beside the checkpoint (s.pt -> s.vrnm)"
    )


def check_lod_levels(cfg, res: tuple[int, int], btf_path) -> None:
    """``--lod-levels`` fits the BTF: the last level still has whole 2x2 blocks (and the
    student's half-resolution coarse texture a texel per block)."""
    fit = min((r & -r).bit_length() - 1 for r in res)  # 2^fit divides both sides
    if cfg.lod_levels > fit:
        raise VrnError(
            f"--lod-levels = {cfg.lod_levels} does not fit {btf_path} ({res[0]}x{res[1]} "
            f"texels): level {cfg.lod_levels - 1} needs whole 2x2 blocks; allowed [1, "
            f"{min(max(fit, 1), 12)}]"
        )
