"""`vrneural distill teacher.pt -o student.pt`: distill the coarse-to-fine student (or train a
baseline with --method)."""

from __future__ import annotations

from vrneural.cli.teach import _report
from vrneural.config import add_config_args, config_from_args
from vrneural.distill.config import DistillConfig


def register(sub) -> None:
    p = sub.add_parser(
        "distill",
        help="distill a student (or baseline) from a teacher checkpoint",
        description="Train the 8-wide coarse-to-fine student from a teacher (paper Eq. 5), "
        "or a baseline (--method single8|neumip, --no-distill for ground truth only). The BTF "
        "path recorded in the teacher is used unless --btf is given. Writes the checkpoint, "
        "<output>.vrnm (unless --no-export) and config JSON beside them.",
    )
    p.add_argument("teacher", help="teacher checkpoint from `vrneural teach`")
    p.add_argument(
        "-o", "--output", default="student.pt", help="output checkpoint (.pt; default: student.pt)"
    )
    add_config_args(p, DistillConfig)
    p.set_defaults(func=run)


def run(args) -> int:
    from vrneural.distill.distill import run_distill

    cfg = config_from_args(DistillConfig, args)
    return _report(lambda: run_distill(cfg), cfg.output)
