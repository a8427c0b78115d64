"""Identity of a BTF and the train/test split of its directions (numpy only).

A checkpoint or pack records :func:`btf_fingerprint` of the BTF it was trained on, so a later
command can tell the same BTF from another one (:func:`check_btf_record`), and the seeded
:func:`split_pairs` that held out its test directions, so any command can rebuild the split.
Training (:mod:`vrneural.distill`) and evaluation without torch (``vrneural eval``) share them.
"""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path

import numpy as np

from vrneural.btf.format import Btf, read_btf
from vrneural.errors import VrnError
from vrneural.grazing import directions_range

#: The value sample of :func:`btf_fingerprint`: this many evenly spaced runs of ``SAMPLE_RUN``
#: float16 values (2 MiB in all; a file up to that size is hashed whole).
SAMPLE_RUNS = 64
SAMPLE_RUN = 16_384


def btf_fingerprint(btf: Btf) -> dict:
    """Identity of a BTF: name, shape, a SHA-256 of its header (``sha256``) and one of a fixed
    sample of its values (``values_sha256``); also its directions' range ``dir_range``
    (largest light and view polar angles, degrees: :mod:`vrneural.grazing`), which checkpoints
    carry to the packs.

    The header holds the generator settings and directions' layout but not the values (a
    streamed file has no per-array checksum), so the values are sampled: ``SAMPLE_RUNS``
    evenly spaced runs of ``SAMPLE_RUN`` values, a few MiB read from a file of any size. A
    value changed outside the sample goes unnoticed; a truncated, regenerated or re-imported
    file does not. Checkpoints from before ``values_sha256`` lack it: compare with
    :func:`fingerprint_mismatch`, which compares what both have.
    """
    p = Path(btf.path)
    with open(p, "rb") as f:
        f.seek(16)
        hlen = int.from_bytes(f.read(8), "little")
        head = f.read(hlen)
    L, V, H, W = btf.shape
    return {
        "path": str(p.resolve()),
        "name": str(btf.meta.get("name", p.stem)),
        "sha256": hashlib.sha256(head).hexdigest(),
        "values_sha256": _values_sha256(btf.values),
        "shape": [L, V, H, W],
        "dir_range": list(directions_range(btf.light_dirs, btf.view_dirs)),
    }


def _values_sha256(values: np.ndarray) -> str:
    """SHA-256 of the value sample of :func:`btf_fingerprint` (``values`` may be a memmap)."""
    flat = values.reshape(-1)
    h = hashlib.sha256()
    if flat.size <= SAMPLE_RUNS * SAMPLE_RUN:
        h.update(np.ascontiguousarray(flat).tobytes())
    else:
        for start in np.linspace(0, flat.size - SAMPLE_RUN, SAMPLE_RUNS).astype(np.int64):
            h.update(np.ascontiguousarray(flat[start : start + SAMPLE_RUN]).tobytes())
    return h.hexdigest()


FINGERPRINT_KEYS = ("name", "shape", "sha256", "values_sha256")


def fingerprint_mismatch(have: dict, want: dict, keys=FINGERPRINT_KEYS) -> str | None:
    """The first of ``keys`` (default :data:`FINGERPRINT_KEYS`) on which two fingerprints
    differ (keys one of them lacks, from an older release, are skipped), or None when they
    match."""
    for k in keys:
        if k in have and k in want and have[k] != want[k]:
            return k
    return None


def moved_btf(record: dict, beside) -> str | None:
    """Where a recorded BTF went when a folder was moved or copied: the file of the recorded
    name beside ``beside`` (the checkpoint or pack that records it), if it exists and is that
    very BTF (every fingerprint key the record has matches, ``values_sha256`` included when
    recorded), said on stderr; else None."""
    name = Path(str(record.get("path") or "")).name
    if not name or "sha256" not in record:
        return None
    cand = Path(beside).parent / name
    if not cand.is_file():
        return None
    try:
        fp = btf_fingerprint(read_btf(cand))
    except (VrnError, OSError, ValueError):
        return None
    if fingerprint_mismatch(fp, record):
        return None
    gone = record["path"]
    print(f"{beside}: recorded BTF {gone} is gone; using the same BTF at {cand}", file=sys.stderr)
    return str(cand)


def check_btf_record(
    path, fp: dict, want: dict, mismatch: str, recorded: str, remedy: str = ""
) -> None:
    """One-line :class:`VrnError` when the BTF at ``path`` (fingerprint ``fp``) is not the one
    the record ``want`` names: ``"{path}: BTF {mismatch}: KEY is A, {recorded} B{remedy}"``."""
    key = fingerprint_mismatch(fp, want)
    if key:
        raise VrnError(
            f"{path}: BTF {mismatch}: {key} is {fp[key]!s:.24}, {recorded} {want[key]!s:.24}"
            + remedy
        )


def split_pairs(n_light: int, n_view: int, fraction: float, seed: int) -> tuple[list, list]:
    """Deterministic train/test split of the ``L * V`` pair indices (``p = l * V + v``)."""
    n = n_light * n_view
    perm = np.random.default_rng(seed).permutation(n)
    n_test = max(1, round(n * fraction)) if fraction > 0 else 0
    if n - n_test < 1:
        raise VrnError(
            f"--test-fraction = {fraction} leaves no training (light, view) pairs: the BTF has "
            f"only {n}; use a BTF with more directions"
        )
    return sorted(perm[n_test:].tolist()), sorted(perm[:n_test].tolist())
