"""Checkpoints: plain dicts of tensors, numbers, strings and lists, saved atomically and only
ever loaded with ``torch.load(..., weights_only=True)``.

Layout (``format`` = ``"vrneural-checkpoint"``, ``version`` = 1)::

    kind        "teacher" | "student"         method  "teacher" | "student" | "single8" | "neumip"
    spec        model spec (models.make_spec)  state   model state_dict
    aux         extra trainable modules (T1, T2) state_dict
    optimizer / scheduler                      state dicts
    epoch, step completed epochs; steps done in the running epoch (resume point)
    gen_state   jitter generator state (ByteTensor)
    history     [{"epoch", "train_loss", "test_l1", "lr", "seconds"}]
    config      resolved config dict           btf  btf_fingerprint()
    split       {"train": [...], "test": [...]} pair indices
    teacher     (students) {"path", "sha256"} of the teacher checkpoint
    finished    bool
"""

from __future__ import annotations

import pickle
import re
import warnings
import zipfile
from pathlib import Path

import torch

from vrneural.btf.format import BTF_MAGIC
from vrneural.btf.identity import moved_btf
from vrneural.distill.models import NeuralModel
from vrneural.errors import VrnError, input_file
from vrneural.formats.vrnm import VRNM_MAGIC
from vrneural.grazing import DEFAULT_THETA_MAX_DEG
from vrneural.outputs import atomic_path
from vrneural.warn import VrnWarning

FORMAT = "vrneural-checkpoint"
VERSION = 1
KINDS = ("teacher", "student")
ARCHS = ("single", "coarse_fine")  # models.NeuralModel


class UnfinishedRunWarning(VrnWarning):
    """A checkpoint whose training did not finish, exported or distilled from as it is."""


def unfinished_run(ck: dict) -> str:
    """``"an unfinished run (1 of 3 epochs done and 40 steps of the next)"``."""
    step = int(ck.get("step", 0))
    return (
        f"an unfinished run ({ck['epoch']} of {ck['config'].get('epochs', '?')} epochs "
        f"done{f' and {step} steps of the next' if step else ''})"
    )


def save_checkpoint(path, payload: dict) -> None:
    """``torch.save`` through :func:`vrneural.outputs.atomic_path`: a failed write (one-line
    :class:`VrnError`) leaves the previous checkpoint as it was."""
    with atomic_path(path) as tmp:
        try:
            torch.save({"format": FORMAT, "version": VERSION, **payload}, tmp)
        except (OSError, RuntimeError) as e:  # torch reports a failed open as a RuntimeError
            raise VrnError(f"{path}: cannot write the checkpoint ({_first_sentence(e)})") from None


