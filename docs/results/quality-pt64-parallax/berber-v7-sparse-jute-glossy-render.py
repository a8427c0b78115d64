"""berber variant: the pale jute backing of v6, a thinner yarn (radius 0.25 of the row pitch, the
preset's 0.3: wider gaps between the rows) and a glossier one (GGX alpha 0.08, as v2).

    python berber-v7-sparse-jute-glossy-render.py btf render berber --res 64 --dirs 24 --spp 64 --bounces 5 -o berber.btf
"""
import functools
import sys

from vrneural.btf import pt_presets as P

P.PT_PRESETS["berber"] = functools.partial(
    P.berber, backing=(0.45, 0.38, 0.26), yarn=0.25, gloss=0.08, heights=(0.05, 0.17)
)
if __name__ == "__main__":
    from vrneural.cli import main

    sys.exit(main(sys.argv[1:]))
