"""Research script (docs/quality-research.md, "Beyond the measured directions"): the extension
beyond a BTF's direction range against training on directions out to 89 degrees.

For each preset: BTF A with the usual quasi-uniform directions to 75 degrees, BTF B with the
same solid-angle density to 89 degrees; a teacher and a student on each; then the students' L1
on B's BTF by the larger of theta_i and theta_o, and the terminator step on the sphere in the
three modes. About 15 minutes on two cores.

    .venv/bin/python scripts/research/grazing_directions.py WORKDIR [--presets leather,wood]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

BINS = ((0, 60), (60, 75), (75, 82), (82, 90))


def spiral(n: int, theta_max: float) -> np.ndarray:
    """``btf.dirs.direction_set``'s spiral over [0, theta_max] degrees."""
    from vrneural.btf.dirs import spherical

    cos_max = np.cos(np.radians(theta_max))
    cos_t = 1.0 - (1.0 - cos_max) * (np.arange(n) + 0.5) / n
    return spherical(np.arccos(cos_t), np.pi * (3.0 - np.sqrt(5.0)) * np.arange(n))


def make_btf(path: Path, preset: str, n: int, theta_max: float) -> None:
    import vrneural.btf.synth as synth

    synth.direction_set = lambda k: spiral(k, theta_max)
    synth.synthesize(synth.BtfConfig(preset=preset, res=32, dirs=n, seed=0), path, progress=False)


def vrn(*args) -> None:
    subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys; from vrneural.cli import main; sys.exit(main(sys.argv[1:]))",
            *map(str, args),
        ],
        check=True,
    )


def score(pack: Path, btf) -> dict:
    from vrneural.formats.vrnm import read_vrnm
    from vrneural.scoring.score import predict_slice, texel_blocks

    mat = read_vrnm(pack)
    L, V, H, W = btf.shape
    uv = texel_blocks(H, W)
    th = [np.degrees(np.arccos(np.clip(d[:, 2], -1, 1))) for d in (btf.light_dirs, btf.view_dirs)]
    acc = {b: [] for b in BINS}
    for li in range(L):
        for vi in range(V):
            m = max(th[0][li], th[1][vi])
            y = predict_slice(mat, btf.light_dirs[li], btf.view_dirs[vi], uv, H, W, "f32")
            acc[next(b for b in BINS if b[0] <= m < b[1] or b[1] == 90)].append(
                float(np.abs(y - btf.slice(li, vi)).mean())
            )
    return {f"{a}-{b}": float(np.mean(v)) for (a, b), v in acc.items()} | {
        "dir_range": mat.dir_range
    }


def main() -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
    from extremes import terminator as term  # the terminator check (tests/extremes)

    from vrneural.btf import read_btf
    from vrneural.formats.vrnm import read_vrnm
    from vrneural.runtime.scene import MaterialDesc

    ap = argparse.ArgumentParser()
    ap.add_argument("work", type=Path)
    ap.add_argument("--presets", default="leather,wood")
    a = ap.parse_args()
    out = {}
    for preset in a.presets.split(","):
        d = a.work / preset
        d.mkdir(parents=True, exist_ok=True)
        for v, n, tmax in (("a", 24, 75.0), ("b", 32, 89.0)):
            if not (d / f"{v}.btf").exists():
                make_btf(d / f"{v}.btf", preset, n, tmax)
            if not (d / f"{v}.student.vrnm").exists():
                vrn(
                    "teach",
                    d / f"{v}.btf",
                    "-o",
                    d / f"{v}.teacher.pt",
                    "--epochs",
                    8,
                    "--seed",
                    0,
                    "--no-progress",
                    "--force",
                )
                vrn(
                    "distill",
                    d / f"{v}.teacher.pt",
                    "-o",
                    d / f"{v}.student.pt",
                    "--epochs",
                    12,
                    "--seed",
                    0,
                    "--no-progress",
                    "--force",
                )
        btf_b = read_btf(d / "b.btf")
        for v in ("a", "b"):
            rec = score(d / f"{v}.student.vrnm", btf_b)
            desc = MaterialDesc(
                "neural",
                read_vrnm(d / f"{v}.student.vrnm"),
                v,
                1.0,
                reference=read_vrnm(d / f"{v}.teacher.vrnm"),
            )
            for mode in ("texture", "screen", "reference"):
                rec[f"step_{mode}"] = term.row_steps(term.render_sphere(desc, mode))["max"]
            out[f"{preset}/{v}"] = rec
            print(preset, v, json.dumps(rec), flush=True)
    (a.work / "results.json").write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
