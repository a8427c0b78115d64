"""Sub-configs several benches share (:func:`vrneural.config.part`): their fields are the
benches' options, declared and checked once here instead of copied into every bench.
"""

from __future__ import annotations

from dataclasses import dataclass

from vrneural.btf.config import BtfConfig
from vrneural.config import opt, unset
from vrneural.errors import check_range
from vrneural.runtime.config import parse_res

#: the largest sample count per pixel (each sample is a full per-pixel teacher render)
SPP_MAX = 256


def bench_config(name: str, quick: str, force: str = "", resume: str = ""):
    """``@dataclass`` for the config of `vrneural bench NAME`, adding the fields every bench
    has: ``out`` first (``bench-NAME``, unless the class places it; ``--out`` itself is
    :func:`~vrneural.bench.entries.add_bench`'s), then the class's own, then ``quick`` (the
    bench's help for it), ``progress``, ``force`` and, with its help, ``resume``."""

    def wrap(cls):
        own = cls.__annotations__
        head = {} if "out" in own else {"out": opt(f"bench-{name}", "output directory", cli=False)}
        tail = {
            "quick": opt(False, quick),
            "progress": opt(True, "show progress bars"),
            "force": opt(False, force or "overwrite an existing output directory"),
        }
        if resume:
            tail["resume"] = opt(False, resume)
        for k, field in (head | tail).items():
            setattr(cls, k, field)
        cls.__annotations__ = dict.fromkeys(head, "str") | own | dict.fromkeys(tail, "bool")
        return dataclass(cls)

    return wrap


@dataclass
class Loop:
    """How a frame bench (``frames``, ``lights``, ``materials``) renders: eyes, their size, and
    the frames measured."""

    eye_res: str | None = unset("2064x2208", "pixels per eye, WIDTHxHEIGHT (quest3)")
    eyes: int = opt(2, "eyes (1 or 2)")
    cycles: int = opt(1, "update cycles measured per configuration (N + 1 frames each)")
    warmup: float = opt(
        0.5, "seconds of unmeasured frames before each configuration (GPU clocks; 0 = none)"
    )

    def check(self) -> tuple[int, int]:
        """One-line errors for bad values; returns ``--eye-res`` as ``(width, height)``."""
        check_range("--eyes", self.eyes, 1, 2)
        check_range("--cycles", self.cycles, 1, 100)
        check_range("--warmup", self.warmup, 0.0, 60.0)
        return parse_res(self.eye_res)


#: ``--quick`` of every frame bench: small eyes
QUICK_LOOP = Loop(eye_res="258x276")


@dataclass
class Scored:
    """The window scored against the supersampled reference (``tradeoff``, ``distance``)."""

    crop: int | None = unset(128, "side (pixels) of the scored window of each quest3 eye image")
    spp: int | None = unset(
        16, "reference samples per pixel (stratified; its noise floor is measured)"
    )
    scored: int | None = unset(6, "consecutive frames scored per condition")

    def check(self) -> None:
        check_range("--crop", self.crop, 16, 2064)
        check_range("--spp", self.spp, 1, SPP_MAX)
        check_range("--scored", self.scored, 2, 1000)


@dataclass
class PackBudget:
    """What the packs ``tradeoff`` and ``distance`` train cost: the synthetic BTF's size, the
    teacher, the epochs."""

    btf_res: int | None = unset(32, "BTF texels per side (training budget)")
    btf_dirs: int | None = unset(10, "BTF light and view directions (dirs^2 slices)")
    teacher_width: int | None = unset(128, "teacher hidden width (the paper's)")
    teacher_epochs: int | None = unset(4, "teacher epochs")
    epochs: int | None = unset(4, "epochs of each small network")
    seed: int = opt(0, "training seed")

    def check(self, presets: list[str], preset_flag: str = "--preset") -> None:
        """Each preset's BTF and the training sizes, with their options' names."""
        flags = {"res": "--btf-res", "dirs": "--btf-dirs", "preset": preset_flag}
        for p in presets:
            BtfConfig(preset=p, res=self.btf_res, dirs=self.btf_dirs, seed=self.seed).validate(
                flags=flags
            )
        check_range("--teacher-width", self.teacher_width, 4, 512)
        for k in ("teacher_epochs", "epochs"):
            check_range(f"--{k.replace('_', '-')}", getattr(self, k), 1, 10_000)

    def of(self, preset: str) -> dict:
        """The budget of one preset's packs (:func:`vrneural.bench.packs.train_packs`)."""
        return dict(preset=preset, res=self.btf_res, dirs=self.btf_dirs,
                    teacher_width=self.teacher_width, teacher_epochs=self.teacher_epochs,
                    epochs=self.epochs, seed=self.seed)  # fmt: skip


#: ``--quick``: 16^2 texels, 6 directions, a 32-wide teacher, one epoch each
QUICK_BUDGET = PackBudget(btf_res=16, btf_dirs=6, teacher_width=32, teacher_epochs=1, epochs=1)
#: ``--quick``: 48-pixel crops, 2 spp, 3 frames
QUICK_SCORED = Scored(crop=48, spp=2, scored=3)
