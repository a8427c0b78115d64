"""The shared trainer loop: one ``(wi, wo)`` slice per step, Adam + ReduceLROnPlateau on the
held-out test L1, an atomic checkpoint every epoch, Ctrl-C saves, exact resume, DDP.

Determinism: the data order and the jitter of epoch ``e`` come from generators seeded with
``(seed, e)``; the jitter generator's state is checkpointed, so resuming (also mid-epoch)
replays the uninterrupted run bit for bit on CPU. With ``--device cuda`` the same streams are
drawn on the CPU and the initialisation is made there, so a GPU run sees the same data, jitter
and initial weights; it agrees with the CPU run to float tolerance, not bit for bit (the
texture gradient is summed with atomic adds), and so does a resumed GPU run with the straight
one. Under ``torchrun`` every rank draws the same
jitter for the whole slice and trains on its equal share of the 2x2 blocks; DDP averages the
gradients, which equals the full-slice gradient (the loss is a mean over equal shares).
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import sys
import time

import torch
import torch.distributed as dist
from torch import nn

from vrneural.distill.averages import Ema
from vrneural.distill.checkpoint import save_checkpoint
from vrneural.distill.core import NonFiniteLossError, epoch_order, epoch_steps
from vrneural.distill.data import SliceData
from vrneural.distill.evaluate import mean_l1
from vrneural.distill.models import NeuralModel
from vrneural.errors import VrnError, count
from vrneural.interrupt import Stop


def compile_networks(mode: str, *models: nn.Module, backend: str = "inductor") -> None:
    """``torch.compile`` each network in place (``--compile``; state dicts keep their keys).

    Every step of one slice is a few hundred small kernels; on a GPU their launches, not the
    arithmetic, bound the step, and fusing them is what compiling buys (docs/training.md).

    The compiler's caches are reset first. Every network shares the code of
    ``NeuralModel.forward``, and each one trained adds two or three entries to that code's
    cache (with and without grad, the teacher), so a process that trains several networks one
    after another (``bench quality --jobs 1``) reached dynamo's limit of 8 at the third or
    fourth network and silently ran the rest uncompiled. ``backend`` is for tests ("eager"
    traces and guards like inductor without generating code).
    """
    if mode == "off":
        return
    torch.compiler.reset()
    for m in models:
        if backend == "inductor":
            m.compile(mode=mode, dynamic=False)
        else:
            m.compile(backend=backend, dynamic=False)


def dist_setup(device: str = "cpu") -> tuple[int, int]:
    """``(rank, world)``; under ``torchrun`` initialises the process group: gloo for CPU
    training, NCCL for CUDA (one GPU per rank, ``cuda:LOCAL_RANK``)."""
    world = int(os.environ.get("WORLD_SIZE", "1"))
    if world > 1 and not dist.is_initialized():
        dist.init_process_group("nccl" if device.startswith("cuda") else "gloo")
    if dist.is_initialized():
        return dist.get_rank(), dist.get_world_size()
    return 0, 1


def dist_teardown(synchronise: bool = True) -> None:
    """End the ``torchrun`` process group (no-op without one). The ranks first meet at a
    barrier, as rank 0 may still be writing the checkpoint and pack: a rank that exits while
    another still holds a connection to it can abort in gloo's teardown. A rank leaving on an
    error skips the barrier (the others may never reach it)."""
    if not dist.is_initialized():
        return
    try:
        if synchronise:
            dist.barrier()
    finally:
        dist.destroy_process_group()


def train_device(name: str) -> torch.device:
    """The ``--device`` to train on (``cpu``, ``cuda``, ``cuda:N``), checked; under
    ``torchrun`` with CUDA each rank takes ``cuda:LOCAL_RANK``. One-line error if absent."""
    m = re.fullmatch(r"cpu|cuda(:\d+)?", name)
    if m is None:
        raise VrnError(f"--device {name!r}: expected cpu, cuda or cuda:N")
    if name == "cpu":
        return torch.device("cpu")
    if not torch.cuda.is_available():
        raise VrnError(
            f"--device {name}: CUDA is not available here (torch {torch.__version__}, "
            f"built for CUDA {torch.version.cuda or 'none'}); use --device cpu"
        )
    n = torch.cuda.device_count()
    index = int(os.environ.get("LOCAL_RANK", "0")) if name == "cuda" else int(name[5:])
    if index >= n:
        raise VrnError(f"--device {name}: CUDA device {index} requested, {n} present")
    torch.cuda.set_device(index)
    return torch.device("cuda", index)


def half_words(cfg) -> str:
    """Which half of a ``distill --wide-start`` run ``cfg`` trains, in words ("" otherwise)."""
    w = getattr(cfg, "wide_start", 0)
    if not w:
        return ""
    return f" (wide half, {w} wide)" if not cfg.init_from else f" (pruned half, {cfg.width} wide)"


class Interrupted(KeyboardInterrupt):
    """Raised after the checkpoint of an interrupted run is saved (a KeyboardInterrupt, so
    callers that do not know it still exit with code 130)."""


def fit(
    net: nn.Module,
    model: NeuralModel,
    data: SliceData,
    pairs: list[int],
    cfg,
    payload: dict,
    resume: dict | None = None,
    on_step=None,
    epochs_flag: str = "--epochs",
) -> dict:
    """Train ``net`` (``net(wi, wo, uv, pair) -> (loss, parts)``, around ``model``) into the
    checkpoint ``cfg.output`` and return the final payload.

    ``on_step(epoch, step)`` is called after every step (tests use it to send Ctrl-C). The
    held-out L1 (linear space) is ``model``'s on the test ``pairs``; ``payload`` holds the fixed
    checkpoint fields (kind, spec, config, btf, split, ...); ``resume`` a loaded checkpoint;
    ``epochs_flag`` the option that sets ``cfg.epochs``, for messages (``bench quality``'s
    ``--teacher-epochs``; "": none does, a ``--wide-start`` half).
    """
    torch.set_num_threads(max(1, int(cfg.threads)))
    rank, world = (dist.get_rank(), dist.get_world_size()) if dist.is_initialized() else (0, 1)
    out, tex_params = cfg.output, model.texture_parameters()
    tex_ids = {id(p) for p in tex_params}
    rest = [p for p in net.parameters() if p.requires_grad and id(p) not in tex_ids]
    groups = [{"params": rest, "lr": cfg.lr}]
    if tex_params:
        groups.append({"params": list(tex_params), "lr": cfg.lr * cfg.tex_lr_scale})
    opt = torch.optim.Adam(groups, betas=(0.9, 0.999), eps=1e-8)
    sched = torch.optim.lr_scheduler.ReduceLROnPlateau(
        opt,
        mode="min",
        factor=cfg.lr_factor,
        patience=cfg.lr_patience,
        threshold=cfg.lr_threshold,
        threshold_mode=cfg.lr_threshold_mode,
        min_lr=[cfg.lr_min, cfg.lr_min * cfg.tex_lr_scale][: len(groups)],
    )
    epoch, step, loss_sum, history, seconds = 0, 0, 0.0, [], 0.0
    gen = torch.Generator()
    ema = Ema(net, cfg.ema) if cfg.ema > 0 else None
    if resume is not None:
        net.load_state_dict(resume["net"])
        if ema is not None:
            ema.load(resume["ema"])
        opt.load_state_dict(resume["optimizer"])
        sched.load_state_dict(resume["scheduler"])
        epoch, step = int(resume["epoch"]), int(resume["step"])
        loss_sum, history = float(resume["loss_sum"]), list(resume["history"])
        seconds = float(resume.get("train_seconds", 0.0))
        if step:
            gen.set_state(resume["gen_state"])
    dev = data.device
    stepped = net  # what the steps call: under torchrun the DDP wrapper
    if world > 1:
        stepped = nn.parallel.DistributedDataParallel(
            net, device_ids=[dev.index] if dev.type == "cuda" else None
        )

    def save(finished: bool) -> dict:
        ck = {
            **payload,
            "net": net.state_dict(),
            "optimizer": opt.state_dict(),
            "scheduler": sched.state_dict(),
            "epoch": epoch,
            "step": step,
            "loss_sum": loss_sum,
            "gen_state": gen.get_state(),
            "history": history,
            "train_seconds": seconds,
            "finished": finished,
        }
        if ema is not None:
            ck["ema"] = ema.state()  # the exported network (see model_from_checkpoint)
        if rank == 0:
            save_checkpoint(out, ck)
        return ck

    n = len(data.train)
    bar = None
    if rank == 0 and epoch >= cfg.epochs and epochs_flag:
        # a finished run resumed without more --epochs (no hint where no option sets its
        # epochs directly: bench quality's --wide-start halves)
        print(
            f"{out}: already trained for {count(epoch, 'epoch')}, nothing left to train "
            f"({epochs_flag} N with N > {epoch} continues it)",
            file=sys.stderr,
        )
    elif rank == 0 and cfg.progress and epoch < cfg.epochs:  # no empty bar for a finished run
        from tqdm import tqdm

        bar = tqdm(
            total=(cfg.epochs - epoch) * n - step,
            desc=str(payload.get("method") or payload.get("kind") or "train") + half_words(cfg),
            unit="slice",
            dynamic_ncols=True,
        )
    last_test = history[-1]["test_l1"] if history else float("nan")
    with Stop() as stop, bar or contextlib.nullcontext():
        while epoch < cfg.epochs:
            order = epoch_order(cfg.seed, epoch, n, gen, step)
            t0 = time.perf_counter()
            net.train()
            steps = epoch_steps(
                stepped, opt, data, order, step, gen if cfg.jitter else None, ema, world
            )
            while step < n:
                try:
                    value = next(steps)
                except NonFiniteLossError as e:  # before the step: the weights stay finite
                    raise _diverged(f"loss is {e.value}", epoch, step + 1, n, out) from None
                loss_sum += value
                step += 1
                if bar is not None:
                    bar.update(1)
                    if step % 25 == 0:
                        bar.set_postfix(
                            ep=epoch + 1, loss=f"{loss_sum / step:.4g}", test_l1=_l1_text(last_test)
                        )
                if on_step is not None:
                    on_step(epoch, step)
                if _stopping(stop.flag, world, dev):
                    seconds += time.perf_counter() - t0
                    save(False)
                    stopped = Interrupted(f"epoch {epoch + 1} step {step}/{n}{half_words(cfg)}")
                    stopped.path = out  # the checkpoint it saved (a --wide-start half)
                    raise stopped
            net.eval()
            with torch.no_grad(), ema.applied() if ema else contextlib.nullcontext():
                last_test = float(mean_l1(model, data, pairs))
            if not math.isfinite(last_test):  # weights gone non-finite: never checkpoint them
                raise _diverged(f"test L1 is {last_test}", epoch, n, n, out)
            sched.step(last_test)
            seconds += time.perf_counter() - t0
            history.append(
                {
                    "epoch": epoch + 1,
                    "train_loss": loss_sum / n,
                    "test_l1": last_test,
                    "lr": opt.param_groups[0]["lr"],
                    "seconds": time.perf_counter() - t0,
                }
            )
            epoch, step, loss_sum = epoch + 1, 0, 0.0
            if bar is not None:
                bar.set_postfix(
                    ep=epoch, loss=f"{history[-1]['train_loss']:.4g}", test_l1=_l1_text(last_test)
                )
            save(epoch >= cfg.epochs)
    if resume is not None and resume.get("finished") and int(resume["epoch"]) == epoch:
        return resume  # nothing left to train: the file stays as it is (its hash too)
    return save(epoch >= cfg.epochs)


def _diverged(what: str, epoch: int, step: int, n: int, out: str) -> VrnError:
    """The one-line error of a run whose loss or test L1 became NaN/Inf (nothing is saved)."""
    kept = f"{out} is left as it was" if os.path.exists(out) else "no checkpoint was written"
    return VrnError(
        f"training diverged: {what} at epoch {epoch + 1} step {step}/{n}; {kept}; try a lower --lr"
    )


def _l1_text(v: float) -> str:
    """The progress bar's test L1: ``-`` before the first epoch's evaluation."""
    return "-" if math.isnan(v) else f"{v:.4g}"


def _stopping(flag: bool, world: int, device: torch.device) -> bool:
    """All ranks agree to stop when any rank saw Ctrl-C."""
    if world == 1:
        return flag
    t = torch.tensor([1.0 if flag else 0.0], device=device)
    dist.all_reduce(t)
    return bool(t.item() > 0)
