"""``vrneural distill``: train a small model from a teacher (paper Eq. 5) or from ground truth.

``L = L1(y_s, y_gt) + sigma L1(y_s, y_t) + lambda1 L2(z_s1, T1 z_t1) + lambda2 L2(z_s2, T2 z_t2)``
with learnable linear maps ``T: teacher width -> student width`` (no bias). The L1 terms are
taken in the student's output space (linear, or log(1+y)); the latents are the student's two
hidden vectors of :func:`~vrneural.distill.models.make_spec` (for the coarse-to-fine student:
``z_c`` and the fine hidden layer) against the teacher's last two hidden layers.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import warnings
from pathlib import Path

import torch
import torch.distributed as dist

from vrneural.btf.format import read_btf
from vrneural.btf.identity import btf_fingerprint, check_btf_record
from vrneural.config import (
    given,
    resolved,
)
from vrneural.distill.checkpoint import (
    UnfinishedRunWarning,
    load_checkpoint,
    model_from_checkpoint,
    recorded_btf,
    unfinished_run,
)
from vrneural.distill.config import BEFORE_FIELD, DistillConfig, check_lod_levels
from vrneural.distill.core import DistillNet
from vrneural.distill.data import SliceData
from vrneural.distill.evaluate import mean_l1, mean_value, test_pairs
from vrneural.distill.models import NeuralModel, make_spec
from vrneural.distill.outputs import (
    clear_outputs,
    finish_outputs,
    outputs_of,
    prepare_outputs,
)
from vrneural.distill.prune import check_init, prune_to
from vrneural.distill.teach import check_train_config, resumed_config
from vrneural.distill.train import Interrupted, compile_networks, dist_setup, fit, train_device
from vrneural.errors import VrnError, check_range, count
from vrneural.outputs import (
    check_outputs,
    check_resume_force,
    file_sha256,
    output_lock,
    same_file,
)
from vrneural.parallax import setup_parallax


def resolve_method(cfg: DistillConfig, chosen=()) -> DistillConfig:
    """The config as trained: NeuMIP always uses log(1 + y) output, as the paper modified it
    (a --space linear given with it, ``"space" in chosen``, is an error, not silently changed)."""
    if cfg.method != "neumip":
        return cfg
    if cfg.space != "log" and "space" in chosen:
        raise VrnError(
            f"--space {cfg.space} conflicts with --method neumip, which always trains in log "
            "space (log(1 + y), as the paper modified NeuMIP); drop --space"
        )
    return dataclasses.replace(cfg, space="log")


def teacher_split(cfg: DistillConfig, tck: dict, resume: bool, chosen=()) -> DistillConfig:
    """The config with the teacher's split settings, the split every student trains on. A
    ``--split-seed``/``--test-fraction`` given (in ``chosen``) with another value is an error."""
    tc = tck["config"]
    for k in ("split_seed", "test_fraction"):
        if k not in tc or getattr(cfg, k) == tc[k]:
            continue
        if k in chosen and not resume:
            raise VrnError(
                f"--{k.replace('_', '-')} = {getattr(cfg, k)!r}, but the teacher {cfg.teacher} "
                f"was trained with {tc[k]!r}; distill reuses the teacher's train/test split "
                "(drop the flag, or train a teacher with it)"
            )
        cfg = dataclasses.replace(cfg, **{k: tc[k]})
    return cfg


def wide_output(output) -> str:
    """Where ``--wide-start`` keeps its wide half: ``student.pt`` -> ``student.wide.pt``."""
    outputs_of(output, False)  # the .pt check, with its message
    return str(Path(output).with_suffix(".wide.pt"))


def run_of_wide_half(wide_path) -> str:
    """The output of the ``--wide-start`` run a wide half belongs to (``s.wide.pt`` -> ``s.pt``)."""
    return str(Path(wide_path).with_suffix("")).removesuffix(".wide") + ".pt"


def is_wide_half(config: dict) -> bool:
    """Whether a checkpoint's config is the wide half of a ``--wide-start`` run."""
    return bool(config.get("wide_start")) and not config.get("init_from")


