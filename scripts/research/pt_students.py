"""Score the students of a multi-seed run against NeuMIP and the two ablations (issue #35).

``bench quality --repeats 5`` trains and scores every method of the table, the Lafortune fit
included (35 minutes of its own on the mosaic). The students' targets need only the four
networks, so a run may train them with ``vrneural teach`` / ``vrneural distill`` (the bench's
settings: ``--max-test-slices 0 --parallax off``, teacher 48 epochs, networks 50) into

    ROOT/PRESET.btf                 the BTF
    ROOT/PRESET/sS/METHOD.vrnm      METHOD in student, neumip, single8, student_nodistill

and score them here with ``vrneural eval`` (its whole-BTF L1 is the bench's to 1e-11). With
``--suffix ws`` it scores the packs ``METHOD_ws.vrnm`` instead (another recipe of the three
narrow networks, e.g. ``--wide-start 16`` as ``bench quality --wide-start 16`` trains them;
NeuMIP is the plain ``neumip.vrnm``, as the bench never widens it). Writes
``OUT.json`` and ``OUT.md``: the L1 of every network and seed, the means, and the bench's three
verdicts (student within 10% of NeuMIP on the means; below the single-level net and below the
no-distillation student, on the means and seed pair by seed pair), and on how many presets
each target is met. ``--add`` scores a few presets into an existing OUT.json, keeping the
others, and whatever OUT.md has above its table::

    python scripts/research/pt_students.py ROOT --presets bark,mosaic,fur -o OUT
    python scripts/research/pt_students.py ROOT2 --presets weave --add -o OUT
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

METHODS = ("student", "neumip", "single8", "student_nodistill")
TABLE_HEAD = (
    "| preset | student | NeuMIP | single-level 8 | no distillation | student / NeuMIP "
    "(by seed) | student / single8 (pairs below) | student / no-distill (pairs below) |"
)


def stems(suffix: str = "") -> dict[str, str]:
    """The pack stem of each method: ``METHOD`` or, with a suffix, ``METHOD_SUFFIX`` for the
    three narrow networks (NeuMIP's stays plain)."""
    return {m: f"{m}_{suffix}" if suffix and m != "neumip" else m for m in METHODS}


def score(root: Path, preset: str, suffix: str = "") -> dict:
    """L1 (whole BTF, f32) of every pack of ``preset`` found, by method, in seed order."""
    method = {v: k for k, v in stems(suffix).items()}
    packs = sorted((root / preset).glob("s*/*.vrnm"))
    packs = [p for p in packs if p.stem in method]
    if not packs:
        sys.exit(f"{root / preset}: no packs s*/{{{','.join(method)}}}.vrnm")
    cmd = ["vrneural", "eval", *map(str, packs), "--btf", str(root / f"{preset}.btf")]
    r = subprocess.run([*cmd, "--json", "--quiet"], capture_output=True, text=True, check=True)
    doc = json.loads(r.stdout)
    out: dict = {m: {} for m in METHODS}
    for p, rec in zip(packs, doc["packs"], strict=True):
        out[method[p.stem]][int(p.parent.name[1:])] = rec["scores"][0]["l1"]
    return {m: dict(sorted(v.items())) for m, v in out.items() if v}


def _record(l1s) -> dict:
    """A bench method record (``vrneural.bench.quality_report``'s input) of these L1s."""
    return {"whole_l1": statistics.fmean(l1s), "whole_l1_seeds": list(l1s)}


def verdicts(l1: dict) -> dict:
    """The bench's three student targets (``quality_report.targets``, on the seed means) and
    its seed pairs (``quality_report.seed_pairs``, over the seeds both networks have)."""
    from vrneural.bench.quality_report import TARGETS, seed_pairs, targets

    met = targets({m: _record(v.values()) for m, v in l1.items()})
    name = {base: t for t, (base, _) in TARGETS.items()}
    mean = {m: statistics.fmean(v.values()) for m, v in l1.items()}
    out: dict = {"mean": mean, "seeds": {m: list(v) for m, v in l1.items()}}
    if "neumip" in mean:
        out["student_over_neumip"] = mean["student"] / mean["neumip"]
        out["student_over_neumip_by_seed"] = [
            l1["student"][s] / l1["neumip"][s] for s in l1["student"] if s in l1["neumip"]
        ]
        out["within_10pct_of_neumip"] = met[name["neumip"]]
    for base in ("single8", "student_nodistill"):
        if base not in mean:
            continue
        both = [s for s in l1["student"] if s in l1[base]]
        pairs = seed_pairs({k: _record([l1[k][s] for s in both]) for k in ("student", base)})
        out[f"student_over_{base}"] = mean["student"] / mean[base]
        out[f"below_{base}"] = met[name[base]]
        out[f"below_{base}_pairs"] = list(pairs[base])
    return out


def _cell(v: dict, k: str) -> str:
    """A method's mean L1 and its seed count, or '-'."""
    return f"{v['mean'][k]:.5f} ({len(v['seeds'][k])})" if k in v["mean"] else "-"


def _ratio(v: dict, base: str) -> str:
    """The student over ``base`` on the means, and the seed pairs where it is below."""
    if f"student_over_{base}" not in v:
        return "-"
    a, n = v[f"below_{base}_pairs"]
    return f"{v[f'student_over_{base}']:.3f} ({a} of {n})"


def report(res: dict) -> str:
    lines = [TABLE_HEAD, "|---|---|---|---|---|---|---|---|"]
    for p, v in res.items():
        by = v.get("student_over_neumip_by_seed", [])
        rng = f" ({min(by):.2f}-{max(by):.2f})" if by else ""
        son = f"{v['student_over_neumip']:.3f}{rng}" if "student_over_neumip" in v else "-"
        cells = [_cell(v, k) for k in METHODS]
        lines.append(
            f"| {p} | {' | '.join(cells)} | {son} | {_ratio(v, 'single8')} | "
            f"{_ratio(v, 'student_nodistill')} |"
        )
    note = "Means of the whole-BTF L1 over the seeds (their count in brackets).\n"
    return "\n".join(lines) + "\n\n" + note + tally(res)


def tally(res: dict) -> str:
    """On how many presets each of the three targets is met (on the seed means)."""
    parts = []
    for key, what in (
        ("within_10pct_of_neumip", "within 10% of NeuMIP"),
        ("below_single8", "below the single-level net"),
        ("below_student_nodistill", "below the no-distillation student"),
    ):
        had = [p for p, v in res.items() if key in v]
        if had:
            misses = [p for p in had if not res[p][key]]
            miss = f" (not {', '.join(misses)})" if misses else ""
            parts.append(f"{what} on {len(had) - len(misses)} of {len(had)}{miss}")
    return f"\nThe student is {'; '.join(parts)}.\n" if parts else ""


def preamble(md: str) -> str:
    """``--add``: whatever an earlier OUT.md has before its table (an introduction written by
    hand), kept as it is."""
    at = md.find(TABLE_HEAD)
    return md[:at] if at > 0 else ""


def merge(old: dict, new: dict) -> dict:
    """``--add``: the presets of an earlier result file, those scored again replaced in place,
    new ones after them."""
    return {p: new.get(p, v) for p, v in old.items()} | new


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("root", type=Path)
    ap.add_argument("--presets", default="bark,mosaic,fur")
    ap.add_argument("--suffix", default="", help="score METHOD_SUFFIX.vrnm (NeuMIP: neumip.vrnm)")
    ap.add_argument("-o", "--out", type=Path, required=True, help="OUT.json and OUT.md")
    ap.add_argument(
        "--add",
        action="store_true",
        help="keep the other presets of an existing OUT.json (those scored here replace theirs)",
    )
    a = ap.parse_args()
    res = {}
    for p in a.presets.split(","):
        l1 = score(a.root, p, a.suffix)
        res[p] = verdicts(l1) | {
            "l1": {m: {str(s): x for s, x in v.items()} for m, v in l1.items()}
        }
        print(p, json.dumps({k: v for k, v in res[p].items() if k != "l1"}, indent=1), flush=True)
    out_json, out_md = a.out.with_suffix(".json"), a.out.with_suffix(".md")
    intro = ""
    if a.add and out_json.exists():
        res = merge(json.loads(out_json.read_text()), res)
        intro = preamble(out_md.read_text()) if out_md.exists() else ""
    from vrneural.outputs.files import atomic_path

    md = intro + report(res)
    for path, text in ((out_json, json.dumps(res, indent=1) + "\n"), (out_md, md)):
        with atomic_path(path) as tmp:
            tmp.write_text(text)
    print(md)


if __name__ == "__main__":
    main()
