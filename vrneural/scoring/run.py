"""`vrneural eval`: which packs and BTF, their checks, the printed table and the outputs.

The BTF is ``--btf`` or the one every pack records (``meta.provenance.btf``). A pack whose record
names another BTF (another header or value sample SHA-256, or shape) is scored with a warning,
and without its held-out split, which belongs to the other BTF. The held-out split is rebuilt
from what the pack records (``split_seed``, ``test_fraction``) with the trainer's
:func:`vrneural.btf.identity.split_pairs`.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import textwrap
import time
from pathlib import Path

import numpy as np

from vrneural.btf.format import read_btf
from vrneural.btf.identity import btf_fingerprint, fingerprint_mismatch, split_pairs
from vrneural.config import config_dict
from vrneural.errors import VrnError, count
from vrneural.formats.vrnm import read_vrnm
from vrneural.interrupt import Stop
from vrneural.material import distilled, width_words
from vrneural.outputs import OutputDir, atomic_path, write_json
from vrneural.presentation import table
from vrneural.scoring.config import PRECISION_CHOICES, EvalConfig
from vrneural.scoring.score import pick_slices, score

#: the fields of a BTF record compared (not the name, which a renamed copy changes)
COMPARED = ("shape", "sha256", "values_sha256")  # the shape first: the plainest to name


def load_packs(paths: list[str]) -> list:
    """Read and validate each pack (one-line errors name the file); a pack named twice is an
    error."""
    if not paths:
        raise VrnError("no pack given: name one or more runtime packs (.vrnm)")
    seen: dict[Path, str] = {}
    for p in paths:
        key = Path(p).resolve()
        if key in seen:
            raise VrnError(f"{p}: named twice (as {seen[key]!r}); name each pack once")
        seen[key] = p
        if not Path(p).exists():
            raise VrnError(f"{p}: no such pack")
    return [read_vrnm(p) for p in paths]  # a directory or another format: one line each


def labels(paths: list[str]) -> list[str]:
    """Names that tell the packs apart: each path's shortest tail of components that no other
    pack shares (``student.vrnm``, or ``run1/student.vrnm`` beside ``run2/student.vrnm``)."""
    parts = [Path(p).resolve().parts for p in paths]
    out = []
    for i, pa in enumerate(parts):
        for k in range(1, len(pa) + 1):
            tail = pa[-k:]
            if all(q[-k:] != tail for j, q in enumerate(parts) if j != i):
                break
        out.append(str(Path(*tail)))
    return out


def _record(mat) -> dict:
    return (mat.meta.get("provenance") or {}).get("btf") or {}


def btf_path(cfg: EvalConfig, mats: list) -> str:
    """``--btf``, else the BTF path all packs record (one-line errors otherwise)."""
    if cfg.btf:
        return cfg.btf
    recorded = {}
    for p, mat in zip(cfg.packs, mats, strict=True):
        path = _record(mat).get("path")
        if not path:
            raise VrnError(f"{p}: the pack records no BTF; pass --btf BTF to score it against")
        recorded.setdefault(path, p)
    if len(recorded) > 1:
        (a, pa), (b, pb) = list(recorded.items())[:2]
        raise VrnError(
            f"the packs record different BTFs ({pa}: {a}; {pb}: {b}); score them against one "
            "with --btf, or one at a time"
        )
    path = next(iter(recorded))
    if not Path(path).exists():
        from vrneural.btf.identity import moved_btf

        found = moved_btf(_record(mats[0]), cfg.packs[0])  # a moved folder: the copy beside it
        if found is not None:
            return found
        raise VrnError(
            f"{cfg.packs[0]}: records BTF {path}, which does not exist (moved, or built on "
            f"another machine); pass --btf BTF{_recipe(mats[0])}"
        )
    return path


def _recipe(mat) -> str:
    """``" (the pack records how it was made: `vrneural btf synth ...`)"`` for a pack whose
    ``build`` entry (the bundled packs, ``demo/make_assets.py``) holds the BTF's command."""
    steps = (mat.meta.get("build") or {}).get("steps") or []
    cmd = next((s.get("command") for s in steps if s.get("step") == "btf synth"), None)
    if not isinstance(cmd, str):
        return ""
    words = [w for w in cmd.split() if w not in ("--force", "--no-progress")]
    if "-o" in words:  # the recorded output path is the missing one: let the user choose
        k = words.index("-o")
        words[k : k + 2] = ["-o", "BTF"]
    return f" (it was made by `{' '.join(words)}`)"