def stored_wide_start(output: str) -> dict | None:
    """The config of the ``--wide-start`` run at ``output`` (its pruned half, or where that has
    not begun its wide half ``<output>.wide.pt``), None where there is none. ``output`` itself
    being a wide half is an error: the run is resumed by its own output."""
    if Path(output).is_file():
        c = load_checkpoint(output)["config"]
        if is_wide_half(c):
            raise VrnError(
                f"{output}: is the wide half of a --wide-start run; resume the run: "
                f"vrneural distill TEACHER -o {run_of_wide_half(output)} --resume"
            )
        return c if c.get("wide_start") else None
    wide = wide_output(output)
    if Path(wide).is_file():
        c = load_checkpoint(wide)["config"]
        return c if is_wide_half(c) else None
    return None


#: (option, field of the checkpoint's config recording it) that a --resume must not contradict
WIDE_START_RECORD = (
    ("wide_start", "wide_start"),
    ("width", "wide_start_width"),
    ("epochs", "wide_start_epochs"),
    ("export", "export"),  # the run's: the wide half records it and never writes a pack
)


def run_wide_start(cfg: DistillConfig, on_step=None, stored: dict | None = None) -> dict:
    """``--wide-start W``: train W wide for ``epochs // 2`` epochs into ``<output>.wide.pt``,
    prune that half to ``--width`` and train on for the other epochs into ``--output`` (what
    ``--width W`` and then ``--init-from`` do, as one run). Every output of both halves is
    checked before any work; ``--force`` then removes both halves of the old run (see
    :func:`~vrneural.distill.outputs.clear_outputs`); ``--resume`` (of the output, with or
    without ``--wide-start``) continues whichever half was interrupted, with the settings the
    run was started with (``stored``: :func:`stored_wide_start` of the output, where the
    caller read it). Returns the pruned half's final checkpoint."""
    if cfg.resume and stored is None:
        stored = stored_wide_start(cfg.output)
    if cfg.resume and stored is None:
        if Path(cfg.output).exists():
            raise VrnError(
                f"{cfg.output}: was not trained with --wide-start (it started from random "
                "weights or from --init-from); resume it without --wide-start, or start over "
                "with --force"
            )
        raise VrnError(
            f"--resume: nothing to resume, neither {cfg.output} nor its wide half "
            f"{wide_output(cfg.output)} exists; drop --resume to start a new run"
        )
    if stored is not None:  # the run's own settings; a flag that contradicts one is an error
        kind = resolved(cfg)
        ran = {k: type(getattr(kind, k))(stored[key]) for k, key in WIDE_START_RECORD}
        for name, was in ran.items():
            now = getattr(cfg, name)
            if now is not None and now != was:
                why = (
                    "its epochs were split between the halves when it began"
                    if name == "epochs"
                    else "--resume continues the run's settings"
                )
                raise VrnError(
                    f"--{name.replace('_', '-')} = {now}, but {cfg.output} is a --wide-start "
                    f"run with --{name.replace('_', '-')} {was}; {why} (drop the flag, or start "
                    "over: --force instead of --resume)"
                )
        cfg = dataclasses.replace(cfg, **ran)
    asked, cfg = cfg, resolved(cfg)  # the halves resolve the fields left open themselves
    w = cfg.wide_start
    if cfg.method == "neumip":
        raise VrnError(
            "--wide-start: prunes the 8-wide networks (student, single8); NeuMIP is "
            "always 4 x 25 (drop --wide-start)"
        )
    if cfg.init_from:
        raise VrnError(
            "--wide-start trains its own wide run; --init-from starts from another "
            "one (pass one of the two)"
            if not stored
            else f"--init-from: {cfg.output} is a --wide-start run, which started from its own "
            "wide half (drop --init-from)"
        )
    check_range("--width", cfg.width, 1, 64)
    if cfg.width == 64:
        raise VrnError("--wide-start: --width 64 leaves no wider start (64 is the widest)")
    if not cfg.width < w <= 64:
        raise VrnError(
            f"--wide-start {w}: 0 (off) or a width in [{cfg.width + 1}, 64], wider than "
            f"--width {cfg.width}"
        )
    if cfg.epochs < 2:
        raise VrnError(
            f"--epochs {cfg.epochs} with --wide-start: the wide half gets epochs // 2 and the "
            "pruned half the rest, so at least 2"
        )
    wide_path, wide_epochs = wide_output(cfg.output), cfg.epochs // 2
    record = dict(wide_start_epochs=cfg.epochs, wide_start_width=cfg.width)
    # each half goes to its share of the epochs, not its stored target
    wide = dataclasses.replace(asked, output=wide_path, width=w, epochs=wide_epochs, **record)
    narrow = dataclasses.replace(
        asked, epochs=cfg.epochs - wide_epochs, init_from=wide_path, **record
    )
    outs = outputs_of(cfg.output, cfg.export)
    try:
        if cfg.resume and Path(cfg.output).exists():  # the pruned half began: continue it
            return _resume_pruned_half(cfg, narrow, wide_path, on_step)
        if cfg.resume:  # the wide half only: its pruned half will write every output
            for o in outs:
                if Path(o).exists():
                    raise VrnError(
                        f"{o}: exists, and the pruned half of {cfg.output} (not begun yet) "
                        "would write it; --resume replaces only its own files, so move it away "
                        "first"
                    )
        else:  # both halves' outputs, before any work
            wide_outs = outputs_of(wide_path, False)
            prepare_outputs(narrow, outs, inputs=[cfg.teacher, cfg.btf, wide_path])
            prepare_outputs(wide, wide_outs, inputs=[cfg.teacher, cfg.btf])
            if cfg.force and _rank() == 0:  # the old run's halves go (see clear_outputs)
                clear_outputs(outs + wide_outs)
        wck = _train(wide, on_step, epochs_flag="")  # no option sets a half's epochs
        if cfg.progress and _rank() == 0:
            test = wck["history"][-1]["test_l1"] if wck["history"] else float("nan")
            print(
                f"{wide_path}: wide half done ({w} wide, {count(wide_epochs, 'epoch')}, test "
                f"L1 {test:.5f}); pruning to {cfg.width} wide",
                file=sys.stderr,
            )
        if dist.is_initialized():
            dist.barrier()  # rank 0 wrote the wide half; every rank prunes it
        return _train(dataclasses.replace(narrow, resume=False, force=False), on_step, "")
    except Interrupted as e:
        e.resume = f"-o {cfg.output} --resume"  # the whole run, not the half's file
        raise


