"""Frames of two `vrneural run` outputs against each other (their ``--save-frames`` EXRs, read
with OpenImageIO): ``python docs/results/h200/compare_frames.py A_DIR B_DIR [OUT.json]``. Per
common file: values that differ (count and share), the largest difference, and the pixels that
differ in any channel."""

import json
import sys
from pathlib import Path

import numpy as np
import OpenImageIO as oiio  # noqa: N813

a_dir, b_dir = Path(sys.argv[1]), Path(sys.argv[2])
rows = {}
for fa in sorted(a_dir.glob("*.exr")):
    fb = b_dir / fa.name
    if not fb.exists():
        continue
    a, b = (oiio.ImageBuf(str(f)).get_pixels(oiio.FLOAT) for f in (fa, fb))
    d = np.abs(a - b)
    px = np.count_nonzero(d.max(axis=-1))
    rows[fa.name] = {"values_differing": int(np.count_nonzero(d)), "share": float(np.mean(d > 0)),
                     "max_abs": float(d.max()), "pixels_differing": int(px),
                     "pixels": int(d.shape[0] * d.shape[1])}  # fmt: skip
    print(f"{fa.name}: {px} of {d.shape[0] * d.shape[1]} pixels differ, max {d.max():.4g}")
if len(sys.argv) > 3:
    Path(sys.argv[3]).write_text(json.dumps(rows, indent=1))
