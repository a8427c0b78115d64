"""berber variant: flecked loop to loop as v4 and a glossier yarn (GGX alpha 0.08, as v2).

    python berber-v5-flecked-glossy-render.py btf render berber --res 64 --dirs 24 --spp 64 --bounces 5 -o berber.btf
"""
import functools
import sys

from vrneural.btf import pt_presets as P

P.PT_PRESETS["berber"] = functools.partial(
    P.berber, flecks=(12.0, 32.0), shares=(0.3, 0.5, 0.7), gloss=0.08, heights=(0.05, 0.17)
)
if __name__ == "__main__":
    from vrneural.cli import main

    sys.exit(main(sys.argv[1:]))
