"""Render a version of the loop pile `berber` (issue #35; docs/quality-research.md): the
preset's keyword arguments of each version measured, v9 being the preset's defaults now.

    python berber-variants-render.py VERSION btf render berber --res 64 --dirs 24 --spp 64 --bounces 5 -o berber.btf
"""

import sys

from variants_render import run

FIRST = dict(gloss=0.2, heights=(0.05, 0.17))  # the first version's yarn and pile
FLECKED = dict(flecks=(12.0, 32.0), shares=(0.3, 0.5, 0.7))  # colour from loop to loop
JUTE = (0.45, 0.38, 0.26)  # a pale backing (the preset's near black)
VERSIONS = {
    "v1": FIRST,
    "v2": {**FIRST, "gloss": 0.08},  # glossier yarn
    "v3": dict(gloss=0.08, heights=(0.04, 0.12)),  # glossier, lower loops
    "v4": {**FIRST, **FLECKED},
    "v5": {**FIRST, **FLECKED, "gloss": 0.08},
    "v6": {**FIRST, "backing": JUTE},
    "v7": {**FIRST, "backing": JUTE, "yarn": 0.25, "gloss": 0.08},  # thinner yarn: wider gaps
    "v8": {**FIRST, "gloss": 0.04},  # shiny synthetic yarn
    "v9": dict(gloss=0.04, heights=(0.04, 0.12)),  # the preset's defaults
}

if __name__ == "__main__":
    sys.exit(run("berber", VERSIONS))
