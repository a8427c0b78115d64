"""Training the networks of `bench quality` and `bench widths`: the synthetic BTF, the
``--jobs`` worker pool or training in this process, ``--resume``'s checks that a checkpoint
is this very run's, and the records of networks pruned from a wide start."""

from __future__ import annotations

import contextlib
import dataclasses
import json
import multiprocessing
import os
import signal
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from vrneural.bench.quality_btf import given_btfs
from vrneural.bench.quality_parallax import resolved_parallax
from vrneural.config import config_dict, resolved
from vrneural.distill.config import BEFORE_FIELD, RESUME_FREE
from vrneural.errors import VrnError, count
from vrneural.interrupt import interrupt_saying, raise_terminated, threading_main
from vrneural.outputs import OutputDir, file_sha256


def make_btf(preset: str, cfg, path: Path) -> Path:
    """Synthesise (or reuse an identical, already synthesised) BTF.

    With ``--resume`` a BTF synthesised with other settings is an error, not replaced: the
    teachers there were trained on it, and a file from an older release cannot be remade."""
    if preset in given_btfs(cfg):  # --btf: benched as it is
        return path
    try:
        from vrneural.btf.synth import BtfConfig, synthesize
    except ImportError as e:
        raise VrnError(f"BTF synthesis is unavailable ({e})") from None
    bcfg = BtfConfig(preset=preset, res=cfg.res, dirs=cfg.dirs, seed=cfg.seed)
    stamp = path.with_name(path.name + ".synth.json")
    want = json.dumps(config_dict(bcfg), sort_keys=True)
    if path.exists() and stamp.exists() and stamp.read_text() == want:
        return path
    if cfg.resume and path.exists():
        have = stamp.read_text().strip() if stamp.exists() else "no record (no .synth.json)"
        raise VrnError(
            f"{path}: --resume cannot reuse this BTF: it was synthesised with {have}, this run "
            f"asks for {want}; move it away (with the checkpoints trained on it) to start "
            "over, or pass --force to retrain every network"
        )
    path.unlink(missing_ok=True)
    path.parent.mkdir(parents=True, exist_ok=True)
    synthesize(bcfg, path, progress=cfg.progress)
    stamp.write_text(want)
    return path


def check_wide_start(path: Path, wide_epochs: int, epochs: int) -> None:
    """``--resume --wide-start``: a network pruned from a wide start of another length cannot
    be continued (it would have to start again from the longer wide run): one line."""
    from vrneural.distill.checkpoint import load_checkpoint

    if not path.is_file():
        return
    try:
        init = load_checkpoint(path).get("init_from")
    except VrnError:
        return  # unreadable: set_resume names the problem
    if init and int(init["epochs"]) != wide_epochs:
        raise VrnError(
            f"{path}: --resume cannot reuse this checkpoint: it was pruned from a wide start "
            f"of {count(int(init['epochs']), 'epoch')}, and --epochs {epochs} with --wide-start "
            f"asks for {wide_epochs}; a wide start cannot be extended (--force retrains, or "
            "use another --out)"
        )


#: in a worker of :func:`job_pool`: the pool's stop event (set when the run is stopped)
_STOP = None


def _job(kind: str, job_cfg) -> str:
    """One step of ``--jobs`` in a worker process; returns its time for the log (``reused``
    for a checkpoint taken as it was). A step that begins after the run was stopped does
    nothing; one in training stops at its next step (saving, as Ctrl-C does)."""
    if _STOP is not None and _STOP.is_set():
        raise VrnError("stopped before it began")
    if kind == "synth":
        preset, qcfg, path = job_cfg
        t0 = time.perf_counter()
        make_btf(preset, qcfg, path)
        return f"{time.perf_counter() - t0:.0f} s"
    from vrneural.distill.distill import run_distill
    from vrneural.distill.teach import run_teach

    reused = _finished(job_cfg)
    run = run_teach if kind == "teach" else run_distill
    ck = run(as_given(job_cfg), on_step=_stop_check, epochs_flag=epochs_flag(job_cfg))
    return took(ck, reused)