def held_out(pack: str, mat, fp: dict, btf, warnings: list[str]) -> list[int] | None:
    """The pack's held-out pair indices on ``btf`` (fingerprint ``fp``), None when the pack
    was trained on another BTF (a warning says so) or records no split."""
    rec = _record(mat)
    differs = fingerprint_mismatch(fp, rec, COMPARED)
    if differs:
        what = (
            f"shape {_shape(rec['shape'])}, not {_shape(fp['shape'])} (lights x views x "
            "height x width)"
            if differs == "shape"
            else f"{differs} differs from {btf.path}'s"
        )
        warnings.append(
            f"{pack}: was trained on another BTF ({what}): its scores are on a BTF it never "
            "saw, and it has no held-out split there"
        )
        return None
    prov = mat.meta.get("provenance") or {}
    seed, frac = prov.get("split_seed"), (prov.get("config") or {}).get("test_fraction")
    if not rec or not isinstance(seed, int) or not isinstance(frac, (int, float)):
        return None
    L, V = btf.shape[:2]
    return split_pairs(L, V, float(frac), seed)[1]


def _shape(s) -> str:
    return "x".join(map(str, s)) if isinstance(s, (list, tuple)) else str(s)


def trainer_test(mat, test: list[int] | None) -> list[int] | None:
    """The held-out pairs the trainer measured its test L1 on (``--max-test-slices``, 64 by
    default: that many evenly spaced ones), as :func:`vrneural.distill.evaluate.test_pairs`
    picks them; None without a split."""
    if test is None:
        return None
    cfg = (mat.meta.get("provenance") or {}).get("config") or {}
    m = cfg.get("max_test_slices")
    if not isinstance(m, int) or m <= 0 or len(test) <= m:
        return list(test)
    idx = np.round(np.linspace(0, len(test) - 1, m)).astype(int)
    return [test[i] for i in idx]


def label(mat, path: str) -> dict:
    """What the table says of a pack: name, method, MACs per texel, bytes."""
    method = (mat.meta.get("method") or "?") + width_words(mat)
    if mat.meta.get("method") in ("student", "single8") and distilled(mat) is False:
        method += " w/o distillation"
    return {
        "pack": str(path),
        "method": method,
        "arch": mat.arch,
        "macs_per_texel": float(mat.macs_per_texel),
        "weight_bytes": int(mat.weight_bytes),
        "texture_bytes": int(mat.texture_bytes),
    }