def _rank() -> int:
    """This process's rank (under ``torchrun`` also before the process group is set up)."""
    return dist.get_rank() if dist.is_initialized() else int(os.environ.get("RANK", "0"))


def _resume_pruned_half(cfg, narrow, wide_path: str, on_step) -> dict:
    """``--resume`` of a wide-start run whose pruned half began: continue it, after checking
    that it was pruned from the wide half that is there now."""
    ck = load_checkpoint(cfg.output, kind="student")
    init = ck.get("init_from") or {}
    if Path(wide_path).is_file() and file_sha256(wide_path) != init.get("sha256"):
        raise VrnError(
            f"{cfg.output}: was pruned from another {Path(wide_path).name} than the one there "
            "now (its SHA-256 differs); start over with --force"
        )
    if ck.get("finished", True) and int(ck["epoch"]) >= narrow.epochs and _rank() == 0:
        print(
            f"{cfg.output}: already trained ({count(cfg.epochs, 'epoch')}: {cfg.wide_start} wide "
            f"for {init.get('epochs', '?')}, then {cfg.width} wide), nothing left to train; a "
            "wide start cannot be extended (--force retrains both halves)",
            file=sys.stderr,
        )
    return _train(narrow, on_step, epochs_flag="")


#: options that shape one method only: (field, the methods it applies to, what it is)
METHOD_OPTIONS = (
    ("coarse_channels", ("student",), "the coarse-to-fine student's U_c channels"),
    ("fine_channels", ("student",), "the coarse-to-fine student's U_f channels"),
    ("neumip_dirs", ("neumip",), "NeuMIP's direction inputs"),
)


def check_method_options(cfg: DistillConfig, chosen) -> None:
    """An option given (named in ``chosen``: the fields not left None) that the run
    would not use is a one-line error (it was recorded in the config as if it had been, and
    did nothing): the student's texture channels for single8 or NeuMIP, ``--neumip-dirs`` for
    the others, Eq. 5's weights with ``--no-distill``. ``cfg``: the run's config as trained
    (a resumed run's method is its checkpoint's)."""
    for name, methods, what in METHOD_OPTIONS:
        if name in chosen and cfg.method not in methods:
            raise VrnError(
                f"--{name.replace('_', '-')} sets {what}; it does nothing for --method "
                f"{cfg.method} (drop the flag)"
            )
    unused = [f"--{k}" for k in ("sigma", "lambda1", "lambda2") if k in chosen]
    if unused and not cfg.distill:
        raise VrnError(
            f"{', '.join(unused)} {'weighs' if len(unused) == 1 else 'weigh'} the teacher's "
            "terms of the loss (Eq. 5); --no-distill trains on the ground truth alone "
            "(drop the flag)"
        )


