"""How much of `bench distance`'s floor is the student's training seed? (docs/lod.md, "The
student's seed and budget")

At 10 m and at tiling 8 the bench's sphere is seen over a few degrees of view, lit by two
lights: FLIP against the supersampled teacher there is mostly the student's mean colour at a
handful of (light, view) pairs, its "network" column. This trains students from one teacher
(a bench's ``packs/teacher.pt``) at several seeds and budgets with ``vrneural distill``
(``--method student``, the bench's settings; a pack that is already there is reused) and scores
each, supersampled with the reference's samples, against the teacher at the conditions'
first scored frame::

    python scripts/research/distance_student_seeds.py PACKS OUT --seeds 0,1,2 \\
        --budgets 24,48,48+ema --conds "tiling 8,10 m"

A budget is ``EPOCHS`` or ``EPOCHS+ema`` (``--ema 0.999``). Writes ``OUT/seeds.json`` and
``OUT/seeds.md`` (FLIP per seed, the mean and the spread; the JSON also holds each render's
mean colour beside the teacher's).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

EMA = 0.999


def parse_budget(s: str) -> tuple[int, bool]:
    """``"48"`` -> (48, False); ``"48+ema"`` -> (48, True)."""
    epochs, _, extra = s.partition("+")
    if extra not in ("", "ema") or not epochs.isdigit() or int(epochs) < 1:
        sys.exit(f"--budgets: {s!r} is not EPOCHS or EPOCHS+ema (e.g. 48, 48+ema)")
    return int(epochs), extra == "ema"


def stem(seed: int, budget: str) -> str:
    return f"student-e{budget.replace('+', '-')}-s{seed}"


def train(packs: Path, out: Path, seed: int, budget: str) -> Path:
    """The student of ``seed`` and ``budget`` from ``packs/teacher.pt`` (reused if there)."""
    pack = out / f"{stem(seed, budget)}.vrnm"
    if pack.exists():
        return pack
    epochs, ema = parse_budget(budget)
    cmd = ["vrneural", "distill", str(packs / "teacher.pt"), "--method", "student",
           "--epochs", str(epochs), "--seed", str(seed), "--max-test-slices", "0",
           "--threads", "1", "--no-progress", "-o", str(pack.with_suffix(".pt"))]  # fmt: skip
    if ema:
        cmd += ["--ema", str(EMA)]
    print(" ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)
    return pack


def summary(flips: list[float]) -> dict:
    return {
        "flip": flips,
        "mean": statistics.fmean(flips),
        "min": min(flips),
        "max": max(flips),
        "spread": max(flips) / min(flips),
    }


def report(doc: dict) -> str:
    """The markdown table: one row per condition and budget."""
    seeds = doc["seeds"]
    head = ["condition", "budget", *[f"seed {s}" for s in seeds], "mean", "spread (max/min)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for cond, by in doc["results"].items():
        for budget, r in by.items():
            cells = [cond, budget, *[f"{f:.4f}" for f in r["flip"]], f"{r['mean']:.4f}",
                     f"{r['spread']:.2f}"]  # fmt: skip
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("packs", type=Path, help="a bench's packs/ (its teacher.pt and .vrnm)")
    ap.add_argument("out", type=Path)
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--budgets", default="24,48")
    ap.add_argument("--conds", default="tiling 8,10 m")
    a = ap.parse_args()
    seeds = [int(s) for s in a.seeds.split(",")]
    budgets = a.budgets.split(",")
    for b in budgets:
        parse_budget(b)
    a.out.mkdir(parents=True, exist_ok=True)
    packs = {(s, b): train(a.packs, a.out, s, b) for b in budgets for s in seeds}

    from vrneural.bench import distance as dist
    from vrneural.bench.train_configs import DistanceConfig
    from vrneural.scoring import metrics
    from vrneural.scoring.run import load_packs

    c = DistanceConfig(out=str(a.out)).resolved()
    prof, full, ppd = dist.quest3_view()
    conds = {x.name: x for x in dist.conditions(c)}
    teacher = load_packs([str(a.packs / "teacher.vrnm")])[0]
    doc: dict = {"packs": str(a.packs), "seeds": seeds, "ema": EMA, "results": {},
                 "mean_rgb": {}}  # fmt: skip
    for name in a.conds.split(","):
        if name not in conds:
            sys.exit(f"--conds: {name!r} is not one of {', '.join(conds)}")
        cond = conds[name]
        f = cond.scored[0]
        ref = dist.supersampled(c, cond, prof, full, teacher, [f])[f]
        doc["mean_rgb"][name] = {"teacher": ref.mean((0, 1, 2)).tolist()}
        doc["results"][name] = {}
        for b in budgets:
            flips = []
            for s in seeds:
                mat = load_packs([str(packs[s, b])])[0]
                img = dist.supersampled(c, cond, prof, full, mat, [f])[f]
                flips.append(float(metrics.flip_hdr_eyes(ref, img, ppd)))
                doc["mean_rgb"][name][stem(s, b)] = img.mean((0, 1, 2)).tolist()
                print(f"{name} {b} seed {s}: FLIP {flips[-1]:.4f}", flush=True)
            doc["results"][name][b] = summary(flips)
    (a.out / "seeds.json").write_text(json.dumps(doc, indent=1))
    (a.out / "seeds.md").write_text(report(doc))
    print(report(doc))


if __name__ == "__main__":
    main()
