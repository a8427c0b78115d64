#!/usr/bin/env python3
"""Regenerate the bundled material packs of the built-in demo from their seeds and configs.

For each preset: ``btf synth`` -> ``teach`` -> ``distill`` -> ``export`` (teacher and student),
then the packs, the resolved training configs and the wall time of every step are written to
``vrneural/data/materials/``::

    <preset>.vrnm                student (arch coarse_fine), what the demo renders
    <preset>.teacher.vrnm        teacher (arch single), for ``vrneural run --mode reference``
    <preset>.teacher.config.json / <preset>.student.config.json   resolved configs
    manifest.json                settings, seeds, per-step wall seconds, test L1 per pack

Each pack's ``meta`` keeps the provenance/metrics/ranges that export writes and gains a
``build`` entry (the commands and the wall seconds of every step). Intermediate files (BTF,
checkpoints) go to ``--work`` (default ``out/assets``); a rerun without ``--force`` reuses the
finished steps recorded in ``<work>/<preset>/steps.json`` (same command, output present) and
keeps their recorded times. Usage::

    .venv/bin/python demo/make_assets.py       # leather, fabric, wood; ~15 min unloaded on 2 cores
    .venv/bin/python demo/make_assets.py --presets wood --jobs 1 --force
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "vrneural" / "data" / "materials"

#: The recipe of the bundled packs (edit here, rerun, commit the packs).
RECIPE = {
    "res": 48,  # texels per side of the BTF tile
    "dirs": 40,  # light and view directions (40 x 40 (wi, wo) slices)
    "spp": 4,  # jittered sub-samples per texel in btf synth
    "seed": 0,  # btf synth seed and training seed
    "teach_epochs": 16,
    "distill_epochs": 24,
    "ema": 0.999,  # weight average of teacher and student (docs/training.md, --ema)
}


def step(log: list, name: str, cmd: list[str], prefix: str, done: dict | None = None) -> None:
    """Run one CLI step, streaming its output with a ``[preset]`` prefix; record wall time.
    ``done``: the record of this exact step from an earlier run whose output exists (reused)."""
    if done is not None and done.get("command") == "vrneural " + " ".join(cmd):
        print(f"[{prefix}] {name}: reusing the output of an earlier run ({done['seconds']} s)")
        log.append(dict(done, reused=True))
        return
    print(f"[{prefix}] $ vrneural {' '.join(cmd)}", flush=True)
    t0 = time.perf_counter()
    env = dict(os.environ, XDG_RUNTIME_DIR=os.environ.get("XDG_RUNTIME_DIR", "/tmp"))
    r = subprocess.run([sys.executable, "-m", "vrneural", *cmd], env=env, cwd=ROOT)
    dt = time.perf_counter() - t0
    if r.returncode:
        raise SystemExit(f"[{prefix}] step '{name}' failed (exit {r.returncode}) after {dt:.0f} s")
    print(f"[{prefix}] {name}: {dt:.1f} s", flush=True)
    log.append({"step": name, "command": "vrneural " + " ".join(cmd), "seconds": round(dt, 1)})


def build(preset: str, work: Path, force: bool) -> dict:
    """Train one preset and install its packs. Returns the manifest entry."""
    from vrneural.formats.vrnm import read_vrnm, write_vrnm

    r, w = RECIPE, work / preset
    w.mkdir(parents=True, exist_ok=True)
    f = ["--force"] if force else []
    btf, tea, stu = str(w / f"{preset}.btf"), str(w / "teacher.pt"), str(w / "student.pt")
    log: list = []
    rec = w / "steps.json"  # per-step records, so an interrupted run resumes at the next step
    prev = {} if force or not rec.is_file() else json.loads(rec.read_text())

    def keep(name: str, out: str) -> dict | None:
        return prev.get(name) if Path(out).is_file() else None

    def save() -> None:
        rec.write_text(json.dumps({e["step"]: e for e in log}, indent=1) + "\n")

    ep = ["--no-progress"] if os.environ.get("VRN_NO_PROGRESS") else []
    synth = ["btf", "synth", "--preset", preset, "--res", str(r["res"]), "--dirs", str(r["dirs"])]
    synth += ["--spp", str(r["spp"]), "--seed", str(r["seed"]), "-o", btf, *ep]
    step(log, "btf synth", synth + f, preset, keep("btf synth", btf))
    save()
    teach = ["teach", btf, "-o", tea, "--epochs", str(r["teach_epochs"]), "--seed", str(r["seed"])]
    teach += ["--ema", str(r["ema"])]
    step(log, "teach", [*teach, "--no-export", *ep, *f], preset, keep("teach", tea))
    save()
    dist = ["distill", tea, "-o", stu, "--epochs", str(r["distill_epochs"]), "--ema", str(r["ema"])]
    step(log, "distill", [*dist, "--seed", str(r["seed"]), "--no-export", *ep, *f], preset)
    save()
    out_s, out_t = DATA / f"{preset}.vrnm", DATA / f"{preset}.teacher.vrnm"
    step(log, "export student", ["export", stu, "-o", str(out_s), "--force"], preset)
    step(log, "export teacher", ["export", tea, "-o", str(out_t), "--force"], preset)
    save()
    total = round(sum(e["seconds"] for e in log), 1)  # sum of steps (earlier runs included)
    entry = {"preset": preset, "recipe": dict(r), "steps": log, "total_seconds": total}
    for role, src in (("teacher", tea), ("student", stu)):
        for cfg in (Path(src + ".config.json"), Path(src).with_suffix(".config.json")):
            if cfg.is_file():
                shutil.copyfile(cfg, DATA / f"{preset}.{role}.config.json")
                break
    for role, pack in (("student", out_s), ("teacher", out_t)):
        mat = read_vrnm(pack)
        mat.meta["build"] = {"script": "demo/make_assets.py", **entry}
        write_vrnm(pack, mat)
        entry[f"{role}_test_l1"] = mat.meta.get("metrics", {}).get("test_l1")
        entry[f"{role}_bytes"] = pack.stat().st_size
    print(f"[{preset}] done in {total:.0f} s", flush=True)
    return entry


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--presets", default="leather,fabric,wood", help="comma-separated presets")
    ap.add_argument("--work", default=str(ROOT / "out" / "assets"), help="intermediate files")
    ap.add_argument("--jobs", type=int, default=3, help="presets trained at the same time")
    ap.add_argument("--force", action="store_true", help="overwrite intermediate files")
    a = ap.parse_args()
    presets = [p.strip() for p in a.presets.split(",") if p.strip()]
    DATA.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    with ThreadPoolExecutor(max(1, a.jobs)) as ex:
        entries = list(ex.map(lambda p: build(p, Path(a.work), a.force), presets))
    man_path = DATA / "manifest.json"
    man = json.loads(man_path.read_text()) if man_path.is_file() else {"packs": {}}
    man["packs"].update({e["preset"]: e for e in entries})
    man["last_run"] = {
        "presets": presets,
        "jobs": a.jobs,
        "wall_seconds": round(time.perf_counter() - t0, 1),
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    }
    man_path.write_text(json.dumps(man, indent=1) + "\n")
    print(f"all done in {man['last_run']['wall_seconds']:.0f} s -> {DATA}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