def epochs_flag(cfg) -> str:
    """The bench's option that sets a network's epochs, for the stage's messages: a teacher's
    ``--teacher-epochs``; none for a ``--wide-start`` half (its share of ``--epochs``)."""
    if not hasattr(cfg, "teacher"):
        return "--teacher-epochs"
    return "" if cfg.init_from or cfg.output.endswith(".wide.pt") else "--epochs"


def _stop_check(epoch: int, step: int) -> None:
    """After every training step of a worker: once the run is stopped, Ctrl-C this process,
    which the training loop turns into a save and a stop at this very step."""
    if _STOP is not None and _STOP.is_set():
        os.kill(os.getpid(), signal.SIGINT)


@contextlib.contextmanager
def job_pool(jobs: int):
    """The worker processes of ``--jobs`` (spawned: CUDA-safe, no forked torch thread pools).

    Used inside :func:`resume_hint`, which makes SIGTERM to this process (``kill``, a
    scheduler) a Ctrl-C. On any exception a shared event tells the workers: a network in
    training saves at its next step and stops, a queued one does not begin (the pool hands
    workers jobs ahead, which cancelling cannot recall), and the run waits for them, so no
    worker outlives it. Workers ignore Ctrl-C itself outside training (the event stops them).
    ``--resume`` then continues the interrupted networks."""
    ctx = multiprocessing.get_context("spawn")
    stop = ctx.Event()
    pool = ProcessPoolExecutor(
        max_workers=jobs, mp_context=ctx, initializer=_worker_init, initargs=(stop,)
    )
    try:
        yield pool
    except BaseException:
        stop.set()
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    finally:
        pool.shutdown(wait=True)


def _worker_init(stop) -> None:
    global _STOP
    _STOP = stop
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # training installs its own handler


def run_jobs(pool, jobs: list, log) -> None:
    """Run ``(label, kind, config)`` steps (:func:`_job`) in ``pool`` (:func:`job_pool`); log
    each as it ends."""
    futures = {pool.submit(_job, kind, c): label for label, kind, c in jobs}
    for f in as_completed(futures):
        log(f"{futures[f]}  {f.result()}")


def run_networks(pool, runs: list, log) -> None:
    """``(label, name, config)`` networks of :func:`network_runs` in ``pool``: the wide halves
    (name None) first, since the networks pruned from them read them."""
    for wide in (True, False):
        run_jobs(pool, [(lab, "distill", c) for lab, n, c in runs if (n is None) == wide], log)


def with_wide_start(ck: dict, wide_path: str) -> dict:
    """A network pruned from a wide start (``--wide-start``) as one run: its history after the
    wide run's (read where it is now, ``wide_path``: OUT may have moved), its epochs and
    training seconds the two together."""
    if not ck.get("init_from") or not wide_path:
        return ck
    from vrneural.distill.checkpoint import load_checkpoint

    wide = load_checkpoint(wide_path)
    return ck | {
        "history": list(wide["history"]) + list(ck["history"]),
        "epoch": int(wide["epoch"]) + int(ck["epoch"]),
        "train_seconds": float(wide["train_seconds"]) + float(ck["train_seconds"]),
    }


def wide_start_record(ck: dict) -> dict | None:
    """``{"width", "epochs"}`` of the wide run a network was pruned from (``--wide-start``),
    or None for one trained from random weights."""
    from vrneural.distill.export import init_record

    init = init_record(ck.get("init_from"))
    return init and {k: init[k] for k in ("width", "epochs")}


# Fields that may differ between a reusable checkpoint and this run: paths and workflow flags
# (the BTF and the teacher are compared by content; ``export``: whether a pack was written
# beside it), the epochs (a shorter run continues), and where and how fast it trains
# (device, compile), which do not change what is trained.
_FREE = {
    "btf",
    "output",
    "teacher",
    "init_from",
    "epochs",
    "progress",
    "force",
    "resume",
    "export",
    "device",
    "compile",
}