def run_distill(cfg: DistillConfig, on_step=None, epochs_flag: str = "--epochs") -> dict:
    """Train (or resume) a student/baseline; returns the final checkpoint dict. Holds a lock on its
    outputs while it trains (:func:`vrneural.outputs.output_lock`). Fields left None take
    their defaults, or on ``--resume`` the checkpoint's; ``epochs_flag``: the option that
    sets ``cfg.epochs``, for messages."""
    with output_lock(cfg.output):
        check_resume_force(cfg.resume, cfg.force)
        if not cfg.resume:  # a resumed run's method is its checkpoint's: checked in _train
            check_method_options(resolved(cfg), given(cfg))
        stored = stored_wide_start(cfg.output) if cfg.resume else None
        if cfg.wide_start or stored:
            with output_lock(wide_output(cfg.output)):  # its wide half's outputs too
                return run_wide_start(cfg, on_step, stored)
        wide = cfg.output.endswith(".pt") and Path(wide_output(cfg.output))
        if not cfg.resume and wide and wide.is_file():  # an unfinished wide half left behind?
            try:
                c = load_checkpoint(wide)
            except VrnError:
                c = {}
            if is_wide_half(c.get("config", {})) and not c.get("finished", True):
                warnings.warn(
                    f"{wide}: holds the unfinished wide half of a --wide-start run at "
                    f"{cfg.output}; this run (without --wide-start) leaves it as it is",
                    UnfinishedRunWarning,
                    stacklevel=2,
                )
        return _train(cfg, on_step, epochs_flag)


