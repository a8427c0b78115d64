"""`vrneural eval PACK [PACK ...]`: score runtime packs against a BTF (numpy alone)."""

from __future__ import annotations

import json

from vrneural.config import add_config_args, config_from_args
from vrneural.scoring.config import EvalConfig


def register(sub) -> None:
    p = sub.add_parser(
        "eval",
        help="score runtime packs (.vrnm) against a BTF: L1, PSNR, SSIM, f16 cost",
        description="Score each PACK against a BTF (--btf, else the one the packs record) as "
        "the shader computes it (float16 textures; --precision f16 emulates the runtime's "
        "half-precision path): L1 over all slices, the held-out ones and the training ones, "
        "RMSE, PSNR and SSIM of each slice as displayed, the worst slices. Prints a table; "
        "--out DIR also writes results.json, results.md, slices.png (the BTF, each pack "
        "and its error at characteristic slices) and config.json. Needs no torch.",
    )
    p.add_argument("packs", nargs="+", metavar="PACK", help="runtime pack (.vrnm)")
    add_config_args(p, EvalConfig, skip=("packs", "out"))
    p.add_argument(
        "-o",
        "--out",
        default="",
        help="directory for results.json, results.md, slices.png and config.json "
        "(default: print only)",
    )
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    p.add_argument(
        "--quiet", "--no-progress", dest="quiet", action="store_true", help="no progress bar"
    )
    p.set_defaults(func=main)


def main(args) -> int:
    from vrneural.scoring.run import OUT_FILES, evaluate, text_table

    cfg = config_from_args(EvalConfig, args, packs=tuple(args.packs))
    doc = evaluate(cfg, progress=not args.quiet)
    if args.json:
        print(json.dumps(doc, indent=1))
        return 0
    print(text_table(doc))
    if cfg.out:
        print(f"wrote {cfg.out}/: {', '.join(OUT_FILES)}")
    return 0
