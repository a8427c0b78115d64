"""Extreme training inputs through ``vrneural teach`` (``run_teach``): all-zero BTFs, HDR
peaks of 1e4, BTFs containing NaN, learning-rate schedules that reach their floor, 1 epoch.
Tiny sizes (8 x 8 texels, 3 x 3 directions, a 16-wide teacher) keep each case to seconds.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from vrneural.btf.dirs import direction_set
from vrneural.btf.format import BtfWriter, write_btf

RES, NDIRS = 8, 3


def btf_values(kind: str, seed: int = 0) -> np.ndarray:
    """``[L, V, RES, RES, 3]`` float32 values: ``zeros``, ``smooth`` (a Lambertian-like
    pattern, 0..0.3) or ``hdr`` (smooth plus a few texels at 1e4)."""
    d = direction_set(NDIRS)
    rng = np.random.default_rng(seed)
    if kind == "zeros":
        return np.zeros((len(d), len(d), RES, RES, 3), np.float32)
    alb = rng.uniform(0.2, 0.9, (RES, RES, 3)).astype(np.float32)
    v = alb[None, None] / np.pi * d[:, None, None, None, 2:3]  # albedo/pi * cos(theta_i)
    v = np.broadcast_to(v, (len(d), len(d), RES, RES, 3)).copy()
    if kind == "hdr":
        v[:, :, 2, 3] = 1e4
        v[0, 0, 5, 5] = 1e4
    return v


def write_kind(path: Path, kind: str) -> Path:
    d = direction_set(NDIRS)
    if kind == "nan":  # write_btf refuses NaN; a streamed (or damaged) file can still hold it
        w = BtfWriter(path, d, d, (RES, RES), {"name": "nan"})
        w.values[:] = np.float16(0.1)
        w.values[1, 2, 3, 4, 0] = np.float16(np.nan)
        return w.finalize()
    return write_btf(path, btf_values(kind), d, d, {"name": kind})


def teach(kind: str, **kw) -> dict:
    """Train a tiny teacher on a BTF of ``kind``; returns the checkpoint's history and the
    exported pack's shading of a few directions."""
    from vrneural.distill.config import TeachConfig
    from vrneural.distill.teach import run_teach
    from vrneural.formats.vrnm import read_vrnm
    from vrneural.material import material_forward

    with tempfile.TemporaryDirectory() as tmp:
        btf = write_kind(Path(tmp) / f"{kind}.btf", kind)
        args = dict(width=16, layers=3, channels=4, epochs=2, progress=False, max_test_slices=4)
        args.update(kw)
        cfg = TeachConfig(btf=str(btf), output=str(Path(tmp) / "t.pt"), **args)
        ck = run_teach(cfg)
        mat = read_vrnm(Path(tmp) / "t.vrnm")
        d = direction_set(NDIRS).astype(np.float32)
        y = material_forward(mat, d, d[::-1].copy(), np.full((len(d), 4, 2), 0.3, np.float32))
    hist = ck["history"]
    return {
        "epochs": len(hist),
        "train_loss": [float(h["train_loss"]) for h in hist],
        "test_l1": [float(h["test_l1"]) for h in hist],
        "lr": [float(h["lr"]) for h in hist],
        "pack_max": float(y.max()),
        "finite": bool(np.isfinite(y).all() and all(np.isfinite(h["train_loss"]) for h in hist)),
    }


def case_train_zeros(quick: bool) -> dict:
    r = teach("zeros", epochs=6, lr=5e-3)
    # a black BTF trains toward a black material: finite, the loss falls (a dead ReLU output
    # has zero gradient, so the loss may stop above 0 but never turns NaN)
    ok = r["finite"] and r["train_loss"][-1] < 0.5 * r["train_loss"][0]
    return {"ok": ok, **r}


def case_train_hdr(quick: bool) -> dict:
    out, ok = {}, True
    for space in ("linear", "log"):
        r = teach("hdr", space=space)
        ok &= r["finite"]
        out[f"{space}_final_loss"] = r["train_loss"][-1]
        out[f"{space}_pack_max"] = r["pack_max"]
    return {"ok": ok, **out, "note": "peaks of 1e4 in an otherwise <= 0.3 BTF"}


def case_train_nan(quick: bool) -> dict:
    teach("nan")
    return {"ok": False}


def case_train_lr_floor(quick: bool) -> dict:
    """lr 1e-3 -> floor 1e-5 in factors of 0.1 (absolute threshold 10, no patience: every epoch
    counts as a plateau): the lr reaches the floor, stays there, and training goes on finite."""
    r = teach(
        "smooth",
        epochs=5,
        lr=1e-3,
        lr_min=1e-5,
        lr_factor=0.1,
        lr_threshold=10.0,
        lr_threshold_mode="abs",
        lr_patience=0,
    )
    lr = r["lr"]
    ok = r["finite"] and abs(lr[-1] - 1e-5) < 1e-12 and min(lr) >= 1e-5 * (1 - 1e-9)
    return {"ok": bool(ok), "lr": lr, "train_loss": r["train_loss"]}


def case_train_one_epoch(quick: bool) -> dict:
    r = teach("smooth", epochs=1)
    return {"ok": r["finite"] and r["epochs"] == 1, "train_loss": r["train_loss"]}
