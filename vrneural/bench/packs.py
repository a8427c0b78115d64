"""Tiny trained packs for `bench tradeoff`: one synthetic BTF, its teacher and four small
networks, trained with :mod:`vrneural.distill` at a small stated budget and cached in
``OUT/packs`` (reused while the training config is unchanged, also across ``--force`` reruns).

Packs: ``teacher`` (128-wide, the per-pixel reference), ``student`` (coarse-to-fine, distilled),
``student_nodistill`` (coarse-to-fine, ground truth only), ``single8`` (single-level 8-wide,
distilled) and ``neumip`` (arch single, 7 channels, 4 x 25, log1p, ground truth only) -- the same
five as `bench quality`.
"""

from __future__ import annotations

import json
from pathlib import Path

from vrneural.errors import VrnError

RUNS = {
    "student": dict(method="student"),
    "student_nodistill": dict(method="student", distill=False),
    "single8": dict(method="single8"),
    "neumip": dict(method="neumip", distill=False),
}
PACKS = ("teacher", *RUNS)


def train_packs(d: Path, budget: dict, progress: bool, log=print) -> dict[str, Path]:
    """Train (or reuse) every pack under ``d``; ``budget``: preset, res, dirs, teacher_width,
    teacher_epochs, epochs, seed. Returns name -> .vrnm path."""
    from vrneural.btf.synth import BtfConfig, synthesize
    from vrneural.distill.config import DistillConfig, TeachConfig
    from vrneural.distill.distill import run_distill
    from vrneural.distill.teach import run_teach

    paths = {k: d / f"{k}.vrnm" for k in PACKS}
    stamp = d / "budget.json"
    want = json.dumps(budget, sort_keys=True)
    if stamp.exists() and stamp.read_text() == want and all(p.exists() for p in paths.values()):
        log(f"packs: reusing {d}")
        return paths
    d.mkdir(parents=True, exist_ok=True)
    stamp.unlink(missing_ok=True)
    btf = d / "btf.btf"
    btf.unlink(missing_ok=True)
    synthesize(
        BtfConfig(
            preset=budget["preset"], res=budget["res"], dirs=budget["dirs"], seed=budget["seed"]
        ),
        btf,
        progress=progress,
    )
    common = dict(seed=budget["seed"], progress=progress, force=True, max_test_slices=0)
    run_teach(
        TeachConfig(
            btf=str(btf),
            output=str(d / "teacher.pt"),
            epochs=budget["teacher_epochs"],
            width=budget["teacher_width"],
            **common,
        )
    )
    for name, kw in RUNS.items():
        run_distill(
            DistillConfig(
                teacher=str(d / "teacher.pt"),
                output=str(d / f"{name}.pt"),
                epochs=budget["epochs"],
                **kw,
                **common,
            )
        )
    missing = [str(p) for p in paths.values() if not p.exists()]
    if missing:
        raise VrnError(f"training finished but packs are missing: {', '.join(missing)}")
    stamp.write_text(want)
    return paths


def load_packs(paths: dict[str, Path]) -> dict:
    """name -> NeuralMaterial."""
    from vrneural.formats.vrnm import read_vrnm

    out = {}
    for k, p in paths.items():
        if not Path(p).is_file():
            raise VrnError(f"--packs: {str(p)!r} not found (needs {', '.join(PACKS)} .vrnm)")
        out[k] = read_vrnm(p)
    return out
