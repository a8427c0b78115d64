"""``EvalConfig``: what `vrneural eval` takes (each field's help is its --help line); a light
module, which the CLI's parser imports without the scoring code."""

from __future__ import annotations

from dataclasses import dataclass

from vrneural.config import opt

#: ``--slices auto`` scores every slice up to this many texels in all, else slices drawn at
#: random adding up to about as many (a few minutes on two CPU cores for an 8-wide student)
AUTO_TEXELS = 64 * 1024 * 1024
PRECISION_CHOICES = ("f32", "f16", "both")


@dataclass
class EvalConfig:
    """What ``vrneural eval`` scores and where it writes (one field per option)."""

    packs: tuple = opt((), "runtime packs (.vrnm) to score", cli=False)
    btf: str = opt("", "BTF to score against (default: the one the packs record)")
    slices: str = opt(
        "auto",
        "slices scored: 'all', a count N (drawn at random, fixed seed), or 'auto' (all "
        f"unless the BTF holds more than {AUTO_TEXELS // 2**20}Mi texels, default)",
    )
    precision: str = opt(
        "f32", "arithmetic of the runtime emulated: f32, f16 or both", choices=PRECISION_CHOICES
    )
    out: str = opt("", "directory for results.json, results.md, slices.png, config.json")
    force: bool = opt(False, "overwrite an existing --out")
