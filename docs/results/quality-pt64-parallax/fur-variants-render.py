"""Render a variant of the cut pile `fur` (issue #35; docs/quality-research.md) by the preset's
keyword arguments, the labels those of the research log's fur table (fur17 is the preset's
defaults now, the sixth version; fur10 the fifth).

    python fur-variants-render.py VARIANT btf render fur --res 64 --dirs 24 --spp 64 --bounces 5 -o fur.btf
"""

import sys

from variants_render import run

FIFTH = dict(heights=(0.07, 0.19))  # the fifth version: tufts of varied height
VARIANTS = {
    "fur10": FIFTH,
    "fur11": {**FIFTH, "lean": 0.35},  # tufts leaning more
    "fur12": {**FIFTH, "gloss": 0.06},  # glossier
    "fur13": dict(gloss=0.04, heights=(0.05, 0.13)),  # berber's recipe: shinier, lower pile
    # thick crimped strands (wool): each strand's highlight wanders with its waves
    "fur14": {**FIFTH, "gloss": 0.04, "per_tuft": 14, "radius": 0.009, "crimp": 0.012},
    # saxony: each tuft a twisted bundle of thick glossy strands, gaps onto the backing
    "fur15": {**FIFTH, "gloss": 0.04, "per_tuft": 8, "radius": 0.006, "bundle": 0.014},
    "fur16": dict(gloss=0.04, per_tuft=8, radius=0.006, bundle=0.014, heights=(0.04, 0.12)),
    # a clipped pile: tufts of one height, so the tips are one surface that slides coherently
    "fur17": {},  # the preset's defaults (0.14-0.17)
    "fur18": dict(heights=(0.09, 0.11)),
    "fur19": dict(heights=(0.19, 0.22)),  # (render stopped: no time left to judge it)
}

if __name__ == "__main__":
    sys.exit(run("fur", VARIANTS))
