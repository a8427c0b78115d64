"""The Lafortune baseline of `bench quality` (per-texel lobes fitted to the training slices,
the fit cached beside the networks), and the slices the bench shows."""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from vrneural.bench.quality_parallax import bin_pairs
from vrneural.outputs import atomic_path


def slice_pairs(data) -> list[int]:
    """Two held-out pairs to show: the brightest (highlight) and the median one."""
    means = sorted((float(data.target(p, shard=False).mean()), p) for p in data.test)
    return [means[-1][1], means[len(means) // 2][1]]


def lafortune(data, every, slices, cfg, out: dict, path: Path, btf_sha: str):
    """Fit (or, with --resume, reload a matching fit from ``path``) and evaluate Lafortune;
    returns the record and whether the fit was reloaded."""
    import torch

    from vrneural.distill.lafortune import N_PARAMS, fit_lafortune, predict_lafortune

    L = data.values.shape[0]
    H, W = data.res
    flat = data.values.reshape(L * data.n_view, H * W, 3)
    key = json.dumps({"btf": btf_sha, "train": list(data.train), "iters": cfg.lafortune_iters})
    params, reused = None, False
    if cfg.resume and path.exists():
        try:
            with np.load(path, allow_pickle=False) as z:
                if str(z["key"]) == key:
                    params, seconds = torch.from_numpy(z["params"]), float(z["seconds"])
                    reused = True
        except (OSError, ValueError, KeyError):
            params = None
    if params is None:
        t0 = time.perf_counter()
        wi = torch.stack([data.dirs(p)[0] for p in data.train])
        wo = torch.stack([data.dirs(p)[1] for p in data.train])
        y = flat[data.train].float().transpose(0, 1)  # [T, M, 3]
        params = fit_lafortune(y, wi, wo, iters=cfg.lafortune_iters)
        seconds = time.perf_counter() - t0
        with atomic_path(path) as tmp, open(tmp, "wb") as f:
            np.savez(f, key=np.array(key), params=params.numpy(), seconds=np.array(seconds))

    def l1(pairs):
        e = [
            float((predict_lafortune(params, *data.dirs(p)) - flat[p].float()).abs().mean())
            for p in pairs
        ]
        return sum(e) / len(e)

    out["slices"]["lafortune"] = [
        predict_lafortune(params, *data.dirs(p)).reshape(H, W, 3).numpy() for p in slices
    ]
    whole, test = l1(every), l1(data.test)
    bins = [l1(ps) if ps else None for ps in bin_pairs(data, every)]
    return {
        "view_bins_l1": bins,
        "whole_l1": whole,
        "test_l1": test,
        "whole_l1_seeds": [whole],  # deterministic: one fit
        "test_l1_seeds": [test],
        "seeds": [],
        "train_seconds": seconds,
        "epochs": None,
        "curve": [],
        "weight_bytes": 0,
        "texture_bytes": 4 * N_PARAMS * H * W,
        "storage_bytes": 4 * N_PARAMS * H * W,
        "macs_per_texel": None,
    }, reused
