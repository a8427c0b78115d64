"""Steady-state numbers of `vrneural run` outputs: ``python docs/results/h200/steady_state.py
OUT.json LABEL=RUN_DIR [LABEL=RUN_DIR ...]``. Per run, over frames 100 onwards (the GPU's clocks
settle over the first dozen frames after a pause; every run here had 300 frames of warm-up in
the same process sequence before it): the wall time per frame (median, mean, p95), the passes'
GPU timestamps (median) and the main thread's host CPU (median). Labels that repeat (``new=a
new=b``) are rounds of one configuration: the median over their medians is kept beside each."""

import json
import sys
from pathlib import Path

import numpy as np

FIRST = 100
out, pairs = Path(sys.argv[1]), [a.split("=", 1) for a in sys.argv[2:]]
runs: dict = {}
for label, d in pairs:
    pf = json.loads((Path(d) / "summary.json").read_text())["per_frame"]
    w = np.array(pf["wall_ms"][FIRST:])
    rec = {
        "dir": Path(d).name,
        "frames": len(pf["wall_ms"]),
        "wall_ms": {"median": float(np.median(w)), "mean": float(w.mean()),
                    "p95": float(np.percentile(w, 95))},
        "gpu_ms": {k: float(np.median(v[FIRST:])) for k, v in pf["gpu_ms"].items()},
    }  # fmt: skip
    if "host_cpu_ms" in pf:
        rec["host_cpu_ms"] = float(np.median(pf["host_cpu_ms"][FIRST:]))
    runs.setdefault(label, []).append(rec)
doc = {}
for label, rs in runs.items():
    med = float(np.median([r["wall_ms"]["median"] for r in rs]))
    doc[label] = {"wall_ms_median": med, "fps": 1e3 / med, "rounds": rs}
    print(f"{label:24s} {med:6.2f} ms/frame ({1e3 / med:5.0f} FPS) over {len(rs)} round(s): "
          + ", ".join(f"{r['wall_ms']['median']:.2f}" for r in rs)
          + "; GPU " + ", ".join(f"{k} {v:.2f}" for k, v in rs[0]["gpu_ms"].items()))  # fmt: skip
out.write_text(json.dumps({"first_frame": FIRST, "runs": doc}, indent=1))
