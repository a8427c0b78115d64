"""`vrneural teach material.btf -o teacher.pt`: train the 128-wide teacher ("NeuMIP Max")."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from vrneural.config import add_config_args, config_from_args
from vrneural.distill.config import TeachConfig
from vrneural.errors import count


def register(sub) -> None:
    p = sub.add_parser(
        "teach",
        help="train the teacher network on a BTF",
        description="Train the 128-wide teacher (neural texture + MLP, arch 'single') on a "
        "BTF. Writes the checkpoint, <output>.config.json and (unless --no-export) the "
        "teacher's .vrnm beside it (the runtime's per-pixel reference). Ctrl-C saves; "
        "--resume continues exactly (config JSON and pack are written when the run finishes).",
    )
    p.add_argument("btf", help="input BTF file (.btf)")
    p.add_argument(
        "-o", "--output", default="teacher.pt", help="output checkpoint (.pt; default: teacher.pt)"
    )
    add_config_args(p, TeachConfig)
    p.set_defaults(func=run)


def run(args) -> int:
    from vrneural.distill.teach import run_teach

    cfg = config_from_args(TeachConfig, args)
    return _report(lambda: run_teach(cfg), cfg.output)


def _report(fn, output: str) -> int:
    """Run a training stage; report the result or the interruption (exit 130). Under
    ``torchrun`` only rank 0 reports (it alone writes the files), and every rank leaves the
    process group before it exits."""
    from vrneural.distill.specs import spec_width
    from vrneural.distill.train import Interrupted, dist_teardown

    rank0 = int(os.environ.get("RANK", "0")) == 0
    try:
        ck = fn()
    except Interrupted as e:
        dist_teardown(synchronise=False)
        if rank0:
            print(
                f"interrupted at {e}; checkpoint saved to {getattr(e, 'path', output)}; "
                f"continue with {getattr(e, 'resume', '--resume')}",
                file=sys.stderr,
            )
        return 130
    except BaseException:
        dist_teardown(synchronise=False)
        raise
    dist_teardown()
    if not rank0:
        return 0
    h = ck["history"][-1] if ck["history"] else {}
    test = h.get("test_l1", float("nan"))
    pack = Path(output).with_suffix(".vrnm")
    wrote = f"  + {pack}" if ck.get("config", {}).get("export") and pack.is_file() else ""
    method = ck["method"]
    if ck.get("config", {}).get("distill") is False:  # --no-distill: ground truth only
        method += " (no distillation)"
    width = spec_width(ck["spec"]) if ck.get("spec") else None
    if width and width != 8 and ck.get("method") in ("student", "single8"):
        method += f" {width} wide"
    init = ck.get("init_from")
    if init:  # --init-from: where its weights started
        was = spec_width(init["spec"])
        cut = f"pruned to {width}" if was != width else "not pruned"
        method += f", from {init['path']} ({was} wide, {count(init['epochs'], 'epoch')}, {cut})"
    epochs = f"epochs {ck['epoch']}"
    if init:  # the result line counts both halves: "epochs 2 (4 in all)"
        epochs += f" ({int(init['epochs']) + int(ck['epoch'])} in all)"
    black = ck.get("test_mean")  # the test slices' mean value: the L1 of predicting black
    rel = f" ({test / black:.0%} of the mean value)" if black and test == test else ""
    print(
        f"{output}: {method} {epochs}  test L1 {test:.5f}{rel}"
        f"  train {ck.get('train_seconds', 0):.1f} s{wrote}"
    )
    if black and test > black:
        print(
            f"warning: {output}: test L1 {test:.5f} is above the test slices' mean value "
            f"{black:.5f} ({test / black:.0%}): predicting black would score better; "
            "undertrained, or a learning rate too high for this BTF?",
            file=sys.stderr,
        )
    ref = ck.get("teacher_test_l1")
    if ref and test == test:  # a student: compare it with its teacher on the same slices
        ratio = test / ref
        print(f"  teacher test L1 {ref:.5f} on the same slices: {ratio:.2f}x")
        if ratio > WORSE_THAN_TEACHER:
            print(
                f"warning: {output}: test L1 {ratio:.1f}x the teacher's (above "
                f"{WORSE_THAN_TEACHER:g}x): undertrained? more --epochs usually closes much "
                "of it (the quality report's 50-epoch students reach 1.7-6x)",
                file=sys.stderr,
            )
    return 0


#: Student-to-teacher test-L1 ratio above which `distill` warns: the 50-epoch students of
#: docs/results/quality-50-5seeds.md reach 1.7x (stone) to 6x (metal) of their teachers
WORSE_THAN_TEACHER = 8.0