def evaluate(cfg: EvalConfig, progress: bool = True) -> dict:
    """Score ``cfg.packs``; print warnings; write ``cfg.out`` when set. Returns the results."""
    t0 = time.perf_counter()
    if isinstance(cfg.packs, (str, os.PathLike)):  # one pack given bare, from Python
        cfg = dataclasses.replace(cfg, packs=(str(cfg.packs),))
    if cfg.precision not in PRECISION_CHOICES:
        raise VrnError(
            f"--precision = {cfg.precision!r} is not allowed; choose {', '.join(PRECISION_CHOICES)}"
        )
    mats = load_packs([str(p) for p in cfg.packs])
    path = btf_path(cfg, mats)
    btf = read_btf(path)
    L, V, H, W = btf.shape
    pairs = pick_slices(cfg.slices, L * V, H * W)
    out = Path(cfg.out) if cfg.out else None
    if out is not None:
        OutputDir(out, "eval", force=cfg.force).check()
    fp = btf_fingerprint(btf)
    warnings: list[str] = []
    tests = [held_out(p, m, fp, btf, warnings) for p, m in zip(cfg.packs, mats, strict=True)]
    for w in warnings:
        print(f"warning: {w}", file=sys.stderr)
    precs = ["f32", "f16"] if cfg.precision == "both" else [cfg.precision]
    subs = [trainer_test(m, t) for m, t in zip(mats, tests, strict=True)]
    res = score(mats, btf, pairs, precs, tests, progress, subs)
    names = labels(list(cfg.packs))
    doc = {
        "command": "eval",
        "btf": {"path": str(btf.path), "shape": [L, V, H, W], "name": fp["name"]},
        "slices": res["slices"],
        "precisions": precs,
        "packs": [
            {**label(m, p), "name": n, "scores": s}
            for p, n, m, s in zip(cfg.packs, names, mats, res["scores"], strict=True)
        ],
        "warnings": warnings,
    }
    doc["seconds"] = time.perf_counter() - t0
    if out is not None:
        write_outputs(cfg, out, doc, mats, btf)
    return doc


#: what ``--out`` holds (besides the output marker)
OUT_FILES = ("results.json", "results.md", "slices.png", "config.json")


def write_outputs(cfg: EvalConfig, out: Path, doc: dict, mats: list, btf) -> None:
    """Write :data:`OUT_FILES`. Everything is computed first (the figure too); then the old
    output is replaced and the files written with Ctrl-C held off, so an interrupted eval
    leaves the old output or the whole new one, never a mix."""
    from vrneural.scoring.figure import slices_png

    png = slices_png(mats, [p["name"] for p in doc["packs"]], btf, cfg.precision)
    doc["files"] = [str(out / f) for f in OUT_FILES]
    md = markdown(doc) + "\n"
    config = {**config_dict(cfg), "btf_scored": doc["btf"]["path"]}
    with Stop() as stop, OutputDir(out, "eval", force=cfg.force) as od:
        od.open()
        write_json(out / "results.json", doc)
        for name, data in (("results.md", md.encode()), ("slices.png", png)):
            with atomic_path(out / name) as tmp:
                tmp.write_bytes(data)
        write_json(out / "config.json", config)
    if stop.flag:  # Ctrl-C came while writing: all was written, then stop as asked
        raise KeyboardInterrupt


def _f(v, fmt: str) -> str:
    return "-" if v is None else format(v, fmt)


def _trainer_l1(pack: dict) -> float | None:
    """The first precision's L1 on the trainer's ``--max-test-slices`` subset, where it
    differs from the L1 on all held-out slices (else None: nothing to explain)."""
    s = pack["scores"][0]
    sub = s.get("l1_trainer_test")
    return sub if sub is not None and sub != s["l1_held_out"] else None


def _held_out_note(doc: dict) -> str:
    """``", 160 held out"``: how many scored slices the held-out L1 rests on."""
    counts = {s["held_out_slices"] for p in doc["packs"] for s in p["scores"]}
    counts.discard(None)
    if not counts:
        return ", no held-out split known"
    if len(counts) == 1:
        return f", {counts.pop()} of them held out in training"
    return ", held-out counts differ by pack (results.json: held_out_slices)"


#: the table's legend (printed under it and in results.md)
LEGEND = (
    "L1, RMSE: linear BTF units, over texels and RGB; held-out / train: the slices the pack's "
    "training held out / trained on. rel. L1: L1 / the mean of the BTF slices scored. PSNR, "
    "SSIM: each slice displayed at its own exposure (its 99th percentile at 1, then "
    "x / (1 + x) and sRGB), averaged over slices. bytes: the pack's weights + textures (its "
    "file also holds meta). f16 rows: the runtime's half-precision path emulated, and its L1 "
    "change against f32."
)


