"""berber variant: the shiny yarn of v8 (GGX alpha 0.04) on lower loops (0.04-0.12 tile widths,
the preset's 0.05-0.17, as v3).

    python berber-v9-shiny-low-render.py btf render berber --res 64 --dirs 24 --spp 64 --bounces 5 -o berber.btf
"""
import functools
import sys

from vrneural.btf import pt_presets as P

P.PT_PRESETS["berber"] = functools.partial(P.berber, gloss=0.04, heights=(0.04, 0.12))
if __name__ == "__main__":
    from vrneural.cli import main

    sys.exit(main(sys.argv[1:]))
