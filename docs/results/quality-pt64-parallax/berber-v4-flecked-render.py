"""berber variant: flecked loop to loop (the colour field's band 12-32 cycles per tile, above the
loops' own spacing, so neighbouring loops draw their colours nearly independently; the four
colours in even shares 30/20/20/30%, so dark and pale loops stand side by side).

    python berber-v4-flecked-render.py btf render berber --res 64 --dirs 24 --spp 64 --bounces 5 -o berber.btf
"""
import functools
import sys

from vrneural.btf import pt_presets as P

FIRST = dict(gloss=0.2, heights=(0.05, 0.17))  # the first version's yarn and pile

P.PT_PRESETS["berber"] = functools.partial(P.berber, flecks=(12.0, 32.0), shares=(0.3, 0.5, 0.7), **FIRST)
if __name__ == "__main__":
    from vrneural.cli import main

    sys.exit(main(sys.argv[1:]))