def table_rows(doc: dict) -> list[list[str]]:
    """Header and one row per (pack, precision) of the results table."""
    rows = [
        ["pack", "method", "prec", "MACs/texel", "bytes", "L1", "held-out L1", "train L1",
         "rel. L1", "RMSE", "PSNR dB", "SSIM"]
    ]  # fmt: skip
    for p in doc["packs"]:
        for s in p["scores"]:
            prec = s["precision"]
            base = p["scores"][0]
            if s is not base and base["l1"]:  # f16 after f32: the change it costs
                prec += f" ({s['l1'] / base['l1'] - 1:+.2%})"
            rows.append(
                [
                    p["name"],
                    p["method"],
                    prec,
                    f"{p['macs_per_texel']:g}",
                    str(p["weight_bytes"] + p["texture_bytes"]),
                    _f(s["l1"], ".6f"),
                    _f(s["l1_held_out"], ".6f"),
                    _f(s["l1_train"], ".6f"),
                    _f(s["l1_relative"], ".1%"),
                    _f(s["rmse"], ".6f"),
                    _f(s["psnr_db"], ".2f"),
                    _f(s["ssim"], ".4f"),
                ]
            )
    return rows


def headline(doc: dict) -> str:
    b, sl = doc["btf"], doc["slices"]
    L, V, H, W = b["shape"]
    which = (
        f"all {sl['scored']} slices"
        if sl["scored"] == sl["of"]
        else f"{sl['scored']} of {sl['of']} slices, drawn at random (--slices all: every one)"
    )
    return (
        f"{count(len(doc['packs']), 'pack')} on {b['path']} ({L} lights x {V} views x "
        f"{H}x{W} texels), {which}{_held_out_note(doc)}"
    )


def text_table(doc: dict) -> str:
    rows = table_rows(doc)
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = ["  ".join(c.ljust(w) if i < 3 else c.rjust(w) for i, (c, w) in
                       enumerate(zip(r, widths, strict=True))) for r in rows]  # fmt: skip
    lines.insert(0, headline(doc))
    for p in doc["packs"]:
        s = p["scores"][0]
        worst = "; ".join(f"l{w['light']} v{w['view']} {w['angles']} {w['l1']:.4g}"
                          for w in s["worst"][:3])  # fmt: skip
        lines.append(f"worst slices of {p['name']} ({s['precision']}, L1): {worst}")
        sub = _trainer_l1(p)
        if sub is not None:
            lines.append(
                f"  the test L1 distill/export printed for {p['name']} is over the held-out "
                f"slices of --max-test-slices (64 by default); on those: {sub:.6f}"
            )
    lines += textwrap.wrap(LEGEND, 100)
    return "\n".join(lines)


def markdown(doc: dict) -> str:
    rows = table_rows(doc)
    md = [f"# vrneural eval: {doc['btf']['name']}", "", headline(doc) + ".", ""]
    md += table(rows[0], rows[1:])
    md += ["", LEGEND, ""]
    trainer = [
        f"{p['name']} {_trainer_l1(p):.6f}" for p in doc["packs"] if _trainer_l1(p) is not None
    ]
    if trainer:  # why the held-out L1 differs from the test L1 that distill/export printed
        md += [
            "The test L1 that `distill` and `export` print is measured on at most "
            "--max-test-slices (64) evenly spaced held-out slices, not all of them; on those "
            f"slices ({doc['precisions'][0]}): {', '.join(trainer)}.",
            "",
        ]
    md += [
        "## Worst slices (L1)",
        "",
    ]
    for p in doc["packs"]:
        for s in p["scores"]:
            worst = ", ".join(f"l{w['light']} v{w['view']} ({w['angles']}) {w['l1']:.4g}"
                              for w in s["worst"])  # fmt: skip
            md.append(f"- {p['name']} ({s['precision']}): {worst}")
    if doc["warnings"]:  # their own section, not bullets of the worst slices
        md += ["", "## Warnings", "", *[f"- {w}" for w in doc["warnings"]]]
    md += ["", f"Run time {doc['seconds']:.1f} s. Figure: slices.png. Raw records: results.json."]
    return "\n".join(md)
