"""The files a training stage writes, checked before any work starts.

``teach`` and ``distill`` write the checkpoint ``x.pt``, its ``x.pt.config.json`` and (unless
``--no-export``) the pack ``x.vrnm`` with ``x.vrnm.config.json``. A fresh run refuses every
one that exists without ``--force``; with ``--force`` the old files are removed once every
check has passed, just before training (:func:`clear_outputs`); no run writes over one of its
inputs, even with ``--force``. ``--resume`` continues the checkpoint and, when it finishes,
replaces the pack and config files beside it only where this run wrote them earlier: their
recorded test-L1 curve is the start of the checkpoint's (for a given config and BTF that curve
identifies the run). Any other file there is an error, never silently replaced. A finished
run resumed trains nothing and writes only the files that are missing.
"""

from __future__ import annotations

import json
import os
import warnings
from pathlib import Path

from vrneural.config import config_path, write_config
from vrneural.distill.checkpoint import load_checkpoint, unfinished_run
from vrneural.errors import VrnError
from vrneural.outputs import (
    check_outputs,
    check_resume_force,
    check_suffix,
    json_safe,
)
from vrneural.warn import VrnWarning


def outputs_of(output: str, export: bool) -> list[str]:
    """Files a stage writes: the checkpoint, its config and (optionally) the ``.vrnm`` beside
    it with its config."""
    check_suffix(output, ".pt", "checkpoint", "run.pt")  # the pack beside it: <stem>.vrnm
    p = Path(output)
    files = [p, config_path(p)]
    if export:
        pack = p.with_suffix(".vrnm")
        files += [pack, config_path(pack)]
    return [str(f) for f in files]


def prepare_outputs(cfg, outputs: list[str], inputs: list[str]) -> dict | None:
    """Check every output before any work; with --resume return the checkpoint to resume.

    Refuses outputs that are ``inputs``, existing outputs without --force (an interrupted run
    at ``cfg.output`` is named as such), unwritable directories, --resume with --force, and on
    --resume a pack or config file that this run did not write (see the module docstring).
    """
    check_resume_force(cfg.resume, cfg.force)  # (the caller holds the output's lock)
    if cfg.resume:
        check_outputs(outputs, True, inputs)  # inputs and writable directories only
        if not Path(cfg.output).exists():
            raise VrnError(
                f"--resume: nothing to resume, {cfg.output} does not exist; drop --resume to "
                "start a new run"
            )
        ck = load_checkpoint(cfg.output)
        for o in outputs[1:]:
            if Path(o).exists() and not written_by(o, ck, cfg.output):
                raise VrnError(
                    f"{o}: exists and was not written by the run in {cfg.output}; --resume "
                    "replaces only its own files, so move it away first"
                )
        return ck
    if not cfg.force and Path(cfg.output).is_file():
        try:
            ck = load_checkpoint(cfg.output)
        except VrnError:
            ck = None  # not a checkpoint: the plain "output exists" below
        if ck is not None and not ck.get("finished", True):
            raise VrnError(
                f"{cfg.output}: holds {unfinished_run(ck)}; pass --resume to continue it or "
                "--force to start over"
            )
    check_outputs(outputs, cfg.force, inputs)
    pack = Path(cfg.output).with_suffix(".vrnm")
    if not cfg.export and pack.exists():  # kept, but it will not be this run's network
        warnings.warn(
            f"{pack}: left as it is (--no-export), so it stays the pack of an earlier run and "
            f"will not match the new {cfg.output}; `vrneural export {cfg.output} -o {pack} "
            "--force` replaces it afterwards",
            StalePackWarning,
            stacklevel=2,
        )
    return None


