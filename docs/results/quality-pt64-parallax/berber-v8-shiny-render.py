"""berber variant: a shiny synthetic yarn (GGX alpha 0.04, the preset's 0.2): each fibre's
highlight a narrow cone around its axis, the twisted fibres' cones crossing within a texel.

    python berber-v8-shiny-render.py btf render berber --res 64 --dirs 24 --spp 64 --bounces 5 -o berber.btf
"""
import functools
import sys

from vrneural.btf import pt_presets as P

P.PT_PRESETS["berber"] = functools.partial(P.berber, gloss=0.04, heights=(0.05, 0.17))
if __name__ == "__main__":
    from vrneural.cli import main

    sys.exit(main(sys.argv[1:]))
