"""The Lafortune baseline of `bench quality` (diffuse + 4 lobes per texel, Levenberg-Marquardt)
on its own: fitted to a BTF's training slices under a teacher's split, scored on the whole BTF
and the held-out slices exactly as the bench scores it, without training the bench's networks
(issue #35: the ratio Lafortune / NeuMIP on a BTF whose networks were trained one by one)::

    python scripts/research/lafortune_fit.py PRESET.btf PRESET/teacher.pt OUT.json [--iters 20]

Writes ``OUT.json`` (whole and held-out L1, fit seconds) and the fit beside it (``OUT.npz``,
reused by a second run with the same BTF, split and iterations).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from types import SimpleNamespace


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("btf", type=Path)
    ap.add_argument("teacher", type=Path, help="its split (held-out pairs) is the bench's")
    ap.add_argument("out", type=Path)
    ap.add_argument("--iters", type=int, default=20, help="LM iterations (the gauges' 20)")
    a = ap.parse_args()

    import torch

    from vrneural.bench.quality_lafortune import lafortune
    from vrneural.btf.format import read_btf
    from vrneural.distill.checkpoint import load_checkpoint
    from vrneural.distill.data import SliceData

    torch.set_num_threads(1)
    tck = load_checkpoint(a.teacher)
    data = SliceData(read_btf(a.btf), tck["split"]["test"])
    every = list(range(len(data.train) + len(data.test)))
    cfg = SimpleNamespace(lafortune_iters=a.iters, resume=True)
    rec, reused = lafortune(data, every, [], cfg, {"slices": {}}, a.out.with_suffix(".npz"),
                            tck["btf"]["sha256"])  # fmt: skip
    doc = {k: rec[k] for k in ("whole_l1", "test_l1", "train_seconds")}
    doc.update(btf=str(a.btf), teacher=str(a.teacher), iters=a.iters, reused=reused)
    a.out.write_text(json.dumps(doc, indent=1))
    print(json.dumps(doc))


if __name__ == "__main__":
    main()
