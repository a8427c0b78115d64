"""berber variant: a pale jute backing (albedo 0.45/0.38/0.26, the preset's is near black), so the
backing seen between the rows is lit or shadowed by the loops beside it as the light moves.

    python berber-v6-jute-render.py btf render berber --res 64 --dirs 24 --spp 64 --bounces 5 -o berber.btf
"""
import functools
import sys

from vrneural.btf import pt_presets as P

FIRST = dict(gloss=0.2, heights=(0.05, 0.17))  # the first version's yarn and pile

P.PT_PRESETS["berber"] = functools.partial(P.berber, backing=(0.45, 0.38, 0.26), **FIRST)
if __name__ == "__main__":
    from vrneural.cli import main

    sys.exit(main(sys.argv[1:]))
