"""Tiny trained packs for `bench tradeoff`: one synthetic BTF, its teacher and four small
networks, trained with :mod:`vrneural.distill` at a small stated budget and cached in
``OUT/packs`` (reused while the training config is unchanged, also across ``--force`` reruns).

Packs: ``teacher`` (128-wide, the per-pixel reference), ``student`` (coarse-to-fine, distilled),
``student_nodistill`` (coarse-to-fine, ground truth only), ``single8`` (single-level 8-wide,
distilled) and ``neumip`` (arch single, 7 channels, 4 x 25, log1p, ground truth only) -- the same
five as `bench quality`.
"""

from __future__ import annotations

import json
from pathlib import Path

from vrneural.btf.identity import fingerprint_mismatch
from vrneural.btf.synth import BtfConfig, synthesize
from vrneural.distill.config import DistillConfig, TeachConfig
from vrneural.errors import VrnError
from vrneural.formats.vrnm import read_vrnm
from vrneural.material import distilled, pack_width

RUNS = {
    "student": dict(method="student"),
    "student_nodistill": dict(method="student", distill=False),
    "single8": dict(method="single8"),
    "neumip": dict(method="neumip", distill=False),
}
#: trained only when asked for (``train_packs(only=...)``): the distilled student with
#: prefiltered neural textures (bench distance)
EXTRA_RUNS = {"student_lod": dict(method="student", lod_levels=4)}
#: exported from another run's checkpoint when asked for (``only``): the distilled student with
#: a pyramid of box averages of its own neural textures (``export --lod-levels 4``): the same
#: network as ``student``, so a comparison with it isolates the filter (bench distance)
DERIVED = {"student_pyr": ("student", 4)}
PACKS = ("teacher", *RUNS)


def train_packs(
    d: Path, budget: dict, progress: bool, only: tuple | None = None
) -> dict[str, Path]:
    """Train (or reuse) every pack under ``d``; ``budget``: preset, res, dirs, teacher_width,
    teacher_epochs, epochs, seed; ``only``: the networks of :data:`RUNS` to train (default all;
    the teacher always). Returns name -> .vrnm path."""
    from vrneural.distill.distill import run_distill
    from vrneural.distill.teach import run_teach

    derived = {k: v for k, v in DERIVED.items() if only is not None and k in only}
    need = {src for src, _ in derived.values()}
    runs = {
        k: v
        for k, v in (RUNS | EXTRA_RUNS).items()
        if (k in RUNS if only is None else k in only or k in need)
    }
    paths = {k: d / f"{k}.vrnm" for k in ("teacher", *runs, *derived)}
    stamp = d / "budget.json"
    want = json.dumps(budget, sort_keys=True)
    trained = [p for k, p in paths.items() if k not in derived]
    if stamp.exists() and stamp.read_text() == want and all(p.exists() for p in trained):
        derive(d, paths, derived, missing_only=True)
        return paths
    d.mkdir(parents=True, exist_ok=True)
    stamp.unlink(missing_ok=True)
    btf = d / "btf.btf"
    btf.unlink(missing_ok=True)
    bcfg = BtfConfig(**{k: budget[k] for k in ("preset", "res", "dirs", "seed")})
    synthesize(bcfg, btf, progress=progress)
    common = dict(seed=budget["seed"], progress=progress, force=True, max_test_slices=0)
    run_teach(
        TeachConfig(
            btf=str(btf),
            output=str(d / "teacher.pt"),
            epochs=budget["teacher_epochs"],
            width=budget["teacher_width"],
            **common,
        )
    )
    for name, kw in runs.items():
        run_distill(
            DistillConfig(
                teacher=str(d / "teacher.pt"),
                output=str(d / f"{name}.pt"),
                epochs=budget["epochs"],
                **kw,
                **common,
            )
        )
    derive(d, paths, derived)
    missing = [str(p) for p in paths.values() if not p.exists()]
    if missing:
        raise VrnError(f"training finished but packs are missing: {', '.join(missing)}")
    stamp.write_text(want)
    return paths


def derive(d: Path, paths: dict, derived: dict, missing_only: bool = False) -> None:
    """Export each :data:`DERIVED` pack from its source run's checkpoint in ``d``."""
    from vrneural.distill.checkpoint import load_checkpoint
    from vrneural.distill.export import export_checkpoint

    for name, (src, levels) in derived.items():
        if missing_only and paths[name].exists():
            continue
        pt = d / f"{src}.pt"
        export_checkpoint(load_checkpoint(pt), paths[name], force=True, source=str(pt),
                          lod_levels=levels)  # fmt: skip


#: the packs `bench tradeoff --packs DIR` cannot do without: the reference and the base
#: network; the other networks' rows are left out where their pack is not there
REQUIRED = ("teacher", "student")


def pack_paths(d) -> dict[str, Path]:
    """The packs of ``--packs DIR`` that are there (the :data:`REQUIRED` ones always, so that
    :func:`load_packs` names a missing one)."""
    if not Path(d).is_dir():
        what = "is a file" if Path(d).exists() else "does not exist"
        raise VrnError(
            f"--packs = {str(d)!r} {what}; name the folder that holds "
            f"{' and '.join(f'{k}.vrnm' for k in REQUIRED)} (from `bench tradeoff`'s packs/)"
        )
    return {
        k: Path(d) / f"{k}.vrnm"
        for k in PACKS
        if k in REQUIRED or (Path(d) / f"{k}.vrnm").is_file()
    }


