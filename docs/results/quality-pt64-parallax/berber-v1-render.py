"""berber's first version (GGX alpha 0.2, loops 0.05-0.17 tile widths): the material of the
2026-12-05 five-seed runs, students and 144-spp render; the preset's defaults are now v9's.

    python berber-v1-render.py btf render berber --res 64 --dirs 24 --spp 64 --bounces 5 -o berber.btf
"""
import functools
import sys

from vrneural.btf import pt_presets as P

P.PT_PRESETS["berber"] = functools.partial(P.berber, gloss=0.2, heights=(0.05, 0.17))
if __name__ == "__main__":
    from vrneural.cli import main

    sys.exit(main(sys.argv[1:]))
