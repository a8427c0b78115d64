"""fur variant: glossy strands (GGX alpha 0.12, the fifth version's) and tufts leaning more
(slope standard deviation 0.35, the preset 0.15).

    python fur-v9-glossy-lean-render.py btf render fur --res 64 --dirs 24 --spp 64 --bounces 5 -o fur.btf
"""
import functools
import sys

from vrneural.btf import pt_presets as P

P.PT_PRESETS["fur"] = functools.partial(P.fur, gloss=0.12, lean=0.35)
if __name__ == "__main__":
    from vrneural.cli import main

    sys.exit(main(sys.argv[1:]))