def _train(asked: DistillConfig, on_step=None, epochs_flag: str = "--epochs") -> dict:
    """One training run (a whole ``distill`` run, or one half of a ``--wide-start`` run):
    ``asked`` as given (None: not given), ``epochs_flag`` the option that sets its epochs."""
    cfg, chosen = resolved(asked), given(asked)
    check_train_config(cfg)
    for k in ("sigma", "lambda1", "lambda2", "lod_weight", "offset_weight"):
        check_range(f"--{k.replace('_', '-')}", getattr(cfg, k), 0.0, 100.0)
    check_range("--lod-levels", cfg.lod_levels, 1, 12)
    check_range("--coarse-channels", cfg.coarse_channels, 1, 64)
    check_range("--fine-channels", cfg.fine_channels, 1, 64)
    check_range("--width", cfg.width, 1, 64)
    if cfg.method == "neumip" and "width" in chosen:
        raise VrnError("--width: NeuMIP is always 4 x 25 (the paper's baseline); drop --width")
    cfg = resolve_method(cfg, chosen)
    if cfg.init_from and not cfg.resume and not Path(cfg.init_from).is_file():  # named first
        raise VrnError(f"--init-from {cfg.init_from}: no such checkpoint")
    export = cfg.export and not is_wide_half(dataclasses.asdict(cfg))  # a wide half: no pack
    outs = outputs_of(cfg.output, export)
    resume = prepare_outputs(cfg, outs, inputs=[cfg.teacher, cfg.btf, cfg.init_from])
    if resume is not None:
        if resume.get("kind") != "student":
            raise VrnError(f"{cfg.output}: is not a student checkpoint; cannot --resume distill")
        was = resume["config"].get("init_from") or ""
        if cfg.init_from and was and same_file(cfg.init_from, was):  # ./wide.pt == wide.pt
            asked = dataclasses.replace(asked, init_from=was)
        # output and teacher: where they are now (the directory may have moved)
        stored = BEFORE_FIELD | resume["config"]
        old = resumed_config(asked, stored, resume, epochs_flag=epochs_flag)
        old["teacher"] = cfg.teacher
        if cfg.btf:
            old["btf"] = cfg.btf
        cfg = resolved(DistillConfig(**old))
        check_method_options(cfg, chosen)
    tck = load_checkpoint(cfg.teacher, kind="teacher")
    if resume is None and not tck.get("finished", True):
        warnings.warn(
            f"{cfg.teacher}: {unfinished_run(tck)}; distilling from it as it is; finishing it "
            "later (`vrneural teach BTF -o TEACHER --resume`) makes it another teacher, whose "
            "pack this student no longer matches",
            UnfinishedRunWarning,
            stacklevel=2,
        )
    tsha = file_sha256(cfg.teacher)
    if resume is not None and resume["teacher"]["sha256"] != tsha:
        raise VrnError(f"{cfg.teacher}: teacher differs from the one {cfg.output} was trained with")
    cfg = teacher_split(cfg, tck, resume is not None, chosen)
    btf_path = cfg.btf or recorded_btf(tck, cfg.teacher)
    check_outputs(outs, True, [btf_path])  # (checked above; now against the BTF)
    btf = read_btf(btf_path)
    fp = btf_fingerprint(btf)
    mismatch = f"does not match the teacher {cfg.teacher}"
    check_btf_record(btf_path, fp, tck["btf"], mismatch, "the teacher was trained on")
    if resume is not None:  # also its own record: a teacher from before the value hash does
        # not see values that changed (a BTF synthesised again on another machine can differ)
        mismatch = f"differs from the one {cfg.output} was trained on"
        remedy = "; resume it with that BTF (--btf), or start over with --force"
        check_btf_record(btf_path, fp, resume["btf"], mismatch, "the run began on", remedy)
    dev = train_device(cfg.device)
    rank, world = dist_setup(cfg.device)
    teacher = model_from_checkpoint(tck, cfg.teacher)
    data = SliceData(btf, tck["split"]["test"], rank, world, device=dev)
    H, W = btf.resolution
    spec = make_spec(
        cfg.method,
        (H, W),
        cfg.space,
        coarse_channels=cfg.coarse_channels,
        fine_channels=cfg.fine_channels,
        neumip_dirs=cfg.neumip_dirs,
        width=cfg.width,
    )
    if cfg.lod_levels > 1:
        check_lod_levels(cfg, (H, W), btf_path)
        spec["lod"] = {"levels": cfg.lod_levels, "kind": cfg.lod_kind}
    recorded = resume.get("parallax") if resume is not None else None
    height, parallax = setup_parallax(cfg, spec, btf, btf_path, recorded)
    model = NeuralModel(spec, cfg.seed)
    init = None
    if cfg.init_from and resume is None:  # a resumed run has its weights already
        try:
            ick = load_checkpoint(cfg.init_from, kind="student")
        except VrnError as e:
            raise VrnError(f"--init-from: {e}") from None
        check_init(cfg.init_from, ick, cfg, spec, tsha)
        model = prune_to(model_from_checkpoint(ick, cfg.init_from), spec, data.on("cpu"))
        init = {
            "path": str(cfg.init_from),
            "resolved": str(Path(cfg.init_from).resolve()),
            "sha256": file_sha256(cfg.init_from),
            "spec": ick["spec"],
            "epochs": int(ick["epoch"]),
        }
    if height is not None:  # after --init-from's pruning, which builds a fresh model
        model.set_height(height)
    net = DistillNet(model, teacher.to(dev), data, cfg).to(dev)
    compile_networks(cfg.compile, model, teacher)
    pairs = test_pairs(data, cfg.max_test_slices)
    payload = {
        "kind": "student",
        "method": cfg.method,
        "spec": spec,
        "config": dataclasses.asdict(cfg),
        "btf": fp,
        "split": tck["split"],
        "parallax": parallax,
        "teacher": {
            "path": str(cfg.teacher),
            "resolved": str(Path(cfg.teacher).resolve()),
            "sha256": tsha,
            "spec": tck["spec"],
        },
        "versions": {"torch": str(torch.__version__)},
        "init_from": init if resume is None else resume.get("init_from"),
        # the teacher on the same test slices: what `distill` compares the student with
        "teacher_test_l1": float(mean_l1(teacher, data, pairs)),  # frozen: no autograd graph
        "test_mean": mean_value(data, pairs),  # the L1 of predicting black
    }
    if cfg.force and resume is None and rank == 0:
        clear_outputs(outs)
    ck = fit(net, model, data, pairs, cfg, payload, resume, on_step, epochs_flag)
    if rank == 0:
        finish_outputs(ck, cfg, data, export, missing_only=ck is resume)
    return ck
