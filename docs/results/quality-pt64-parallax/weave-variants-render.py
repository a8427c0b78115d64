"""Render a variant of the plain weave `weave` (issue #35; docs/quality-research.md) by the
preset's keyword arguments, the labels those of the research log's weave screen (wv0 is the
preset's defaults).

    python weave-variants-render.py VARIANT btf render weave --res 64 --dirs 24 --spp 64 --bounces 5 -o weave.btf
"""

import sys

from variants_render import run

# cream weft over near-black warp: every crossing a step from light to dark
STEP = {
    "warp_a": (0.02, 0.02, 0.025),
    "warp_b": (0.03, 0.03, 0.035),
    "weft_a": (0.80, 0.74, 0.60),
    "weft_b": (0.86, 0.80, 0.66),
}
VARIANTS = {
    "wv0": {},  # the preset
    "wv1": {"gloss": 0.08},  # glossier fibres: a narrow highlight along each twisted fibre
    "wv2": {"threads": 6},  # finer yarns: 6 a tile (pitch 10.7 texels at 64^2, was 16)
    "wv3": {"colours": STEP},  # two-tone: cream weft, near-black warp
}

if __name__ == "__main__":
    sys.exit(run("weave", VARIANTS))