def clear_outputs(outputs: list[str]) -> None:
    """``--force``, once every check has passed and just before training: remove the old
    run's files (checkpoint, config, pack), so that a new run interrupted before its first
    save cannot be taken for the old one by ``--resume``, nor the old files for its own.
    All or nothing: each is first renamed aside; if one cannot be (an immutable file, a folder
    of someone else's with the sticky bit), the others are put back and it is a one-line
    error, so the old run stays whole."""
    moved: list[tuple[Path, Path]] = []
    for o in map(Path, outputs):
        if not (o.exists() or o.is_symlink()):
            continue
        aside = o.with_name(f".{o.name}.old-{os.getpid()}")
        moved.append((o, aside))
        try:
            o.rename(aside)
        except BaseException as e:  # Ctrl-C between two renames too: put them back
            for orig, back in reversed(moved):
                if (back.exists() or back.is_symlink()) and not orig.exists():
                    back.rename(orig)
            if not isinstance(e, OSError):
                raise
            raise VrnError(
                f"{o}: cannot remove the old output to replace it ({e.strerror or e}); "
                "nothing was changed"
            ) from None
    for _, aside in moved:
        aside.unlink(missing_ok=True)


class StalePackWarning(VrnWarning):
    """A new run with ``--no-export`` beside a pack an earlier run exported."""


def written_by(path, ck: dict, output=None) -> bool:
    """Whether the pack or config file ``path`` was written by the run of checkpoint ``ck``
    (at ``output``): the test-L1 curve it records is a non-empty start of the checkpoint's
    history; or, for a `vrneural export` of the run interrupted in its first epoch (no curve
    yet), it names the checkpoint ``output`` as its source and records the run's config."""
    curve, src, config = _recorded(Path(path))
    have = json_safe([h.get("test_l1") for h in ck.get("history", [])])
    if curve:
        return json_safe(curve) == have[: len(curve)]
    if curve != [] or output is None:
        return False
    same = src is not None and Path(src).resolve() == Path(output).resolve()
    return same and json_safe(config) == json_safe(ck.get("config"))


def _recorded(p: Path) -> tuple:
    """``(per-epoch test L1, checkpoint path, training config)`` that a pack (its metrics and
    provenance) or a config file (its history; the sidecar of `vrneural export`: its source)
    records; the curve None for anything not ours."""
    try:
        if p.suffix == ".vrnm":
            from vrneural.formats.vrnm import read_vrnm

            meta = read_vrnm(p).meta
            prov = meta.get("provenance")
            prov = prov if isinstance(prov, dict) else {}
            doc = {"metrics": meta.get("metrics", {}), "checkpoint": prov.get("checkpoint")}
            doc["training_config"] = prov.get("config")
        else:
            doc = json.loads(p.read_text())
        if isinstance(doc.get("history"), list):
            curve = [h.get("test_l1") for h in doc["history"]]
        else:
            curve = doc.get("metrics", {}).get("test_l1_curve")
        curve = curve if isinstance(curve, list) else None
        return curve, doc.get("checkpoint"), doc.get("training_config")
    except (VrnError, OSError, ValueError, AttributeError, TypeError):
        return None, None, None


def finish_outputs(ck: dict, cfg, data, export: bool | None = None, missing_only=False) -> None:
    """Write ``<output>.config.json`` and (with export; default ``cfg.export``) the ``.vrnm``
    pack + its config.

    Called when a run finishes: an interrupted run has only its checkpoint until then. With
    ``missing_only`` (a finished run resumed, nothing trained) only files that are not there
    are written: the ones there describe this very checkpoint already, and a pack exported
    from it since (``vrneural export``) stays as it is."""
    extra = {"epochs_done": ck["epoch"], "history": ck["history"], "btf": ck["btf"]}
    if not (missing_only and config_path(cfg.output).exists()):
        write_config(cfg.output, cfg, extra)
    if cfg.export if export is None else export:
        from vrneural.distill.export import export_checkpoint

        pack = outputs_of(cfg.output, True)[2]
        if missing_only and Path(pack).exists() and config_path(pack).exists():
            return
        _, meta = export_checkpoint(ck, pack, data=data.on("cpu"), force=True, source=cfg.output)
        write_config(pack, cfg, {**extra, "metrics": meta["metrics"]})
