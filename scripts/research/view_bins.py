"""Research script (docs/quality-research.md, "NeuMIP's neural offset module"): whole-BTF L1
and L1 by view-angle bin of trained checkpoints, with ``bench quality``'s own definitions
(``mean_l1`` of vrneural.distill.evaluate, ``parallax_record`` of
vrneural.bench.quality_parallax), without the bench's PSNR/SSIM pass (which takes most of
its evaluation time). Seconds per network. The JSON holds one record per checkpoint
(``whole_l1``, ``view_bins_l1``, ``view_bin_pairs``, ``macs_per_texel``,
``fetches_per_texel``, ``parallax``).

    .venv/bin/python scripts/research/view_bins.py BTF OUT.json CHECKPOINT...
"""

from __future__ import annotations

import argparse
import json

import torch

from vrneural.bench.quality_parallax import parallax_record
from vrneural.btf.format import read_btf
from vrneural.distill.checkpoint import load_checkpoint, model_from_checkpoint
from vrneural.distill.data import SliceData
from vrneural.distill.evaluate import mean_l1


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("btf")
    ap.add_argument("out")
    ap.add_argument("checkpoints", nargs="+")
    args = ap.parse_args()
    torch.set_num_threads(1)
    btf = read_btf(args.btf)
    out, data, every = {}, None, []
    for path in args.checkpoints:
        ck = load_checkpoint(path)
        if data is None:  # every checkpoint of a bench shares the teacher's split
            data = SliceData(btf, ck["split"]["test"])
            every = list(range(len(data.train) + len(data.test)))
        model = model_from_checkpoint(ck, path)
        mat = model.to_material()
        rec = parallax_record([model], mat, data, every)
        rec |= {"whole_l1": mean_l1(model, data, every), "macs_per_texel": mat.macs_per_texel}
        out[path] = rec
        bins = ", ".join(f"{x:.5f}" for x in rec["view_bins_l1"] if x is not None)
        print(f"{path}: whole {rec['whole_l1']:.5f}; bins {bins}", flush=True)
    with open(args.out, "w") as f:
        json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
