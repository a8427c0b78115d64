"""The glossy fur's fits trained on its 64-spp render, judged against a 256-spp render of the
same material (issue #35: how much of each L1 is Monte Carlo noise in the target).

    python fur-v11-cross-spp.py FUR64.btf FUR256.btf GAUGE_DIR SEED_DIRS... -o OUT.json

GAUGE_DIR: the 64-spp gauge's `fur.btf/` folder (teacher.pt for the split, lafortune.npz,
neumip_neural.pt); SEED_DIRS: folders holding seeds 1-4's neumip_neural.pt. The loop pile's
(berber-cross-spp.json) came from the same script with its 144-spp render, `--hi-spp 144`
(the cleaner render's sample count, which names its keys in the JSON). Prints and writes
the whole-BTF L1 of the Lafortune fit and of NeuMIP with neural offsets (each seed) against
both renders, their ratio, and the L1 between the two renders themselves.
"""

import argparse
import json
import statistics
import sys
from pathlib import Path

import numpy as np
import torch

from vrneural.btf.format import read_btf
from vrneural.distill.checkpoint import load_checkpoint, model_from_checkpoint
from vrneural.distill.data import SliceData
from vrneural.distill.evaluate import mean_l1
from vrneural.distill.lafortune import predict_lafortune

p = argparse.ArgumentParser()
p.add_argument("fur64")
p.add_argument("fur256")
p.add_argument("--hi-spp", default="256", help="the cleaner render's samples per pixel")
p.add_argument("gauge")
p.add_argument("seeds", nargs="*")
p.add_argument("-o", "--out", required=True)
a = p.parse_args()
g = Path(a.gauge)
test = load_checkpoint(g / "teacher.pt")["split"]["test"]
hi = a.hi_spp
btfs = {"64": read_btf(a.fur64), hi: read_btf(a.fur256)}
datas = {k: SliceData(b, test) for k, b in btfs.items()}
every = list(range(len(datas["64"].train) + len(datas["64"].test)))
v64, v_hi = (np.asarray(btfs[k].values, np.float32) for k in ("64", hi))
between = float(np.abs(v64 - v_hi).mean())
mean_value = float(v_hi.mean())
with np.load(g / "lafortune.npz", allow_pickle=False) as z:
    params = torch.from_numpy(z["params"])
out = {"between_renders_l1": between, "mean_value": mean_value, "methods": {}}


def laf_l1(data) -> float:
    L = data.values.shape[0]
    H, W = data.res
    flat = data.values.reshape(L * data.n_view, H * W, 3)
    e = [float((predict_lafortune(params, *data.dirs(q)) - flat[q].float()).abs().mean())
         for q in every]  # fmt: skip
    return sum(e) / len(e)


out["methods"]["lafortune"] = {k: [laf_l1(d)] for k, d in datas.items()}
packs = [g / "neumip_neural.pt", *(Path(s) / "neumip_neural.pt" for s in a.seeds)]
models = [model_from_checkpoint(load_checkpoint(pth)) for pth in packs]
out["methods"]["neumip_neural"] = {k: [mean_l1(m, d, every) for m in models]
                                   for k, d in datas.items()}  # fmt: skip
for k in ("64", hi):
    laf = out["methods"]["lafortune"][k][0]
    nm = out["methods"]["neumip_neural"][k]
    out[f"ratio_{k}"] = [laf / x for x in nm]
    print(f"judged against the {k}-spp render: Lafortune {laf:.6f}, NeuMIP+offset "
          + ", ".join(f"{x:.6f}" for x in nm)
          + f" -> ratio {statistics.fmean(out[f'ratio_{k}']):.3f} "
          f"({min(out[f'ratio_{k}']):.3f}-{max(out[f'ratio_{k}']):.3f} by seed)")  # fmt: skip
print(f"L1 between the two renders {between:.6f} (mean value {mean_value:.4f})")
Path(a.out).write_text(json.dumps(out, indent=1))
sys.exit(0)
