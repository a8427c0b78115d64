"""The variants scripts' shared entry (issue #35): render a preset with one variant's keyword
arguments through the CLI. ``python SCRIPT.py VARIANT btf render PRESET ...`` calls
``run(PRESET, VARIANTS)`` with its table of keyword arguments. ``python SCRIPT.py VARIANT
noise X.btf ...`` measures a variant's render's noise floor (``scripts/pt_noise.py``'s
arguments), rendering it again with the variant's keywords: ``pt_noise.py`` alone rebuilds
the preset's defaults, another material."""

import functools
import runpy
import sys
from pathlib import Path

from vrneural.btf import pt_presets


def run(preset: str, variants: dict[str, dict]) -> int:
    """Swap ``preset`` for ``functools.partial(preset, **variants[argv[1]])``, then run the CLI
    on ``argv[2:]``; a usage line naming the variants if ``argv[1]`` is none of them."""
    if len(sys.argv) < 2 or sys.argv[1] not in variants:
        sys.exit(f"usage: {sys.argv[0]} {{{','.join(variants)}}} (btf render {preset} | noise) ...")
    make = getattr(pt_presets, preset)
    pt_presets.PT_PRESETS[preset] = functools.partial(make, **variants[sys.argv[1]])
    if sys.argv[2:3] == ["noise"]:
        script = Path(__file__).resolve().parents[3] / "scripts" / "pt_noise.py"
        sys.argv = [str(script), *sys.argv[3:]]
        runpy.run_path(str(script), run_name="__main__")
        return 0
    from vrneural.cli import main

    return main(sys.argv[2:])