def load_checkpoint(path, kind: str | None = None) -> dict:
    """Load and validate a checkpoint; any problem is a one-line :class:`VrnError`.

    Refuses files that need arbitrary unpickling (``weights_only=True``), corrupt or foreign
    files, other formats/versions, and (with ``kind``) checkpoints of another kind.
    """
    p = input_file(path, "a checkpoint (.pt)", missing="no such checkpoint")
    _refuse_our_other_formats(p)
    _check_crcs(p)
    try:
        with warnings.catch_warnings():  # torch warns about legacy/foreign files before failing
            warnings.simplefilter("ignore")
            ck = torch.load(p, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as e:
        m = re.search(r"GLOBAL ([\w.]+)", str(e))
        if m is None:
            raise VrnError(f"{p}: corrupt or not a torch checkpoint (unreadable pickle)") from None
        raise VrnError(
            f"{p}: refusing to load: it needs unpickling of arbitrary objects ({m.group(1)}), "
            "which weights_only=True forbids"
        ) from None
    except (KeyError, IndexError):  # a text file: the unpickler reads its bytes as opcodes
        msg = "not a PyTorch checkpoint (corrupt, or another kind of file)"
        raise VrnError(f"{p}: {msg}") from None
    except Exception as e:  # truncated or foreign files fail anywhere in the unpickler
        raise VrnError(f"{p}: corrupt or not a torch checkpoint ({_first_sentence(e)})") from None
    if not isinstance(ck, dict) or ck.get("format") != FORMAT:
        raise VrnError(f"{p}: not a vrneural checkpoint (no format '{FORMAT}')")
    if ck.get("version") != VERSION:
        raise VrnError(f"{p}: checkpoint version {ck.get('version')!r} unsupported (reads 1)")
    if ck.get("kind") not in KINDS:
        kinds = ", ".join(KINDS)
        raise VrnError(f"{p}: checkpoint kind {ck.get('kind')!r} unknown (reads {kinds})")
    if kind is not None and ck.get("kind") != kind:
        raise VrnError(f"{p}: is a {ck.get('kind')!r} checkpoint, expected a {kind!r} checkpoint")
    for key in ("spec", "net", "config", "btf", "split", "epoch", "history"):
        if key not in ck:
            raise VrnError(f"{p}: checkpoint lacks '{key}'")
    arch = ck["spec"].get("arch") if isinstance(ck["spec"], dict) else None
    if arch not in ARCHS:
        raise VrnError(f"{p}: spec.arch {arch!r} unknown (reads {', '.join(ARCHS)})")
    bad = _non_finite(ck)
    if bad is not None:  # training never saves one (it stops on a NaN/Inf loss or test L1)
        raise VrnError(f"{p}: corrupt checkpoint: tensor '{bad}' holds NaN or Inf")
    return ck


def _check_crcs(p: Path) -> None:
    """A checkpoint is a zip whose entries carry CRC-32s that torch.load does not check: a
    flipped byte in a tensor would load as a wrong weight. Check them all."""
    try:
        if not zipfile.is_zipfile(p):
            return  # torch.load says what it is
        with zipfile.ZipFile(p) as z:
            bad = z.testzip()
    except (OSError, zipfile.BadZipFile, EOFError, ValueError) as e:
        raise VrnError(f"{p}: corrupt checkpoint ({_first_sentence(e)})") from None
    if bad is not None:
        raise VrnError(f"{p}: corrupt checkpoint: entry '{bad}' fails its CRC-32 check")


def _non_finite(obj, name: str = "") -> str | None:
    """The dotted name of the first floating tensor in ``obj`` with a NaN or Inf, or None."""
    if isinstance(obj, torch.Tensor):
        ok = not obj.is_floating_point() or bool(torch.isfinite(obj).all())
        return None if ok else name
    if isinstance(obj, dict):
        items = obj.items()
    elif isinstance(obj, (list, tuple)):
        items = enumerate(obj)
    else:
        return None
    for k, v in items:
        bad = _non_finite(v, f"{name}.{k}" if name else str(k))
        if bad is not None:
            return bad
    return None


def _refuse_our_other_formats(p: Path) -> None:
    """A BTF or a runtime pack given where a checkpoint belongs: say which it is."""
    try:
        with open(p, "rb") as f:
            head = f.read(8)
    except OSError:
        return  # torch.load reports it
    if head.startswith(BTF_MAGIC):
        raise VrnError(
            f"{p}: is a BTF file, expected a checkpoint (.pt); train one with "
            f"`vrneural teach {p.name} -o teacher.pt`"
        )
    if head.startswith(VRNM_MAGIC):
        raise VrnError(f"{p}: is a runtime pack (.vrnm), expected a checkpoint (.pt)")


def recorded_btf(ck: dict, source) -> str:
    """The BTF path recorded in checkpoint ``ck`` (file ``source``), which must still exist,
    or the same BTF (its fingerprint) under the same name beside ``source`` (a moved folder)."""
    path = ck["btf"]["path"]
    if Path(path).exists():
        return path

    found = moved_btf(ck["btf"], source) if isinstance(source, (str, Path)) else None
    if found is None:
        raise VrnError(
            f"{path}: the BTF recorded in {source} does not exist (moved or deleted?); "
            "pass --btf PATH to use another copy"
        )
    return found


def _first_sentence(e: Exception) -> str:
    """The first sentence of an exception's message (torch's run on), or its type."""
    text = str(e).strip()
    if not text or isinstance(e, (KeyError, IndexError)):
        return f"{type(e).__name__}: {text}" if text else type(e).__name__
    first = text.splitlines()[0]
    cut = first.find(". ")
    return first[: cut + 1] if 0 < cut < 160 else first[:160]


def model_from_checkpoint(ck: dict, source=None) -> NeuralModel:
    """The trained :class:`NeuralModel` of a checkpoint (frozen, eval mode): its weight
    average where it was trained with ``--ema``, else the last step's weights. ``source``
    (the file) names it in errors."""
    where = source or "checkpoint"
    try:
        model = NeuralModel(ck["spec"])
    except (KeyError, TypeError, ValueError) as e:
        raise VrnError(f"{where}: invalid model spec ({type(e).__name__}: {e})") from None
    net = dict(ck["net"])
    if ck.get("ema"):
        net.update(ck["ema"]["avg"])
    state = {k[len("model.") :]: v for k, v in net.items() if k.startswith("model.")}
    problem = _state_mismatch(model.state_dict(), state)
    if problem:
        raise VrnError(f"{where}: checkpoint weights do not match its spec: {problem}")
    model.load_state_dict(state)
    model.eval()
    for p in model.parameters():
        p.requires_grad_(False)
    # its BTF's direction range; checkpoints from before it was recorded: the default, which
    # is what ``btf synth`` and UBO2014 hold
    rng = ck.get("btf", {}).get("dir_range")
    model.dir_range = tuple(rng) if rng else (DEFAULT_THETA_MAX_DEG, DEFAULT_THETA_MAX_DEG)
    return model


def _state_mismatch(want: dict, have: dict) -> str | None:
    """The first difference between a model's state dict and a checkpoint's, in words."""
    for k, v in have.items():
        if k not in want:
            return f"unexpected tensor 'model.{k}'"
        if tuple(v.shape) != tuple(want[k].shape):
            return (
                f"'model.{k}' has shape {list(v.shape)} in the file, the spec needs "
                f"{list(want[k].shape)}"
            )
    missing = [k for k in want if k not in have]
    return f"tensor 'model.{missing[0]}' is missing" if missing else None
