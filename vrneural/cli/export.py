"""`vrneural export student.pt -o material.vrnm`: write the runtime pack of a checkpoint."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

from vrneural.config import config_path
from vrneural.errors import check_range
from vrneural.outputs import check_outputs, check_suffix, write_json


def register(sub) -> None:
    p = sub.add_parser(
        "export",
        help="write the runtime pack (.vrnm) of a trained checkpoint",
        description="Convert a teacher or student checkpoint into a .vrnm runtime pack "
        "(float32 weights, float16 textures; no pickle). Refuses NaN/Inf; reports weight, "
        "texture and activation ranges over the training data against the float16 range and "
        "stores them, the provenance and the metrics in the pack's meta.",
    )
    p.add_argument("checkpoint", help="checkpoint (.pt) from `vrneural teach` or `distill`")
    p.add_argument("-o", "--output", required=True, help="output pack (.vrnm)")
    p.add_argument("--btf", default="", help="BTF for the activation ranges (default: recorded)")
    p.add_argument(
        "--lod-levels",
        type=int,
        default=0,
        help="give a checkpoint trained without a pyramid one of N levels, box averages of "
        "level 0 (untrained; `distill --lod-levels N` trains them; default: as trained)",
    )
    p.add_argument("--force", action="store_true", help="overwrite an existing output")
    p.add_argument("--json", action="store_true", help="print the ranges as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    from vrneural.distill.checkpoint import load_checkpoint
    from vrneural.distill.export import export_checkpoint, ranges_table
    from vrneural.formats.vrnm import read_vrnm
    from vrneural.material import width_words

    check_suffix(args.output, ".vrnm", "pack", "material.vrnm")
    sidecar = config_path(args.output)
    check_outputs([args.output, sidecar], args.force, inputs=[args.checkpoint, args.btf])
    ck = load_checkpoint(args.checkpoint)
    if not ck.get("finished", True):
        _warn_unfinished(args.checkpoint, ck, args.output)

    check_range("--lod-levels", args.lod_levels, 0, 12)
    out, meta = export_checkpoint(
        ck,
        args.output,
        force=args.force,
        source=args.checkpoint,
        btf=args.btf or None,
        lod_levels=args.lod_levels,
    )
    write_json(
        sidecar,
        {
            "config": "export",
            "checkpoint": str(args.checkpoint),
            "btf": args.btf or None,
            "training_config": ck["config"],
            "metrics": meta["metrics"],
        },
    )
    if args.json:
        print(json.dumps(meta["ranges"], indent=2))
    else:
        print(ranges_table(meta["ranges"]))
        m = meta["metrics"]
        print(
            f"{out}: {meta['method']}{width_words(read_vrnm(out))}  weights "
            f"{m['weight_bytes']} B  textures "
            f"{m['texture_bytes']} B  {m['macs_per_texel']:g} MACs/texel  test L1 "
            f"{'n/a (no epoch done)' if m['test_l1'] is None else format(m['test_l1'], '.5f')}"
            f"  numpy-vs-torch {m['pack_vs_torch_max_abs']:.2e}"
        )
    return 0


def _warn_unfinished(path, ck: dict, output) -> None:
    """One-line warning: the checkpoint is an interrupted run, and how to finish it."""
    from vrneural.distill.checkpoint import UnfinishedRunWarning, unfinished_run
    from vrneural.distill.distill import is_wide_half, run_of_wide_half

    cmd = "teach BTF" if ck.get("kind") == "teacher" else "distill TEACHER"
    if is_wide_half(ck.get("config", {})):  # the wide half of --wide-start: resume the run
        how = f"its --wide-start run, `vrneural {cmd} -o {run_of_wide_half(path)} --resume`"
    else:
        how = f"`vrneural {cmd} -o {path} --resume`"
        if Path(output).resolve() == Path(path).with_suffix(".vrnm").resolve():
            how += " (which replaces this pack)"  # the pack a finished run writes beside it
    warnings.warn(
        f"{path}: {unfinished_run(ck)}; exporting it as it is; finish it with {how}",
        UnfinishedRunWarning,
        stacklevel=1,
    )
