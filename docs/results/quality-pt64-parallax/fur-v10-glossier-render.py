"""fur variant: the fifth version with a glossier coating (GGX alpha 0.06, the preset 0.12).

    python fur-v10-glossier-render.py btf render fur --res 64 --dirs 24 --spp 64 --bounces 5 -o fur.btf
"""
import functools
import sys

from vrneural.btf import pt_presets as P

P.PT_PRESETS["fur"] = functools.partial(P.fur, gloss=0.06)
if __name__ == "__main__":
    from vrneural.cli import main

    sys.exit(main(sys.argv[1:]))