def _reuse_problem(cfg, btf_sha: str | None = None, teacher_sha: str | None = None):
    """Why the existing checkpoint ``cfg.output`` is not this very training run (up to its
    epochs), or None when it is; a ``None`` hash is not compared."""
    from vrneural.distill.checkpoint import load_checkpoint

    try:
        ck = load_checkpoint(cfg.output)
    except VrnError as e:
        return str(e).removeprefix(f"{cfg.output}: ")
    want, have = dataclasses.asdict(resolved(cfg)), ck["config"]
    if "parallax" in have:  # --parallax auto: what it chose (a teach run's default)
        have = have | {"parallax": resolved_parallax(ck)}
    # a field newer than the checkpoint counts as what that run used: its default, or
    # BEFORE_FIELD where the default changed the behaviour
    default = {f.name: f.metadata.get("default", f.default) for f in dataclasses.fields(cfg)}
    default |= BEFORE_FIELD
    free = _FREE if want.get("method") == "neumip" else _FREE | {"neumip_dirs"}
    diff = [
        f"{k} {have.get(k, default[k])!r} there, {v!r} here"
        for k, v in want.items()
        if k not in free and have.get(k, default[k]) != v
    ]
    pruned = bool(have.get("init_from")), bool(want.get("init_from"))
    if pruned[0] != pruned[1]:
        how = {True: "pruned from a wide start", False: "from random weights"}
        diff.append(f"{how[pruned[0]]} there, {how[pruned[1]]} here")
    if diff:
        return f"it was trained with other settings ({'; '.join(diff)})"
    if int(ck["epoch"]) > cfg.epochs:
        return f"it has {count(ck['epoch'], 'epoch')}, more than the {cfg.epochs} asked for"
    if btf_sha is not None and ck["btf"].get("sha256") != btf_sha:
        return "it was trained on another BTF (the header's SHA-256 differs)"
    init, wide = ck.get("init_from"), getattr(cfg, "init_from", "")
    if wide and init and Path(wide).is_file() and file_sha256(wide) != init["sha256"]:
        return f"it was pruned from another {Path(wide).name} (its SHA-256 differs)"
    if teacher_sha is not None and ck.get("teacher", {}).get("sha256") != teacher_sha:
        return (
            "it was distilled from another teacher (teacher.pt's SHA-256 differs; a teacher "
            "continued to more --teacher-epochs is another teacher)"
        )
    return None


def set_resume(cfg, resume: bool, **hashes) -> None:
    """``--resume``: continue (or take as it is) the checkpoint at ``cfg.output`` when it is
    this run's; one that is not is an error, never silently trained over. Otherwise train
    from scratch (``force``: the output directory was checked by ``run_quality``)."""
    exists = Path(cfg.output).exists()
    if resume and exists:
        why = _reuse_problem(cfg, **hashes)
        if why is not None:
            raise VrnError(
                f"{cfg.output}: --resume cannot reuse this checkpoint: {why}; move it away to "
                "retrain it, or pass --force to retrain every network"
            )
    cfg.resume = resume and exists
    cfg.force = not cfg.resume


def as_given(cfg):
    """What the bench gives the stage for ``cfg``: a resumed network only its epochs and where
    it trains (the rest is its checkpoint's, which :func:`set_resume` matched: a moved
    ``--out`` keeps the paths it recorded)."""
    if not cfg.resume:
        return cfg
    keep = ("epochs", *RESUME_FREE)
    return dataclasses.replace(
        cfg,
        **{f.name: None for f in dataclasses.fields(cfg) if "default" in f.metadata}
        | {k: getattr(cfg, k) for k in keep if hasattr(cfg, k)},
    )


