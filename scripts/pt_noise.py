"""The Monte Carlo noise floor of path-traced BTFs (`btf render`), as JSON + Markdown.

    .venv/bin/python scripts/pt_noise.py A.btf [B.btf ...] --views 6 -o docs/results/pt-noise

For each file: ``views`` evenly spaced views (all lights) rendered again with the next sample
seed, and the L1 between the two renders (vrneural.btf.pt_render.noise_floor).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def main() -> int:
    from vrneural.btf.pt_render import noise_floor
    from vrneural.outputs import write_json

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("files", nargs="+")
    p.add_argument("--views", type=int, default=6)
    p.add_argument("-o", "--out", required=True, help="output stem (.json and .md are added)")
    a = p.parse_args()
    rows = []
    for f in a.files:
        r = noise_floor(f, a.views)
        print(json.dumps(r), file=sys.stderr)
        rows.append(r)
    out = Path(a.out)
    write_json(out.with_suffix(".json"), {"benchmark": "pt-noise", "records": rows})
    lines = [
        "# Noise floor of the path-traced presets",
        "",
        "L1 between two renders of the same material and settings with different sample "
        "seeds, over the views listed (all 24 lights each); against a converged image about "
        "1/sqrt(2) of that.",
        "",
        "| file | spp | views | mean value | L1 (two renders) | L1 vs converged (est.) | "
        "relative | seconds |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {Path(r['file']).name} | {r['spp']} | {len(r['views'])} | {r['mean']:.4f} | "
            f"{r['l1']:.5f} | {r['l1_vs_converged']:.5f} | {100 * r['relative']:.1f}% | "
            f"{r['seconds']:.0f} |"
        )
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print(out.with_suffix(".json"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
