"""Render a variant of the cut pile `fur` (issue #35; docs/quality-research.md) by the preset's
keyword arguments, the labels those of the research log's fur table (fur25 is the preset's
defaults now, the seventh version; fur17 the sixth, fur10 the fifth).

    python fur-variants-render.py VARIANT btf render fur --res 64 --dirs 24 --spp 64 --bounces 5 -o fur.btf
"""

import sys

from variants_render import run

# the sixth version's strands and colours (the variants fur10-fur24 change these)
SIXTH = dict(per_tuft=40, radius=0.0035, bands=(0.4, 0.7))
FIFTH = {**SIXTH, "heights": (0.07, 0.19)}  # the fifth version: tufts of varied height
VARIANTS = {
    "fur10": FIFTH,
    "fur11": {**FIFTH, "lean": 0.35},  # tufts leaning more
    "fur12": {**FIFTH, "gloss": 0.06},  # glossier
    "fur13": {**SIXTH, "gloss": 0.04, "heights": (0.05, 0.13)},  # berber's recipe: shinier, lower pile
    # thick crimped strands (wool): each strand's highlight wanders with its waves
    "fur14": {**FIFTH, "gloss": 0.04, "per_tuft": 14, "radius": 0.009, "crimp": 0.012},
    # saxony: each tuft a twisted bundle of thick glossy strands, gaps onto the backing
    "fur15": {**FIFTH, "gloss": 0.04, "per_tuft": 8, "radius": 0.006, "bundle": 0.014},
    "fur16": {**FIFTH, "gloss": 0.04, "per_tuft": 8, "radius": 0.006, "bundle": 0.014,
              "heights": (0.04, 0.12)},
    # a clipped pile: tufts of one height, so the tips are one surface that slides coherently
    "fur17": SIXTH,  # the sixth version (0.14-0.17)
    "fur18": {**SIXTH, "heights": (0.09, 0.11)},
    "fur19": {**SIXTH, "heights": (0.19, 0.22)},  # clipped taller
    "fur20": {**SIXTH, "tufts": 256, "per_tuft": 30},  # clipped denser: the tips a closed surface
    # carved: the tufts along the patches' borders (3 in 10) cut to half height, channels
    "fur21": {**SIXTH, "carve": 0.3},
    "fur22": {**SIXTH, "heights": (0.19, 0.22), "gloss": 0.06},  # clipped taller and glossier
    "fur23": {**SIXTH, "radius": 0.002, "per_tuft": 80},  # finer strands, twice as many: a velvet
    "fur24": {**SIXTH, "bands": (0.5, 0.5)},  # two colours, cream and near-black, half each
    "fur25": {},  # fur23 and fur24 together: the preset's defaults, the seventh version
}

if __name__ == "__main__":
    sys.exit(run("fur", VARIANTS))