def train_in_process(preset: str, tcfg, runs, log, more=()) -> tuple[dict, list]:
    """``--jobs 1``: train the teacher, then each ``(key, stem, DistillConfig)`` of ``runs()``
    (called once the teacher exists) in order, in this process; log each. Returns the
    teacher's checkpoint and ``(key, checkpoint, init_from)`` of every network with a key (a
    wide start's first half has none: the network pruned from it is the record)."""
    from vrneural.distill.distill import run_distill
    from vrneural.distill.teach import run_teach

    done = []
    for c in (tcfg, *more):  # the teacher, then further ones (the parallax variant's) before
        reused = _finished(c)  # the networks they teach
        ck = run_teach(as_given(c), epochs_flag="--teacher-epochs")
        stem = Path(c.output).stem  # "teacher" for tcfg
        log(f"{preset}: {stem}  {took(ck, reused)}")
        done.append((stem, ck, ""))
    tck = done.pop(0)[1]
    for key, stem, c in runs():
        reused = _finished(c)
        ck = run_distill(as_given(c), epochs_flag=epochs_flag(c))
        log(f"{preset}: {stem}  {took(ck, reused)}")
        if key is not None:
            done.append((key, ck, c.init_from))
    return tck, done


def load_trained(tcfg, runs, more=()) -> tuple[dict, list]:
    """What :func:`train_in_process` returns, for networks the ``--jobs`` workers trained: read
    from their checkpoints, without another pass through the training loop (and its log)."""
    from vrneural.distill.checkpoint import load_checkpoint

    tck = load_checkpoint(tcfg.output, kind="teacher")
    done = [(Path(c.output).stem, load_checkpoint(c.output, kind="teacher"), "") for c in more]
    done += [(k, load_checkpoint(c.output), c.init_from) for k, _, c in runs() if k is not None]
    return tck, done


def _finished(cfg) -> bool:
    """Whether ``--resume`` finds ``cfg.output`` finished at ``cfg.epochs`` (nothing to train)."""
    from vrneural.distill.checkpoint import load_checkpoint

    if not cfg.resume:
        return False
    ck = load_checkpoint(cfg.output)
    return bool(ck.get("finished")) and int(ck["epoch"]) == cfg.epochs


def took(ck: dict, reused: bool) -> str:
    """The log's time of one network: ``reused`` for a checkpoint taken as it was."""
    return "reused" if reused else f"{ck['train_seconds']:.0f} s"


def check_bench_out(root: Path, cfg, command: str, what: str) -> OutputDir:
    """The output folder of a training bench, checked: ``--resume`` needs it to exist; one
    with files in it needs ``--resume`` or ``--force`` and must be this command's (its
    checkpoints are kept either way: --resume reuses them, --force retrains each)."""
    if cfg.resume and not root.exists():  # as teach, distill and btf synth --resume
        raise VrnError(
            f"--resume: nothing to resume, {root} does not exist; drop --resume to start a new "
            f"{what} there"
        )
    remedy = "pass --resume to reuse its checkpoints or --force to retrain"
    od = OutputDir(root, command, resume=cfg.force or cfg.resume, remedy=remedy)
    od.check()
    return od


@contextlib.contextmanager
def resume_hint(root: Path):
    """Ctrl-C or SIGTERM in a training bench, in any phase (training, fits, evaluation, the
    report): finished networks are kept; say how to continue. SIGTERM raises
    KeyboardInterrupt here as SIGINT does (training's own handler saves first)."""
    main = threading_main() and signal.getsignal(signal.SIGTERM) is not signal.SIG_IGN
    old = signal.signal(signal.SIGTERM, raise_terminated) if main else None
    try:
        yield
    except KeyboardInterrupt as e:
        raise interrupt_saying(
            f"(in {root} finished checkpoints are kept, and interrupted ones continue where "
            "they stopped: rerun the same command with --resume)",
            e,
        ) from None
    finally:
        if main and old is not None:  # None: a handler not set from Python, not restorable
            signal.signal(signal.SIGTERM, old)