def load_packs(paths: dict[str, Path]) -> dict:
    """name -> NeuralMaterial, each checked against the role its name gives it
    (:func:`check_packs`). Raises a one-line :class:`VrnError` naming the file."""
    out = {}
    for k, p in paths.items():
        if Path(p).is_dir():
            raise VrnError(f"--packs: {str(p)!r} is a folder, not a runtime pack")
        if not Path(p).is_file():
            raise VrnError(
                f"--packs: {str(p)!r} not found (needs {' and '.join(REQUIRED)} .vrnm; "
                f"{', '.join(x for x in PACKS if x not in REQUIRED)} add their rows)"
            )
        out[k] = read_vrnm(p)
    check_packs(out, paths)
    return out


#: What each pack name must hold: the role's name in the reports, what it must be, and the
#: ``meta`` it must record (``method``, ``arch``; ``distill`` from the training config).
ROLES = {
    "teacher": ("the reference", "a teacher", dict(method="teacher")),
    "student": (
        "the base network",
        "a distilled coarse-to-fine student",
        dict(method="student", arch="coarse_fine", distill=True),
    ),
    "student_nodistill": (
        "the network 'student w/o distillation'",
        "a coarse-to-fine student trained without distillation (distill --no-distill)",
        dict(method="student", arch="coarse_fine", distill=False),
    ),
    "single8": (
        "the network 'single-level 8-wide'",
        "a single-level 8-wide network (distill --method single8)",
        dict(method="single8", arch="single"),
    ),
    "neumip": (
        "the network 'NeuMIP-sized 4x25'",
        "a NeuMIP-sized network (distill --method neumip)",
        dict(method="neumip", arch="single"),
    ),
}
ARCH_WORDS = {"coarse_fine": "coarse-to-fine", "single": "single-level"}
#: The BTF fingerprint fields compared (:data:`vrneural.btf.identity.FINGERPRINT_KEYS` but the
#: name, which a renamed copy changes): the header's and a value sample's SHA-256, and the shape
BTF_KEYS = ("sha256", "values_sha256", "shape")


def describe_pack(mat) -> str:
    """What a pack records being, e.g. ``a coarse-to-fine student pack (8 wide, distilled)``."""
    method = mat.meta.get("method")
    what = f"{pack_width(mat)} wide"
    if mat.output == "log1p":
        what += ", log1p output"
    was = distilled(mat) if method else None
    if was is not None:
        what += ", distilled" if was else ", not distilled"
    if not method:
        return f"a {ARCH_WORDS[mat.arch]} pack ({what}) that records no training method"
    if method == "teacher":
        return f"a teacher pack ({what})"
    return f"a {ARCH_WORDS[mat.arch]} {method} pack ({what})"


def check_packs(mats: dict, paths: dict[str, Path]) -> None:
    """Refuse (one line, naming the file) a pack that is not what its name says, from what it
    records: ``meta.method`` (``"teacher"``, as `run --pack` recognises a teacher), its
    architecture and, for the two students, whether it was distilled; then one trained on
    another BTF than the teacher (``provenance.btf``) or from another teacher checkpoint
    (a pack's ``provenance.teacher`` against the teacher's ``checkpoint_sha256``). A field
    a pack does not record (an older export) is not compared."""
    for k, mat in mats.items():
        if k not in ROLES:
            continue
        role, need, want = ROLES[k]
        have = dict(method=mat.meta.get("method"), arch=mat.arch, distill=distilled(mat))
        if any(have[f] != v for f, v in want.items()):
            raise VrnError(
                f"{paths[k]}: is {describe_pack(mat)}, but {role} ({k}.vrnm) must be {need}"
            )
    if "teacher" not in mats:
        return
    tp = paths["teacher"]
    tprov = mats["teacher"].meta.get("provenance") or {}
    tbtf = tprov.get("btf") or {}
    tsha = tprov.get("checkpoint_sha256")
    same = "all packs in --packs must come from one BTF and its teacher"
    for k, mat in mats.items():
        if k == "teacher":
            continue
        prov = mat.meta.get("provenance") or {}
        btf = prov.get("btf") or {}
        f = fingerprint_mismatch(btf, tbtf, BTF_KEYS)
        if f:
            raise VrnError(
                f"{paths[k]}: was trained on another BTF ({_btf(btf, f)}) than the "
                f"reference {tp} ({_btf(tbtf, f)}); {same}"
            )
        sha = prov.get("teacher")
        if isinstance(sha, str) and isinstance(tsha, str) and sha != tsha:
            raise VrnError(
                f"{paths[k]}: was trained with another teacher (checkpoint SHA-256 "
                f"{sha[:12]}...) than the reference {tp} (checkpoint {tsha[:12]}...); {same}"
            )


def _btf(fp: dict, key: str) -> str:
    """``'leather' 40x40x48x48, sha256 22f6bad8ce61...``: a BTF record, naming ``key``."""
    v = fp[key]
    v = "x".join(map(str, v)) if isinstance(v, list) else f"{str(v)[:12]}..."
    name = f"{fp['name']!r} " if fp.get("name") else ""
    return f"{name}{key} {v}"
