"""The variants scripts' shared entry (issue #35): render a preset with one variant's keyword
arguments through the CLI. ``python SCRIPT.py VARIANT btf render PRESET ...`` calls
``run(PRESET, VARIANTS)`` with its table of keyword arguments."""

import functools
import sys

from vrneural.btf import pt_presets


def run(preset: str, variants: dict[str, dict]) -> int:
    """Swap ``preset`` for ``functools.partial(preset, **variants[argv[1]])``, then run the CLI
    on ``argv[2:]``; a usage line naming the variants if ``argv[1]`` is none of them."""
    if len(sys.argv) < 2 or sys.argv[1] not in variants:
        sys.exit(f"usage: {sys.argv[0]} {{{','.join(variants)}}} btf render {preset} ...")
    make = getattr(pt_presets, preset)
    pt_presets.PT_PRESETS[preset] = functools.partial(make, **variants[sys.argv[1]])
    from vrneural.cli import main

    return main(sys.argv[2:])
