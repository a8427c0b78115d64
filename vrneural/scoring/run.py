"""`vrneural eval`: which packs and BTF, their checks, the printed table and the outputs.

The BTF is ``--btf`` or the one every pack records (``meta.provenance.btf``). A pack whose record
names another BTF (another header or value sample SHA-256, or shape) is scored with a warning,
and without its held-out split, which belongs to the other BTF. The held-out split is rebuilt
from what the pack records (``split_seed``, ``test_fraction``) with the trainer's
:func:`vrneural.btf.identity.split_pairs`.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from vrneural.errors import VrnError, count
from vrneural.scoring.score import EvalConfig, pick_slices, precisions, score

#: the fields of a BTF record compared (not the name, which a renamed copy changes)
COMPARED = ("sha256", "values_sha256", "shape")


def load_packs(paths: list[str]) -> list:
    """Read and validate each pack (one-line errors name the file); a pack named twice is an
    error."""
    from vrneural.formats.vrnm import read_vrnm

    if not paths:
        raise VrnError("no pack given: name one or more runtime packs (.vrnm)")
    seen: dict[Path, str] = {}
    for p in paths:
        key = Path(p).resolve()
        if key in seen:
            raise VrnError(f"{p}: named twice (as {seen[key]!r}); name each pack once")
        seen[key] = p
        if not Path(p).is_file():
            raise VrnError(f"{p}: no such pack" if not Path(p).exists() else f"{p}: not a file")
    return [read_vrnm(p) for p in paths]


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
    words = cmd.split()
    if "-o" in words:  # the recorded output path is the missing one: let the user choose
        k = words.index("-o")
        words[k : k + 2] = ["-o", "BTF"]
    return f" (it was made by `{' '.join(words)}`)"


def held_out(pack: str, mat, fp: dict, btf, warnings: list[str]) -> list[int] | None:
    """The pack's held-out pair indices on ``btf`` (fingerprint ``fp``), None when the pack
    was trained on another BTF (a warning says so) or records no split."""
    from vrneural.btf.identity import split_pairs

    rec = _record(mat)
    differs = next((k for k in COMPARED if k in rec and rec[k] != fp[k]), None)
    if differs:
        warnings.append(
            f"{pack}: was trained on another BTF ({differs} differs from {btf.path}'s): its "
            "scores are on a BTF it never saw, and it has no held-out split there"
        )
        return None
    prov = mat.meta.get("provenance") or {}
    seed, frac = prov.get("split_seed"), (prov.get("config") or {}).get("test_fraction")
    if not rec or not isinstance(seed, int) or not isinstance(frac, (int, float)):
        return None
    L, V = btf.shape[:2]
    return split_pairs(L, V, float(frac), seed)[1]


def label(mat, path: str) -> dict:
    """What the table says of a pack: name, method, MACs per texel, bytes."""
    method = mat.meta.get("method") or "?"
    cfg = (mat.meta.get("provenance") or {}).get("config") or {}
    if method == "student" and cfg.get("distill") is False:
        method = "student w/o distillation"
    return {
        "pack": str(path),
        "name": Path(path).name,
        "method": method,
        "arch": mat.arch,
        "macs_per_texel": float(mat.macs_per_texel),
        "weight_bytes": int(mat.weight_bytes),
        "texture_bytes": int(mat.texture_bytes),
    }


def evaluate(cfg: EvalConfig, progress: bool = True) -> dict:
    """Score ``cfg.packs``; print warnings; write ``cfg.out`` when set. Returns the results."""
    from vrneural.btf.format import read_btf
    from vrneural.btf.identity import btf_fingerprint
    from vrneural.formats.atomic import check_output_dir

    t0 = time.perf_counter()
    mats = load_packs(cfg.packs)
    path = btf_path(cfg, mats)
    btf = read_btf(path)
    L, V, H, W = btf.shape
    pairs = pick_slices(cfg.slices, L * V, H * W)
    out = Path(cfg.out) if cfg.out else None
    if out is not None:
        check_output_dir(out, cfg.force, "eval")
    fp = btf_fingerprint(btf)
    warnings: list[str] = []
    tests = [held_out(p, m, fp, btf, warnings) for p, m in zip(cfg.packs, mats, strict=True)]
    for w in warnings:
        print(f"warning: {w}", file=sys.stderr)
    precs = precisions(cfg.precision)
    res = score(mats, btf, pairs, precs, tests, progress)
    doc = {
        "command": "eval",
        "btf": {"path": str(btf.path), "shape": [L, V, H, W], "name": fp["name"]},
        "slices": res["slices"],
        "precisions": precs,
        "packs": [
            {**label(m, p), "scores": s}
            for p, m, s in zip(cfg.packs, mats, res["scores"], strict=True)
        ],
        "warnings": warnings,
    }
    doc["seconds"] = time.perf_counter() - t0
    if out is not None:
        write_outputs(cfg, out, doc, mats, btf)
    return doc


def write_outputs(cfg: EvalConfig, out: Path, doc: dict, mats: list, btf) -> None:
    from vrneural.config import write_config
    from vrneural.formats.atomic import atomic_path, make_output_dir, seal_output_dir, write_json
    from vrneural.scoring.figure import slices_figure

    make_output_dir(out, "eval")
    files = [out / "results.json", out / "results.md", out / "slices.png"]
    doc["files"] = [str(f) for f in files]
    write_json(files[0], doc)
    with atomic_path(files[1]) as tmp:
        tmp.write_text(markdown(doc) + "\n")
    slices_figure(mats, [Path(p).name for p in cfg.packs], btf, files[2], cfg.precision)
    write_config(out, cfg)
    seal_output_dir(out, "eval")


def _f(v, fmt: str) -> str:
    return "-" if v is None else format(v, fmt)


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
                    _f(s["l1"], ".4g"),
                    _f(s["l1_held_out"], ".4g"),
                    _f(s["l1_train"], ".4g"),
                    _f(s["l1_relative"], ".1%"),
                    _f(s["rmse"], ".4g"),
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
        f"{H}x{W} texels), {which}"
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
    return "\n".join(lines)


def markdown(doc: dict) -> str:
    rows = table_rows(doc)
    md = [f"# vrneural eval: {doc['btf']['name']}", "", headline(doc) + ".", ""]
    md += ["| " + " | ".join(r) + " |" for r in rows[:1]]
    md += ["|" + "---|" * len(rows[0])]
    md += ["| " + " | ".join(r) + " |" for r in rows[1:]]
    md += [
        "",
        "L1, RMSE: linear BTF units, over texels and RGB (held-out / train: the split the pack "
        "records). rel. L1: L1 / the BTF's mean. PSNR, SSIM: each slice displayed at its own "
        "exposure (its 99th percentile at 1, then x / (1 + x) and sRGB), averaged over slices. "
        "bytes: weights + textures of the pack. f16 rows: the runtime's half-precision path "
        "emulated, and its L1 change against f32.",
        "",
        "## Worst slices (L1)",
        "",
    ]
    for p in doc["packs"]:
        for s in p["scores"]:
            worst = ", ".join(f"l{w['light']} v{w['view']} ({w['angles']}) {w['l1']:.4g}"
                              for w in s["worst"])  # fmt: skip
            md.append(f"- {p['name']} ({s['precision']}): {worst}")
    md += [f"- warning: {w}" for w in doc["warnings"]]
    md += ["", f"Run time {doc['seconds']:.1f} s. Figure: slices.png. Raw records: results.json."]
    return "\n".join(md)
